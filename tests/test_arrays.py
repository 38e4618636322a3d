"""Cache keys of arrays (:mod:`breakwater.common.arrays`): identity where it is safe.

Pure array tests: under ``mpiexec -n 2`` every rank runs them.
"""

from __future__ import annotations

import numpy as np
import pytest

from breakwater.common.arrays import equal, equal_at, finite, key_of, read_only, unchanged


def test_read_only_array_is_its_own_key() -> None:
    x = read_only(np.arange(4.0))
    assert key_of(x) is x and unchanged(key_of(x), x)
    with pytest.raises(ValueError, match="read-only"):
        x[0] = 1.0


def test_writeable_array_is_copied_and_compared() -> None:
    # A writeable array may change after it was keyed: its key is a copy, compared.
    x = np.arange(4.0)
    key = key_of(x)
    assert key is not x and unchanged(key, x)
    x[0] = 7.0
    assert not unchanged(key, x)
    assert unchanged(key, np.arange(4.0))  # equal values: the same state
    assert not unchanged(None, x)


def test_two_read_only_arrays_differ_unless_one() -> None:
    # Two read-only arrays are taken to differ (two Newton iterates): no comparison; the
    # cost of equal ones is a recomputation. A read-only key still matches a writeable
    # array of its values (the accepted state gathered from the Functions).
    a, b = read_only(np.arange(4.0)), read_only(np.arange(4.0))
    assert not unchanged(a, b)
    assert unchanged(a, np.arange(4.0))


def test_compiled_comparisons_are_numpys() -> None:
    a = np.array([0.0, -0.0, 1.5, np.nan])
    b = np.array([-0.0, 0.0, 1.5, np.nan])
    assert equal(a[:3], b[:3]) and np.array_equal(a[:3], b[:3])  # ±0 equal
    assert not equal(a, b) and not np.array_equal(a, b)  # NaN ≠ NaN, as NumPy
    assert not equal(a[:3], a[:2])
    c = a.copy()
    c[2] = 2.0
    assert equal_at(a, c, np.array([0, 1])) and not equal_at(a, c, np.array([0, 2]))
    assert unchanged(key_of(np.arange(3)), np.arange(3))  # not float: NumPy's comparison


@pytest.mark.parametrize("bad", [np.inf, -np.inf, np.nan])
def test_finite_finds_any_infinity_or_nan(bad: float) -> None:
    # The run's check of each step's state: np.isfinite(x).all(), compiled.
    x = np.linspace(-1e300, 1e300, 11)
    assert finite(x) and finite(np.zeros(0))
    for k in (0, 5, 10):
        y = x.copy()
        y[k] = bad
        assert not finite(y)
