"""Cache keys of arrays (:mod:`breakwater.common.arrays`): identity where it is safe.

Pure array tests: under ``mpiexec -n 2`` every rank runs them.
"""

from __future__ import annotations

import numpy as np
import pytest

from breakwater.common.arrays import key_of, read_only, unchanged


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
