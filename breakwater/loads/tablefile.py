"""Numeric tables from CSV files as spreadsheets, pandas and MATLAB write them.

:func:`read_table` reads a load's history (rows ``t, value``), :func:`read_rows` any
table of numbers (a storm's waves, :func:`breakwater.storms.seastate.read_wave_table`).
A file is either read as its author meant it or refused in one line naming the file,
the line and what to do: nothing here guesses between two readings of a cell (a
decimal comma or a separator, a thousands separator or a decimal point, seconds or
milliseconds).
"""

from __future__ import annotations

import codecs
import csv
import math
import pathlib
import re
from collections.abc import Sequence
from typing import Literal

__all__ = ["TIME_UNITS", "Quantity", "read_rows", "read_table"]

Quantity = Literal["time", "length", "factor"]
"""What a column holds when its header may give its unit (``t [ms]``, ``H (cm)``); a
``factor`` multiplies a magnitude given elsewhere, and a unit on it is refused."""
#: A factor column's header units that are read as written: none (``value [-]``,
#: ``f (1)``) or the SI units of a load's magnitude (``p (Pa)`` with the magnitude 1).
AS_WRITTEN = ("", "-", "1", "–", "N", "Pa", "N/m", "N/m2", "N/m²", "N/m^2")

TIME_UNITS = {"s": 1.0, "sec": 1.0, "secs": 1.0, "second": 1.0, "seconds": 1.0,
              "ms": 1e-3, "msec": 1e-3, "millisecond": 1e-3, "milliseconds": 1e-3,
              "µs": 1e-6, "μs": 1e-6,
              "us": 1e-6, "min": 60.0, "h": 3600.0}
"""A time column's header units and their factors to seconds."""
LENGTH_UNITS = {"m": 1.0, "metre": 1.0, "meter": 1.0, "metres": 1.0, "meters": 1.0,
                "cm": 1e-2, "mm": 1e-3, "ft": 0.3048}
"""A length column's header units and their factors to metres."""
_UNITS: dict[str, dict[str, float]] = {"time": TIME_UNITS, "length": LENGTH_UNITS}

# Cells of a table row: a number with a decimal point or a decimal comma (strict: no
# "nan", "inf", "1_000", thousands separators or units).
_NUMBER = re.compile(r"[+-]?(?:\d+(?:[.,]\d*)?|[.,]\d+)(?:[eE][+-]?\d+)?", re.ASCII)
# A number that may be written with thousands separators: 1.000, 12.500, 1.000.000.
_GROUPED = re.compile(r"[+-]?[1-9]\d{0,2}(?:\.\d{3})+", re.ASCII)
# Between the cells of a file without ";" or tabs: a comma and/or blanks.
_COMMA_OR_BLANKS = re.compile(r"\s*,\s*|\s+")
# A header cell's unit: "t [ms]", "t (ms)", "t / ms", "t in ms".
_UNIT = re.compile(r"(?:\[\s*([^\]]*?)\s*\]|\(\s*([^)]*?)\s*\)|\s*/\s*(\S+)|\sin\s+(\S+))\s*$")
# Excel's separator line ("sep=;"), before the header.
_SEP_LINE = re.compile(r"sep=(.)\s*", re.IGNORECASE)


def _decode(raw: bytes) -> str:
    """The text of a table file: UTF-16 with its byte-order mark, else UTF-8 (BOM dropped).

    Bytes that are not UTF-8 (a header in a legacy code page, e.g. "°C") become U+FFFD:
    they cannot make a number, so a data row holding one is refused, never misread.
    """
    if raw.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        return raw.decode("utf-16", errors="replace")
    return raw.decode("utf-8-sig", errors="replace").replace("\ufeff", "")


def _separator(lines: list[str]) -> str:
    """The file's cell separator: ``;`` or a tab if any row has one, else commas/blanks."""
    if any(";" in line for line in lines):
        return ";"
    if any("\t" in line for line in lines):
        return "\t"
    return ","


def _cells(text: str, separator: str) -> tuple[list[str], int]:
    """The cells of a row, unquoted, and the number of trailing empty cells removed."""
    if '"' in text:  # quoted cells ("0,5" or "t (s)"): the csv module's rules
        cells = [c.strip() for c in next(csv.reader([text], delimiter=separator,
                                                    skipinitialspace=True))]
    elif separator == ",":
        cells = _COMMA_OR_BLANKS.split(text)
    else:
        cells = [c.strip() for c in text.split(separator)]
    dropped = 0
    while cells and not cells[-1]:
        cells.pop()
        dropped += 1
    return cells, dropped


def _commas_and_blanks(text: str) -> bool:
    """Whether a row of a comma/blank file has cells apart by commas and by blanks alone.

    ``2,5 8``: H = 2, T = 5, start = 8, or H = 2.5 (a decimal comma), T = 8?
    """
    parts = re.split(r"\s*,\s*", text)
    return len(parts) > 1 and any(re.search(r"\s", p) for p in parts)


def _factors(path: pathlib.Path, number: int, header: list[str],
             units: Sequence[Quantity | None]) -> list[float]:
    """The factors to SI of the columns, from the units in their header cells."""
    factors = [1.0] * len(units)
    for k, (cell, quantity) in enumerate(zip(header, units, strict=False)):
        match = _UNIT.search(cell) if quantity is not None else None
        if match is None or quantity is None:
            continue
        unit = next(g for g in match.groups() if g is not None)
        if quantity == "factor":
            if (match.group(1) is None and match.group(2) is None) \
                    or unit in AS_WRITTEN or len(header) != len(units):
                continue  # "F/F_max", "value [-]", "p (Pa)", a header split unlike the rows
            raise ValueError(f"{path.name} line {number}: column {k + 1} ({cell!r}) is in "
                             f"{unit}, which is not read: its values multiply the load's "
                             "magnitude in SI (N, Pa); convert the column, or write it as a "
                             "factor (value [-]) and give the unit in the magnitude (e.g. "
                             "force = 1000.0 for kN)")
        known = _UNITS[quantity]
        if unit.lower() in known and unit not in known:  # "t [S]", "H (M)"
            unit = unit.lower()
        if unit not in known:
            if match.group(1) is None and match.group(2) is None:
                continue  # "Zeit/Time", "time in Sekunden": another word, not a unit
            raise ValueError(f"{path.name} line {number}: column {k + 1} ({cell!r}) is a "
                             f"{quantity} in {unit!r}: give it in one of "
                             f"{', '.join(known)} (or leave the unit out of the header: "
                             f"{'s' if quantity == 'time' else 'm'})")
        factors[k] = known[unit]
    return factors


def _check_grouping(path: pathlib.Path, separator: str,
                    points: tuple[str, int] | None) -> None:
    """Refuse a ``;``/tab file whose every decimal point could be a thousands separator.

    European spreadsheets write ``12.500`` for 12 500 (a grouped number) and ``;``
    between cells; read with a decimal point it would be 12.5. A file with any other
    decimal point (``0.250``, ``1.5``) has decimal points throughout.

    Args:
        path: The file.
        separator: Its separator.
        points: Its first cell with a decimal point and the line, if every such cell of
            the file reads as a grouped number; else None.

    """
    if separator == "," or points is None:
        return
    cell, number = points
    whole = cell.replace(".", "")
    named = "';'" if separator == ";" else "tab"
    raise ValueError(f"{path.name} line {number}: {cell!r} in a {named}-separated file: "
                     f"{whole} with thousands separators or {float(cell):g} with a "
                     f"decimal point? Write it without thousands separators ({whole}) or "
                     f"with a decimal comma ({cell.replace('.', ',', 1)})")


def read_table(path: pathlib.Path) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Read a CSV history: rows ``t, value``, as spreadsheets write them.

    - Encoding: UTF-8, with or without a byte-order mark (Excel's "CSV UTF-8"), or
      UTF-16 with its mark (Excel's "Unicode text"); any line ends (LF, CRLF, CR).
    - Separator, one per file (the rows after the first decide: a header may use
      another): ``;`` if a row has one, else a tab if a row has one, else a comma
      and/or blanks (a row with both, ``0,5 1``, is refused); Excel's ``sep=;`` line
      is obeyed. Trailing empty cells (``0,1,,``) are dropped; a row of empty cells
      (``,,``), a blank line and ``#`` comments are skipped.
    - Decimal commas (``0,5;1,2``) are read in ``;``- or tab-separated files; a file
      mixing decimal commas and decimal points is refused (``1.000`` would be 1 or
      1000), and so is a ``;``/tab file whose every decimal point could be a thousands
      separator (``12.500``).
    - Header: the first row is skipped only when none of its cells is a number (``t,
      value``); a first row with a number in it is data, and a bad one is refused. A
      time unit in the header's first cell (``t [ms]``, ``t (ms)``, ``t / ms``) converts
      the times to seconds (s, ms, µs, min, h, any case; another unit in brackets or
      parentheses is refused); the value is a factor of the load's magnitude (in SI),
      so a unit in brackets or parentheses on its header other than none (``[-]``,
      ``(1)``) or an SI unit (``(N)``, ``(Pa)``, ``(N/m)``) is refused (``F (kN)`` was
      read as 1: silently 1000× off).

    Raises:
        OSError: The file cannot be read (the message names it).
        ValueError: A row is not two numbers (or one is beyond the largest float), the
            times do not increase, or fewer than two rows (the message names the file and
            the line).

    """
    rows = read_rows(path, (2,), "two numbers t, value", ("time", "factor"))
    times: list[float] = []
    values: list[float] = []
    for k, (number, (t, v)) in enumerate(rows):
        if times and not t > times[-1]:
            raise ValueError(f"{path.name} line {number}: t = {t:g} does not increase (line "
                             f"{rows[k - 1][0]} has t = {times[-1]:g}; a jump needs two "
                             "times, however close)")
        times.append(t)
        values.append(v)
    if len(times) < 2:
        raise ValueError(f"{path.name}: a table needs at least two data rows (found "
                         f"{len(times)})")
    return tuple(times), tuple(values)


def read_rows(path: pathlib.Path, counts: tuple[int, ...], expected: str,
              units: Sequence[Quantity | None] = ()) -> list[tuple[int, tuple[float, ...]]]:
    """The numeric rows of a spreadsheet CSV, read as :func:`read_table` describes.

    Args:
        path: The file.
        counts: The numbers of cells a data row may have (e.g. ``(2,)``, ``(2, 3)``).
        expected: What a row holds, for the messages (``"two numbers t, value"``).
        units: What each column holds, where a unit in its header cell converts it to
            SI (``"time"``: s, ``"length"``: m; a unit on a ``"factor"`` is refused), ``None``
            where the header is not read.

    Returns:
        (line number, the row's numbers in SI) for each data row, in order.

    Raises:
        OSError: The file cannot be read (the message names it).
        ValueError: A row with another number of cells, a cell that is not a number (or
            beyond the largest float), mixed decimal marks, a unit that is not one of
            the column's (the message names the file and the line).

    """
    if not path.is_file():
        raise OSError(f"file not found: {path}")
    lines = [line.split("#", 1)[0] for line in _decode(path.read_bytes()).splitlines()]
    first = next((k for k, line in enumerate(lines) if line.strip()), None)
    sep_line = _SEP_LINE.fullmatch(lines[first].strip()) if first is not None else None
    if sep_line is not None:
        assert first is not None
        lines[first] = ""
    # The separator of the data: a header ("time (s)<tab>factor") may use another.
    filled = [line for line in lines if line.strip()]
    separator = sep_line.group(1) if sep_line else _separator(filled[1:] or filled)
    rows: list[tuple[int, tuple[float, ...]]] = []
    decimal: tuple[str, str, int] | None = None  # the file's decimal mark, cell, line
    grouped: tuple[str, int] | None = None  # the first decimal point, while all are 1.000s
    grouped_only = True
    factors = [1.0] * len(units)
    header_allowed = True
    indexed = False  # a header whose first cell is empty: pandas' index column
    for number, line in enumerate(lines, start=1):
        cells, dropped = _cells(line.strip(), separator)
        if not cells:
            continue
        where = f"{path.name} line {number}"
        numeric = [bool(_NUMBER.fullmatch(c)) for c in cells]
        if header_allowed:
            header_allowed = False
            if not any(numeric):  # the header: no number in it ("t [ms], F": 2 cells)
                titles = (next(csv.reader([line.strip()], skipinitialspace=True))
                          if separator == "," and "," in line else cells)
                factors = _factors(path, number, [c.strip() for c in titles], units)
                indexed = len(titles) > 1 and titles[0].strip() in ("", "Unnamed: 0")
                continue
        if separator == "," and _commas_and_blanks(line.strip()):
            raise ValueError(f"{where}: cells apart by commas and by blanks ("
                             f"{line.strip()!r}): is ',' a decimal comma? Separate the "
                             "cells by ';' or tabs (decimal commas) or by commas alone")
        if len(cells) not in counts or not all(numeric):
            bad = next((c for c, ok in zip(cells, numeric, strict=True) if not ok), None)
            named = {";": "';'", "\t": "a tab"}.get(separator, repr(separator)
                                                    if separator != "," else None)
            why = ("an empty cell (a missing value?)" if dropped and len(cells) < min(counts)
                   else f"got {len(cells)} cell{'s' * (len(cells) != 1)}"
                   + (f", the file's separator being {named}" if named else "")
                   + (": an index column? (pandas: to_csv(..., index=False))"
                      if indexed and len(cells) == max(counts) + 1 else "")
                   if len(cells) not in counts else
                   "no number: only the first row may be a header, comment others out "
                   "with #" if not any(numeric) else
                   "an empty cell" if bad == "" else f"{bad!r} is not a number")
            raise ValueError(f"{where}: expected {expected} ({why}: {line.strip()!r})")
        for cell in cells:
            mark = "," if "," in cell else "." if "." in cell else None
            if mark is None:
                continue
            if mark == "." and grouped_only:
                grouped_only = _GROUPED.fullmatch(cell) is not None
                grouped = grouped or (cell, number)
            if decimal is None:
                decimal = (mark, cell, number)
            elif mark != decimal[0]:
                raise ValueError(f"{where}: {cell!r} has a decimal "
                                 f"{'comma' if mark == ',' else 'point'}, {decimal[1]!r} "
                                 f"(line {decimal[2]}) a decimal "
                                 f"{'comma' if decimal[0] == ',' else 'point'}: use one "
                                 "throughout")
        row = tuple(float(c.replace(",", ".")) * (factors[k] if k < len(factors) else 1.0)
                    for k, c in enumerate(cells))
        for cell, x in zip(cells, row, strict=True):
            if not math.isfinite(x):  # 1e400: inf, not an error of float
                raise ValueError(f"{where}: {cell!r} is beyond the largest number (about "
                                 "1.8e308)")
        rows.append((number, row))
    _check_grouping(path, separator, grouped if grouped_only else None)
    return rows
