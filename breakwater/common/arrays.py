"""Cache keys of NumPy arrays: identity for read-only arrays, equality otherwise.

A Newton iteration evaluates the contact residual, its Jacobian, the slip guards and a
round-off estimate at one iterate, and each evaluation asks whether its cached state is
that iterate's: comparing the arrays costs a microsecond or two per question, a few
dozen per iteration. An array that cannot change (read-only, :func:`read_only`) is its
own key and is recognised by identity.
"""

from __future__ import annotations

import numpy as np

from breakwater.common.jit import kernel

__all__ = ["equal", "equal_at", "finite", "first_by_position", "key_of", "read_only",
           "unchanged"]


def read_only(x: np.ndarray) -> np.ndarray:
    """x, made read-only (in place): then its own key (:func:`key_of`)."""
    x.setflags(write=False)  # half the time of ``x.flags.writeable = False``
    return x


def key_of(x: np.ndarray) -> np.ndarray:
    """A cache key of x: x itself if it is read-only, else a copy."""
    return x if not x.flags.writeable else x.copy()


def unchanged(key: np.ndarray | None, x: np.ndarray) -> bool:
    """Whether x is a key of :func:`key_of`, or equals it.

    By identity where it can: two read-only arrays are taken to differ unless they are
    one (an iterate and the next; two equal ones only cost the cache a recomputation
    of the same values), a writeable one is compared entry by entry.
    """
    if key is None:
        return False
    if key is x:
        return True
    if not (x.flags.writeable or key.flags.writeable):
        return False
    if key.ndim == x.ndim == 1 and key.dtype == x.dtype == np.float64:
        return bool(equal(key, x))
    return bool(np.array_equal(key, x))


@kernel
def equal(a, b):  # type: ignore[no-untyped-def]
    """``np.array_equal`` of two float vectors (compiled: a microsecond less a call)."""
    if len(a) != len(b):
        return False
    for i in range(len(a)):
        if a[i] != b[i]:
            return False
    return True


@kernel
def equal_at(a, b, at):  # type: ignore[no-untyped-def]
    """Whether ``a[at]`` equals ``b[at]`` (compiled; stops at the first difference)."""
    for i in at:
        if a[i] != b[i]:
            return False
    return True


@kernel
def finite(x):  # type: ignore[no-untyped-def]
    """``np.isfinite(x).all()`` of a float vector (compiled, without a temporary)."""
    for v in x:
        if not np.isfinite(v):
            return False
    return True


def first_by_position(X: np.ndarray, nodes: np.ndarray) -> int:
    """Of ``nodes`` (indices into the points X), the first by x, then y (then z).

    The same node on every partition where several are as deep or as near to round-off
    (the node a warning or a refusal names).
    """
    return int(nodes[np.lexsort(X[nodes].T[::-1])[0]])
