"""The compiled kernels' decorator (:func:`breakwater.common.jit.kernel`)."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from numba.core import caching

from breakwater.common.jit import kernel


def _sum_of_squares(x: np.ndarray) -> float:
    s = 0.0
    for v in x:
        s += v * v
    return s


def test_kernel_without_a_writable_cache(monkeypatch: pytest.MonkeyPatch) -> None:
    # Where numba finds no directory to cache in (a read-only install, no writable
    # home), njit(cache=True) raises at decoration; kernel() compiles without a cache.
    monkeypatch.setattr(caching.CacheImpl, "_locator_classes", [])
    with pytest.raises(RuntimeError, match="no locator"):
        numba.njit(cache=True)(_sum_of_squares)
    compiled = kernel(_sum_of_squares)
    assert type(compiled._cache).__name__ == "NullCache"
    assert compiled(np.arange(5.0)) == 30.0


def test_kernel_is_cached_where_it_can_be() -> None:
    compiled = kernel(_sum_of_squares)
    assert type(compiled._cache).__name__ == "FunctionCache"
    assert compiled(np.ones(3)) == 3.0
