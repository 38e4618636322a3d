"""The wall time of each part of the fast path, for the benchmark."""

from __future__ import annotations

import time
from types import TracebackType

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

    def __call__(self, key: str) -> _Timer:
        """Time the block under ``key`` (a ``with`` block; exceptions pass through)."""
        return _Timer(self.seconds, key)


class _Timer:
    """The context manager of :meth:`Timings.__call__`.

    A class rather than ``contextlib.contextmanager``: a generator's set-up costs a
    microsecond, and the fast path enters some 30 000 of these blocks in a Goda run.
    """

    __slots__ = ("key", "seconds", "t0")

    def __init__(self, seconds: dict[str, float], key: str) -> None:
        self.seconds, self.key, self.t0 = seconds, key, 0.0

    def __enter__(self) -> None:
        self.t0 = time.perf_counter()

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 trace: TracebackType | None) -> None:
        self.seconds[self.key] += time.perf_counter() - self.t0
