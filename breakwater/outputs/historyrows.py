"""The history rows a run keeps in memory: one float64 array, a row per step.

The summary and a storm's record read the whole history at the end (and the summary at
every checkpoint). Kept as Python dicts, a row of the prototype storm's 50 columns took
about 5 KB: 1.9 GB for a storm of 1000 waves (250 000 steps), the same again per group
of a Monte Carlo on one node. :class:`HistoryRows` keeps them as one array (400 bytes a
row) and gives whole columns as NumPy arrays; indexing a row still gives a dict, so
code that reads a few rows is unchanged. :func:`column` reads a column from either kind
of row sequence (tests and tools pass lists of dicts).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import overload

import numpy as np

__all__ = ["HistoryRows", "column"]


class HistoryRows(Sequence[Mapping[str, float]]):
    """History rows of fixed columns in one growing float64 array.

    Args:
        columns: The column names, in order (every row has every column).
        rows: Rows to start with (mappings with every column), or an array of shape
            (rows, columns).

    Raises:
        KeyError: A row misses a column.
        ValueError: An array of another number of columns.
    """

    def __init__(self, columns: Sequence[str],
                 rows: Iterable[Mapping[str, float]] | np.ndarray = ()) -> None:
        self.columns = tuple(columns)
        self._index = {c: j for j, c in enumerate(self.columns)}
        if isinstance(rows, np.ndarray):
            if rows.ndim != 2 or rows.shape[1] != len(self.columns):
                raise ValueError(f"rows of shape {rows.shape} for {len(self.columns)} columns")
            self._data = np.asarray(rows, dtype=float)  # (a slice: no copy; see append)
            self._n = len(rows)
            return
        self._data = np.empty((64, len(self.columns)))
        self._n = 0
        for row in rows:
            self.append(row)

    def append(self, row: Mapping[str, float]) -> None:
        """Add a row (a mapping with every column; other keys are ignored)."""
        if self._n == len(self._data):  # amortised doubling (rows given: a copy first)
            grown = np.empty((max(2 * self._n, 64), len(self.columns)))
            grown[: self._n] = self._data[: self._n]
            self._data = grown
        self._data[self._n] = [row[c] for c in self.columns]
        self._n += 1

    def column(self, name: str, default: float | None = None) -> np.ndarray:
        """The column ``name`` over the rows (a read-only view).

        Args:
            name: The column.
            default: The value of every row when there is no such column (None: a
                KeyError).
        """
        j = self._index.get(name)
        if j is None:
            if default is None:
                raise KeyError(name)
            return np.full(self._n, default)
        view = self._data[: self._n, j]
        view.flags.writeable = False
        return view

    def __len__(self) -> int:
        return self._n

    @overload
    def __getitem__(self, i: int) -> dict[str, float]: ...

    @overload
    def __getitem__(self, i: slice) -> HistoryRows: ...

    def __getitem__(self, i: int | slice) -> dict[str, float] | HistoryRows:
        if isinstance(i, slice):
            return HistoryRows(self.columns, self._data[: self._n][i])
        if not -self._n <= i < self._n:
            raise IndexError(f"row {i} of {self._n}")
        return dict(zip(self.columns, self._data[i % self._n].tolist(), strict=True))


def column(rows: Sequence[Mapping[str, float]], name: str,
           default: float | None = None) -> np.ndarray:
    """The column ``name`` of history rows (a :class:`HistoryRows` or a list of mappings).

    Args:
        rows: The rows.
        name: The column.
        default: The value where a row has no such column (None: a KeyError).
    """
    if isinstance(rows, HistoryRows):
        return rows.column(name, default)
    if default is None:
        return np.array([r[name] for r in rows], dtype=float)
    return np.array([r.get(name, default) for r in rows], dtype=float)
