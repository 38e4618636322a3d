"""A study's table, ``sweep.csv``: one row per point, from the cases' records.

Each case's folder holds its record, ``sweep_case.json`` (:data:`RECORD`, written by
:mod:`breakwater.studies.sweep`); :func:`write_table` reads them all under a file lock
and writes the table atomically.
"""

from __future__ import annotations

import contextlib
import csv
import fcntl
import io
import math
import pathlib
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

from breakwater.common import files, liveness
from breakwater.studies.studyfile import Point, toml_literal

__all__ = ["LOCK", "RECORD", "TABLE", "read_records", "write_table"]

RECORD = "sweep_case.json"
"""A case's record, written last in its folder."""
TABLE = "sweep.csv"
LOCK = ".sweep.lock"


def read_records(out: pathlib.Path, points: Sequence[Point]) -> list[dict[str, Any] | None]:
    """The record of each point's folder (None when it has none)."""
    return [files.read_json(out / p.folder / RECORD) for p in points]


def write_table(out: pathlib.Path, points: Sequence[Point], keys: Sequence[str],
                fingerprints: Sequence[str], failed: Mapping[str, str] | None = None
                ) -> pathlib.Path:
    """Write ``sweep.csv`` from the points' records (atomically, under a file lock).

    The lock is held while the records are read: the last writer's table holds every
    record written before it.

    Args:
        out: The study's folder.
        points: The study's points.
        keys: The study's parameters (the table's columns of values).
        fingerprints: Each point's case's fingerprint (a record of another is ignored).
        failed: Cases (by folder) failed without their record: its write failed (a
            full disk), the line given as their error.
    """
    with _locked(out):
        return _write_table(out, points, keys, fingerprints, failed or {})


def _write_table(out: pathlib.Path, points: Sequence[Point], keys: Sequence[str],
                 fingerprints: Sequence[str], failed: Mapping[str, str]) -> pathlib.Path:
    records = read_records(out, points)
    for k, p in enumerate(points):
        if p.folder in failed:
            records[k] = {**(records[k] or {}), "fingerprint": fingerprints[k],
                          "status": "failed", "error": failed[p.folder]}
    columns: dict[str, None] = {}
    for r in records:
        if r is not None:
            columns.update(dict.fromkeys(r.get("headline", {})))
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["case", "folder", *keys, "status", "wall_time", *columns, "warnings",
                     "error"])
    for p, r, fp in zip(points, records, fingerprints, strict=True):
        current = r is not None and r.get("fingerprint") == fp
        rec = r if current else {}
        assert rec is not None
        values = [_cell(p.values.get(k)) for k in keys]
        head = rec.get("headline", {})
        status = rec.get("status", "pending")
        if status == "running" and liveness.process_state(rec.get("process")) == "gone":
            status = liveness.STOPPED  # killed (SIGKILL, a node lost): not running
        writer.writerow([p.index, p.folder, *values, status,
                         _cell(rec.get("wall_time")), *(_cell(head.get(c)) for c in columns),
                         " | ".join(rec.get("warnings") or ()), rec.get("error") or ""])
    return files.atomic_write_text(out / TABLE, buffer.getvalue())


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ""
    if isinstance(value, str | bool | int):
        return str(value).lower() if isinstance(value, bool) else str(value)
    return toml_literal(value)


@contextlib.contextmanager
def _locked(out: pathlib.Path) -> Iterator[None]:
    """An exclusive lock on ``out/.sweep.lock`` (groups writing sweep.csv in turn).

    Raises:
        OutputError: The lock file cannot be created (``cannot write <path>: ...``).
    """
    with files.writing(out / LOCK):
        f = open(out / LOCK, "a")  # (closed below)
    with f:
        try:
            fcntl.flock(f, fcntl.LOCK_EX)
        except OSError:  # a file system without locks: the final table is still whole
            pass
        try:
            yield
        finally:
            with contextlib.suppress(OSError):
                fcntl.flock(f, fcntl.LOCK_UN)
