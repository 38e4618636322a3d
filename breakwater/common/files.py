"""The files of an output folder: their names, writing them atomically, reading the history.

A small module without dolfinx, imported by the checkpoints, the outputs and the
figures alike. Small files (``summary.json``, ``case.toml``, ``.npz`` snapshots,
checkpoints, figures) are written to a temporary file beside the target and moved
into place with :func:`os.replace`, so a reader never sees half a file.
"""

from __future__ import annotations

import contextlib
import fnmatch
import hashlib
import io
import json
import math
import os
import pathlib
import tomllib
import unicodedata
from collections.abc import Iterable, Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from breakwater.common.errors import CaseError, cannot_write
from breakwater.common.parallel import on_rank_zero

if TYPE_CHECKING:  # light at import (no MPI): the figures and checkpoints import this
    from mpi4py import MPI

__all__ = [
    "CASE",
    "CHECKPOINT",
    "FIGURES",
    "HISTORY",
    "NAME_MAX",
    "SNAPSHOT",
    "STATIC",
    "STUDY_PATTERNS",
    "SUMMARY",
    "WAVES",
    "atomic_savez",
    "atomic_write_bytes",
    "atomic_write_json",
    "atomic_write_text",
    "atomic_write_toml",
    "check_unmixed",
    "check_writable",
    "clear_previous_run",
    "make_directory",
    "name_problem",
    "outputs_entry",
    "overwritten_inputs",
    "path_problem",
    "per_metre",
    "read_history",
    "read_json",
    "remove_temporaries",
    "sha256_of",
    "temporary_path",
    "to_jsonable",
    "writing",
]

HISTORY = "history.csv"
SUMMARY = "summary.json"


def per_metre(summary: Mapping[str, Any]) -> str:
    """``"/m"`` for a plane-strain run's forces and energies (per metre), ``""`` in 3D.

    Args:
        summary: A run's summary (its ``dimension``; absent in older runs: 2).
    """
    return "" if summary.get("dimension", 2) == 3 else "/m"


CASE = "case.toml"
STATIC = "static.npz"
SNAPSHOT = "snapshot_max_ux.npz"
FIGURES = "figures"
CHECKPOINT = "checkpoint.npz"
WAVES = "waves.csv"
"""A storm's per-wave record (:mod:`breakwater.outputs.stormrecord`)."""
OUTPUT_PATTERNS = (HISTORY, SUMMARY, CASE, STATIC, SNAPSHOT, CHECKPOINT, FIGURES, WAVES,
                   "fields_*.bp", "contact_*.bp", "*.part[0-9]*.bp", ".*.tmp[0-9]*")
"""The names a run may write in its output folder (shell patterns)."""

NAME_MAX = 255
"""The longest file or folder name of the usual file systems (ext4, XFS, APFS), bytes."""


def name_problem(name: str) -> str | None:
    """Why ``name`` cannot name an output folder of its own (``results/<name>``), or None.

    Refused rather than made safe: the name is also the case's label in the reports and
    the tables, and a folder under another name would be looked for in vain. ``"."``,
    ``".."``, a path separator or an absolute path would put the outputs elsewhere (the
    working directory, over the user's files); control characters (C0, DEL and C1) and
    the line and paragraph separators U+2028, U+2029 break the one-line messages and
    the reports that print the name; names longer than :data:`NAME_MAX` bytes cannot be
    created or read back reliably.
    """
    if not name:
        return "must not be empty"
    if name in (".", ".."):
        where = "the working directory" if name == ".." else "the folder results itself"
        return f"must not be '{name}': results/{name} is {where}, not a folder of its own"
    if any(c in name for c in "/\\:"):
        return f"must be a name without path separators ('/', '\\', ':') (got {name!r})"
    if any(unicodedata.category(c) in ("Cc", "Zl", "Zp") for c in name):  # C0, DEL, C1
        # (U+0085 NEL), U+2028, U+2029: each breaks a line of the reports and logs
        return f"must not contain control characters or line breaks (got {name!r})"
    try:
        size = len(name.encode("utf-8"))
    except UnicodeEncodeError:
        return f"is not valid Unicode (got {name!r})"
    if size > NAME_MAX:
        return (f"is {size} bytes long in UTF-8; a file or folder name has at most {NAME_MAX} "
                f"(got {name[:20]!r}...)")
    return None


PATH_MAX = 4096
"""The longest path Linux opens, bytes with the closing NUL (``PATH_MAX``)."""


def path_problem(path: str) -> str | None:
    """Why the text of an input path can name no file, or None.

    Input paths: ``mesh.source``, ``extends``, a table's ``file``, a study's ``base``.

    Checked before the path is resolved or opened: Python refuses a NUL byte with
    ``ValueError: embedded null byte`` and the system a name or path too long with
    ``OSError: File name too long``, neither of which names the input.
    """
    if "\x00" in path:
        return f"a path must not contain a NUL byte (got {path[:40]!r})"
    try:
        size = len(path.encode("utf-8"))
    except UnicodeEncodeError:
        return f"is not valid Unicode (got {path[:40]!r})"
    if size >= PATH_MAX:
        return f"the path is {size} bytes long; a path has at most {PATH_MAX - 1}"
    for part in path.split("/"):
        if len(part.encode("utf-8")) > NAME_MAX:
            return (f"{part[:20]!r}... is {len(part.encode('utf-8'))} bytes long; a file "
                    f"or folder name has at most {NAME_MAX}")
    return None


@contextlib.contextmanager
def writing(path: str | pathlib.Path) -> Iterator[None]:
    """Turn an ``OSError`` of the block into :class:`~breakwater.common.errors.OutputError`.

    The one line ``cannot write <path>: <reason>`` (permissions, a full disk, a name
    too long) names ``path``, the file meant, not a temporary one.
    """
    try:
        yield
    except OSError as e:
        raise cannot_write(path, e) from e


def make_directory(path: str | pathlib.Path, comm: MPI.Comm) -> pathlib.Path:
    """Create the output folder (rank 0); its absolute path, the same on every rank.

    Raises:
        OutputError: The folder cannot be created (on every rank).
    """
    def make() -> pathlib.Path:
        directory = pathlib.Path(path).resolve()
        with writing(directory):
            directory.mkdir(parents=True, exist_ok=True)
        return directory

    return on_rank_zero(comm, make)


def check_writable(directory: str | pathlib.Path, where: str = "--out") -> None:
    """Check (before a run) that files can be written in ``directory``; call on rank 0.

    The folder (and its missing parents) is created, a small file written, synced and
    removed; the folders created here are removed again (the run creates them).

    Args:
        directory: The output folder.
        where: How the messages name it (``--out``, ``output.directory``).

    Raises:
        CaseError: ``cannot write <path>: <reason>``, or ``directory`` is a file.
    """
    directory = pathlib.Path(directory)
    made: list[pathlib.Path] = []
    probe = directory / f".breakwater-write-test{os.getpid()}"
    try:  # is_dir() and exists() raise too (e.g. ENAMETOOLONG)
        if directory.exists() and not directory.is_dir():
            raise CaseError(f"{where} {directory}: not a folder (a file of that name "
                            "exists)")
        for folder in [*reversed(directory.parents), directory]:
            if folder.is_dir():
                continue
            if folder.exists():
                raise CaseError(f"cannot write {directory}: {folder} is a file, not a "
                                "folder")
            folder.mkdir()
            made.append(folder)
        with open(probe, "wb") as f:
            f.write(b"breakwater\n")
            f.flush()
            os.fsync(f.fileno())
        probe.unlink()
    except OSError as e:
        raise CaseError(f"cannot write {directory}: {e.strerror or e}") from None
    finally:
        for folder in reversed(made):
            with contextlib.suppress(OSError):
                folder.rmdir()


STUDY_PATTERNS = ("sweep.csv", ".sweep.lock", FIGURES, ".*.tmp[0-9]*",
                  "case-[0-9][0-9][0-9][0-9]*")
"""The names a study writes in its folder (its cases' folders are replaced whole)."""


RUN_MARKS = (SUMMARY, HISTORY)
"""The files that make a folder a run's output folder."""
STUDY_MARKS = ("sweep.csv", ".sweep.lock")
"""The files that make a folder a study's output folder."""


def check_unmixed(directory: str | pathlib.Path, where: str, study: bool) -> None:
    """Refuse a run's output folder for a study, or a study's for a run; call on rank 0.

    ``sweep --out`` into a run's folder wrote the study's ``sweep.csv`` and case folders
    beside the run's ``summary.json`` and fields (and ``run --out`` into a study's folder
    the run's outputs beside the study's), one folder read as both.

    Args:
        directory: The output folder.
        where: How the message names it (``--out``, ``output.directory``).
        study: Whether a study writes in it (else a run).

    Raises:
        CaseError: ``<where> <path>: holds a run's outputs (summary.json), not a
            study's ...``, one line.
    """
    directory = pathlib.Path(directory)
    marks, theirs, ours = (RUN_MARKS, "run", "study") if study \
        else (STUDY_MARKS, "study", "run")
    for name in marks:
        try:
            found = (directory / name).exists()
        except OSError:  # an unreadable folder: check_writable names it
            found = False
        if found:
            raise CaseError(f"{where} {directory}: holds a {theirs}'s outputs ({name}), not "
                            f"a {ours}'s: the {ours}'s would mix with them (choose another "
                            "folder)")


def overwritten_inputs(directory: str | pathlib.Path, inputs: Iterable[str | pathlib.Path],
                       patterns: Sequence[str] = OUTPUT_PATTERNS) -> list[pathlib.Path]:
    """The input files that outputs written in ``directory`` could replace.

    An input is at risk when it lies in the output folder under a name a run or a
    study writes (``patterns``), or inside a folder of such a name (the figures, the
    ParaView folders, a study's case folders), or when it is the output folder itself.
    """
    out = pathlib.Path(directory).resolve()
    risky = []
    for item in inputs:
        path = pathlib.Path(item).resolve()
        if path == out:
            risky.append(path)
            continue
        try:
            first = path.relative_to(out).parts[0]
        except ValueError:
            continue
        if any(fnmatch.fnmatchcase(first, p) for p in patterns):
            risky.append(path)
    return risky


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


def clear_previous_run(directory: pathlib.Path) -> int:
    """Remove the outputs of an earlier run from its folder, before a new run (rank 0).

    Only where the folder holds a run's ``summary.json``; only the names a run writes
    (:data:`OUTPUT_PATTERNS`, of the figures folder its PNG files), which no input may
    have (the command line refuses those). A run into a finished run's folder left the
    old ParaView fields, figures and a storm's ``waves.csv`` beside the new outputs.

    Returns:
        The entries removed.
    """
    import shutil

    if not (directory / SUMMARY).is_file():
        return 0
    removed = 0
    for pattern in OUTPUT_PATTERNS:
        found = (directory / FIGURES).glob("*.png") if pattern == FIGURES \
            else directory.glob(pattern)
        for path in found:
            with contextlib.suppress(OSError):
                if path.is_dir() and not path.is_symlink():
                    shutil.rmtree(path)
                else:
                    path.unlink()
                removed += 1
    return removed


def remove_temporaries(directory: pathlib.Path) -> None:
    """Remove the temporary files of atomic writes cut short (by a kill) in a folder."""
    for tmp in directory.glob(".*.tmp[0-9]*"):
        with contextlib.suppress(OSError):
            tmp.unlink()


def atomic_write_bytes(path: str | pathlib.Path, data: bytes) -> pathlib.Path:
    """Write ``data`` to ``path`` through a temporary file and :func:`os.replace`.

    Raises:
        OutputError: ``cannot write <path>: <reason>`` (the temporary file removed).
    """
    path = pathlib.Path(path)
    tmp = temporary_path(path)
    with writing(path):
        try:
            with open(tmp, "wb") as f:
                f.write(data)
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, path)
        except OSError:  # e.g. a full disk: no half-written temporary file is left
            with contextlib.suppress(OSError):
                tmp.unlink()
            raise
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


def read_json(path: str | pathlib.Path) -> dict[str, Any] | None:
    """A JSON object from a file (a summary, a study case's record), or None.

    None where the file is missing, unreadable, cut short or not an object.
    """
    with contextlib.suppress(OSError, ValueError):
        data = json.loads(pathlib.Path(path).read_text(encoding="utf-8"))
        if isinstance(data, dict):
            return data
    return None


def read_toml(path: str | pathlib.Path) -> dict[str, Any] | None:
    """A TOML file's table (a run's ``case.toml``), or None where missing or unreadable."""
    with contextlib.suppress(OSError, ValueError):  # (TOMLDecodeError is a ValueError)
        return tomllib.loads(pathlib.Path(path).read_text(encoding="utf-8"))
    return None


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
    """Read a ``history.csv`` into one array per column.

    Args:
        path: The file, or a run's output folder (its ``history.csv``): given the
            folder, it failed with ``IsADirectoryError``.
    """
    path = pathlib.Path(path)
    if path.is_dir():
        path = path / HISTORY
    with open(path, encoding="utf-8") as f:
        header = f.readline().strip().split(",")
        lines = [line for line in f if line.strip()]
    data = (np.loadtxt(lines, delimiter=",", ndmin=2) if lines
            else np.zeros((0, len(header))))
    return {name: data[:, j] for j, name in enumerate(header)}


def sha256_of(path: str | pathlib.Path) -> str:
    """The SHA-256 of a file's bytes (hex), read in blocks of 1 MiB.

    Raises:
        OSError: It cannot be read.
    """
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()
