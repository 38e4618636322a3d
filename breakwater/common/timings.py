"""The wall time of each part of the fast path, for the benchmark."""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator

__all__ = ["Timings"]


class Timings:
    """Wall time spent in each part of the fast path (s), summed over the run.

    ``factorisation`` (A assembled and factorised, and the interface solves for X),
    ``back_solves`` (z = A⁻¹ r₀), ``bulk_products`` (r₀ and Δa = z − X f_c),
    ``interface_assembly`` (the contact forms), ``newton`` (the rest of the SNES on the
    interface: dense solves, the convergence test, the slip guard), ``contact_search``
    (the general pairs' integration points cut and projected onto the master: a part of
    ``interface_assembly``).
    """

    KEYS = ("factorisation", "back_solves", "bulk_products", "interface_assembly", "newton",
            "contact_search")

    def __init__(self) -> None:
        self.seconds = dict.fromkeys(self.KEYS, 0.0)

    @contextlib.contextmanager
    def __call__(self, key: str) -> Iterator[None]:
        """Time the block under ``key``."""
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[key] += time.perf_counter() - t0
