"""Compiled kernels: the fast step's per-iteration arithmetic in machine code (numba).

The fast GN22 step (:mod:`breakwater.stepping.condensed`) spends its time in small
loops over the interface's nodes and a few dense interface-sized matrices: in NumPy each
of them is a handful of calls whose overhead is larger than their arithmetic. They are
written as plain loops and compiled with numba's ``njit``, as the dolfinx demos compile
their custom kernels. :func:`kernel` is the one decorator: compiled once per machine
(``cache=True``: numba keeps the machine code beside the module, or in its user cache
directory where the package is read-only; where neither can be written, e.g. a read-only
install on a cluster node without a writable home, each process compiles them anew),
without fast-math (the kernels must give the
numbers of the NumPy and UFL references they are tested against, to round-off).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, cast

import numba

__all__ = ["kernel"]


def kernel[F: Callable[..., Any]](function: F) -> F:
    """``numba.njit(cache=True)``: ``function`` compiled on its first call.

    Without a cache where numba finds no writable directory for it (it refuses
    ``cache=True`` then).
    """
    try:
        return cast(F, numba.njit(cache=True)(function))
    except RuntimeError:  # "cannot cache function ...: no locator available"
        return cast(F, numba.njit(function))
