"""The files of an output folder: their names, writing them atomically, reading the history.

A small module without dolfinx, imported by the checkpoints, the outputs and the
figures alike. Small files (``summary.json``, ``case.toml``, ``.npz`` snapshots,
checkpoints, figures) are written to a temporary file beside the target and moved
into place with :func:`os.replace`, so a reader never sees half a file.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import pathlib
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .parallel import on_rank_zero

if TYPE_CHECKING:  # light at import (no MPI): the figures and checkpoints import this
    from mpi4py import MPI

__all__ = ["CASE", "CHECKPOINT", "FIGURES", "HISTORY", "SNAPSHOT", "STATIC", "SUMMARY",
           "atomic_savez", "atomic_write_bytes", "atomic_write_json", "atomic_write_text",
           "atomic_write_toml", "make_directory", "outputs_entry", "read_history",
           "remove_temporaries", "temporary_path", "to_jsonable"]

HISTORY = "history.csv"
SUMMARY = "summary.json"
CASE = "case.toml"
STATIC = "static.npz"
SNAPSHOT = "snapshot_max_ux.npz"
FIGURES = "figures"
CHECKPOINT = "checkpoint.npz"


def make_directory(path: str | pathlib.Path, comm: MPI.Comm) -> pathlib.Path:
    """Create the output folder (rank 0); its absolute path, the same on every rank."""
    def make() -> pathlib.Path:
        directory = pathlib.Path(path).resolve()
        directory.mkdir(parents=True, exist_ok=True)
        return directory

    return on_rank_zero(comm, make)


def outputs_entry(directory: pathlib.Path, fields: Sequence[str], snapshot: bool,
                  static: bool = True) -> dict[str, Any]:
    """The ``outputs`` entry of ``summary.json``: the folder and the files of a run.

    Args:
        directory: The output folder.
        fields: The ParaView files.
        snapshot: Whether ``snapshot_max_ux.npz`` is written.
        static: Whether ``static.npz`` and ``history.csv`` (whose first row is the
            static state) are written: not when no static state was found.
    """
    return {"directory": str(directory), "history": HISTORY if static else None,
            "fields": list(fields), "static": STATIC if static else None,
            "snapshot": SNAPSHOT if snapshot else None}


def temporary_path(path: pathlib.Path) -> pathlib.Path:
    """A temporary name beside ``path`` that keeps its suffix (for savefig/np.savez)."""
    return path.with_name(f".{path.stem}.tmp{os.getpid()}{path.suffix}")


def remove_temporaries(directory: pathlib.Path) -> None:
    """Remove the temporary files of atomic writes cut short (by a kill) in a folder."""
    for tmp in directory.glob(".*.tmp[0-9]*"):
        with contextlib.suppress(OSError):
            tmp.unlink()


def atomic_write_bytes(path: str | pathlib.Path, data: bytes) -> pathlib.Path:
    """Write ``data`` to ``path`` through a temporary file and :func:`os.replace`."""
    path = pathlib.Path(path)
    tmp = temporary_path(path)
    with open(tmp, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
    return path


def atomic_write_text(path: str | pathlib.Path, text: str) -> pathlib.Path:
    """Write text (UTF-8) atomically."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def to_jsonable(obj: Any) -> Any:
    """Plain Python types for JSON: numpy scalars and arrays, paths, non-finite floats.

    Non-finite floats become ``None`` (JSON has no NaN).
    """
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.bool_ | bool):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.floating | float):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, pathlib.PurePath):
        return str(obj)
    return obj


def atomic_write_json(path: str | pathlib.Path, data: Mapping[str, Any]) -> pathlib.Path:
    """Write a mapping as indented JSON, atomically."""
    return atomic_write_text(path, json.dumps(to_jsonable(data), indent=2) + "\n")


def atomic_write_toml(path: str | pathlib.Path, data: Mapping[str, Any]) -> pathlib.Path:
    """Write a mapping as TOML (tomli_w), atomically."""
    import tomli_w

    return atomic_write_text(path, tomli_w.dumps(_tomlable(data)))


def _tomlable(obj: Any) -> Any:
    """Plain types for tomli_w (numpy scalars, tuples, paths; None values dropped)."""
    if isinstance(obj, Mapping):
        return {str(k): _tomlable(v) for k, v in obj.items() if v is not None}
    if isinstance(obj, list | tuple):
        return [_tomlable(v) for v in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, pathlib.PurePath):
        return str(obj)
    return obj


def atomic_savez(path: str | pathlib.Path, **arrays: np.ndarray) -> pathlib.Path:
    """``np.savez_compressed`` atomically."""
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays)  # type: ignore[arg-type]
    return atomic_write_bytes(path, buffer.getvalue())


def read_history(path: str | pathlib.Path) -> dict[str, np.ndarray]:
    """Read a ``history.csv`` into one array per column."""
    with open(path, encoding="utf-8") as f:
        header = f.readline().strip().split(",")
        lines = [line for line in f if line.strip()]
    data = (np.loadtxt(lines, delimiter=",", ndmin=2) if lines
            else np.zeros((0, len(header))))
    return {name: data[:, j] for j, name in enumerate(header)}
