"""Checkpoints of a run: everything needed to continue it bit for bit.

A checkpoint is one file, ``checkpoint.npz`` in the output folder, replaced atomically
(temporary file, then :func:`os.replace`) every ``output.checkpoint_interval`` steps;
only the latest is kept. It holds

- ``meta``: a JSON document (floats are written with ``repr``, so they read back
  exactly): format version, the fingerprint of the case, the number of MPI ranks,
  the bodies' names, the history columns, and ``state``, the run's bookkeeping
  (:class:`~breakwater.run.runstate.RunState`: the step-size controller with the accepted
  step sizes, the solver statistics, the static summary, the ledger's cumulative
  sums, the number of ``history.csv`` rows written at the checkpoint...);
- per body ``i``: ``x<i>``, the coordinates of the body's nodes (unique within a
  body), and ``state<i>``, the nodal values of every saved Function of that body
  (shape ``(functions, nodes, block size)``), gathered on rank 0.

Nodal values are keyed by coordinates, not by dof numbers: on loading, each rank
finds its own dofs (owned and ghost) by coordinate lookup (:func:`match_nodes`), so a
checkpoint can be resumed on any number of ranks. Serially the continuation is bit
for bit the uninterrupted run. In parallel, two uninterrupted runs already differ by
round-off (measured; the parallel linear algebra does not add in a fixed order from
one process to the next, MUMPS's dynamic scheduling being the likely cause), and a
resumed run, on the same or another number of ranks, equals them to that round-off.
"""

from __future__ import annotations

import hashlib
import io
import itertools
import json
import pathlib
import zipfile
from collections.abc import Mapping, Sequence
from dataclasses import asdict, is_dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from breakwater.common.errors import BreakwaterError
from breakwater.common.files import CHECKPOINT, SUMMARY, atomic_write_bytes, read_json, sha256_of
from breakwater.common.xdmfinfo import is_xdmf

if TYPE_CHECKING:  # light at import: the command line catches CheckpointError early
    from dolfinx import fem
    from mpi4py import MPI

__all__ = ["CHECKPOINT", "FORMAT", "CaseMismatch", "CheckpointError", "case_differences",
           "case_fingerprint",
           "check", "gather_nodal",
           "match_nodes", "model_fingerprint", "read", "scatter_nodal", "write"]

FORMAT = 5
"""Version of the checkpoint layout; a checkpoint of another version is refused.

5: the run state's per-step lists (the Newton iterations and the step sizes of the
accepted steps) are arrays of the file, ``steps_iterations`` and ``steps_accepted``,
not lists of its JSON metadata.

4: the stepper's state holds ``memory``, the general pairs' last slip velocities at
their slave nodes (Newton's start of the next step:
:meth:`breakwater.contact.general.SurfaceForces.predict`); since 2026-11-28 with the
master facets their searches use, each pair's ``{"slip": [...], "facets": [...]}``
(:meth:`breakwater.stepping.condensed.GeneralPairs.memory`; a bare list, written
before, is read as the slip velocities).

3: the ledger's state holds ``friction_power``, every pair's friction power at the
last record (2 held ``surface_power``, the general pairs' only).
"""

_MATCH_TOL = 1e-9
"""Node coordinates match within this fraction of the body's bounding-box size."""


class CheckpointError(BreakwaterError):
    """No usable checkpoint: missing, from another case, or unreadable (one line)."""


# --- fingerprints -----------------------------------------------------------------

def _canonical(obj: Any) -> Any:
    """Plain, deterministic data for hashing (dataclasses, numpy, tuples, paths).

    Floats are rounded to 12 significant digits: a value computed by the run (a
    calibrated modulus) may differ in its last bits with the number of ranks.
    """
    if isinstance(obj, float | np.floating):
        return float(f"{float(obj):.12g}")
    if is_dataclass(obj) and not isinstance(obj, type):
        return _canonical(asdict(obj))
    if isinstance(obj, Mapping):
        return {str(k): _canonical(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_canonical(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _canonical(obj.tolist())
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, pathlib.PurePath):
        return str(obj)
    if callable(obj):
        # A plain function has no stable repr (it holds an address): its name only.
        return getattr(obj, "__qualname__", type(obj).__name__)
    return obj


def _digest(data: Any) -> str:
    text = json.dumps(_canonical(data), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


class CaseMismatch(CheckpointError):
    """A checkpoint of another case (:meth:`of`: the message, with the keys if known)."""

    @classmethod
    def of(cls, path: pathlib.Path, keys: Sequence[str] = ()) -> CaseMismatch:
        """The refusal to resume ``path``, naming up to five of the ``keys`` that differ."""
        shown = ", ".join(keys[:5]) + (f" and {len(keys) - 5} more" if len(keys) > 5 else "")
        return cls(f"cannot resume: the case differs from the one of the checkpoint {path}"
                   + (f", in {shown}" if keys else "")
                   + " (run it without --resume, or into another --out folder)")


def case_fingerprint(resolved_case: Mapping[str, Any]) -> str:
    """SHA-256 of a resolved case (the content of ``case.toml``) and of the files it reads.

    ``output.directory`` is left out, so a folder can be moved and resumed from its
    new place; floats count to 12 significant digits (see :func:`_canonical`). The
    contents of the mesh file and of the load tables' CSV files count, not only their
    paths: a table edited in place is another case.
    """
    data = _canonical(resolved_case)
    data.get("output", {}).pop("directory", None)
    data["file_contents"] = {path: _file_digest(path) for path in _input_files(data)}
    return _digest(data)


def case_differences(saved: Mapping[str, Any], resolved_case: Mapping[str, Any]) -> list[str]:
    """The keys (dotted) in which a resolved case differs from the checkpointed one.

    As :func:`case_fingerprint` compares them (floats to 12 digits, ``output.directory``
    left out); where no key differs, the fingerprint's other part: its input files'
    contents.

    Args:
        saved: The checkpointed run's resolved case (its folder's ``case.toml``).
        resolved_case: This run's.
    """
    old, new = _canonical(saved), _canonical(resolved_case)
    for data in (old, new):
        data.get("output", {}).pop("directory", None)
    out: list[str] = []

    def walk(a: Any, b: Any, key: str) -> None:
        if isinstance(a, dict) and isinstance(b, dict):
            for k in sorted(set(a) | set(b)):
                walk(a.get(k), b.get(k), f"{key}.{k}" if key else k)
        elif a != b:
            out.append(key)

    walk(old, new, "")
    return out or ["the contents of its input files (a mesh or a table edited since)"]


def _input_files(resolved_case: Mapping[str, Any]) -> list[str]:
    """The files a resolved case reads: its mesh (an XDMF's .h5 too), tables, waves."""
    paths = []
    source = resolved_case.get("mesh", {}).get("source")
    if source is not None and source != "goda":
        paths.append(str(source))
        if is_xdmf(pathlib.Path(source)):  # its arrays (coordinates, cells) are in the .h5
            paths.append(str(pathlib.Path(source).with_suffix(".h5")))
    for load in resolved_case.get("loads", {}).values():
        table = load.get("table") if isinstance(load, Mapping) else None
        if isinstance(table, Mapping) and table.get("file") is not None:
            paths.append(str(table["file"]))
        storm = load.get("storm") if isinstance(load, Mapping) else None
        if isinstance(storm, Mapping) and isinstance(storm.get("waves"), str):
            paths.append(str(storm["waves"]))  # a storm's table of waves
    return paths


_DIGESTS: dict[tuple[str, int, int], str] = {}
"""File digests by (path, size, modification time): a study's cases share their files."""


def _file_digest(path: str) -> str:
    """SHA-256 of a file's contents ("missing" when it cannot be read)."""
    try:
        stat = pathlib.Path(path).stat()
        key = (path, stat.st_size, stat.st_mtime_ns)
        if key not in _DIGESTS:
            _DIGESTS[key] = sha256_of(path)
        return _DIGESTS[key]
    except OSError:
        return "missing"


def model_fingerprint(model: Any, time: Any, output: Any) -> str:
    """SHA-256 of what defines a run built without a case file.

    The bodies (names, materials, global dof counts), contact pairs, number of
    boundary conditions, loads (group, direction, amplitude when it is a dataclass, the
    traction field and the side loaded when given), gravity, damping, the initial
    state's settings (when not the default), the time settings and the probes. A load
    amplitude given as a plain function is known by its name only.
    """
    initial = getattr(model, "initial", None)
    return _digest({
        **({"initial": initial} if initial is not None and initial != type(initial)() else {}),
        "cells": model.comm.allreduce(
            model.mesh.topology.index_map(model.mesh.topology.dim).size_local),
        "bodies": [{"name": b.spec.name, "material": b.spec.material,
                    "dofs": b.V.dofmap.index_map.size_global * b.V.dofmap.index_map_bs}
                   for b in model.bodies],
        "pairs": [p.spec for p in model.pairs],
        "bcs": len(model.bcs),
        "loads": [{"group": ld.spec.group, "direction": ld.spec.direction,
                   "amplitude": ld.spec.amplitude,
                   **{k: v for k, v in (("field", ld.spec.field), ("body", ld.spec.body))
                      if v is not None}}
                  for ld in model.loads],
        "gravity": model.gravity.value,
        "damping": model.damping,
        "time": time,
        "probes": [output.probes, output.pair_probes],
    })


# --- nodal values keyed by coordinates --------------------------------------------

def _rows(a: np.ndarray) -> np.ndarray:
    """Each row of an integer array as one opaque (void) item, for sorting/searching."""
    a = np.ascontiguousarray(a)
    return a.view(np.dtype((np.void, a.dtype.itemsize * a.shape[1]))).ravel()


def match_nodes(stored: np.ndarray, local: np.ndarray, tol: float) -> np.ndarray:
    """Index in ``stored`` of the point nearest each ``local`` point, within ``tol``.

    The points are put on a grid of spacing ``tol``; a match lies in the same or a
    neighbouring cell, so the search is a sort and 3^gdim binary searches (no tree).

    Args:
        stored: Points, shape (N, gdim), pairwise farther apart than 2 tol.
        local: Points to find, shape (n, gdim).
        tol: Largest distance accepted.

    Returns:
        Indices, shape (n,).

    Raises:
        CheckpointError: A point has no match, or two stored points share a cell.
    """
    stored = np.asarray(stored, dtype=float)
    local = np.asarray(local, dtype=float)
    n, gdim = local.shape
    if n == 0:
        return np.zeros(0, np.int64)
    if len(stored) == 0:
        raise CheckpointError("the checkpoint has no nodes for this body")
    keys = _rows(np.floor(stored / tol).astype(np.int64))
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    if len(sorted_keys) > 1 and np.any(sorted_keys[1:] == sorted_keys[:-1]):
        raise CheckpointError("the checkpoint holds coincident nodes in one body")
    cells = np.floor(local / tol).astype(np.int64)
    index = np.full(n, -1, np.int64)
    best = np.full(n, np.inf)
    for offset in itertools.product((-1, 0, 1), repeat=gdim):
        k = _rows(cells + np.array(offset, np.int64))
        pos = np.minimum(np.searchsorted(sorted_keys, k), len(sorted_keys) - 1)
        hit = np.flatnonzero(sorted_keys[pos] == k)
        candidate = order[pos[hit]]
        d = np.linalg.norm(stored[candidate] - local[hit], axis=1)
        closer = d < best[hit]
        best[hit[closer]] = d[closer]
        index[hit[closer]] = candidate[closer]
    missing = np.flatnonzero(~(best <= tol))
    if missing.size:
        raise CheckpointError(f"the mesh differs from the checkpoint's: no stored node "
                              f"at {local[missing[0]].tolist()} ({missing.size} nodes "
                              "unmatched)")
    return index


def gather_nodal(functions: Sequence[Sequence[fem.Function]], comm: MPI.Comm
                 ) -> dict[str, np.ndarray] | None:
    """Coordinates and values of the owned nodes of each body, on rank 0 (collective).

    Args:
        functions: For each body, the Functions to save (all on the body's space).
        comm: The communicator of the mesh.

    Returns:
        On rank 0, ``x<i>`` (N, gdim) and ``state<i>`` (len(functions[i]), N, bs) for
        each body ``i``; None on the other ranks.
    """
    out: dict[str, np.ndarray] = {}
    for i, fs in enumerate(functions):
        V = fs[0].function_space
        imap, bs = V.dofmap.index_map, V.dofmap.index_map_bs
        gdim = V.mesh.geometry.dim
        nloc = imap.size_local
        x = V.tabulate_dof_coordinates()[:nloc, :gdim]
        values = np.stack([f.x.array.reshape(-1, bs)[:nloc] for f in fs])
        parts = comm.gather((x, values), root=0)
        if parts is not None:
            out[f"x{i}"] = np.vstack([p[0] for p in parts])
            out[f"state{i}"] = np.concatenate([p[1] for p in parts], axis=1)
    return out if comm.rank == 0 else None


def scatter_nodal(arrays: Mapping[str, np.ndarray],
                  functions: Sequence[Sequence[fem.Function]]) -> None:
    """Set every local dof (owned and ghost) of the Functions from gathered values.

    Args:
        arrays: ``x<i>`` and ``state<i>`` as written by :func:`gather_nodal`.
        functions: For each body, the Functions to set, in the order saved.

    Raises:
        CheckpointError: The bodies or their meshes differ from the checkpoint's.
    """
    for i, fs in enumerate(functions):
        if f"x{i}" not in arrays:
            raise CheckpointError(f"the checkpoint has no body {i}")
        x, state = arrays[f"x{i}"], arrays[f"state{i}"]
        V = fs[0].function_space
        bs = V.dofmap.index_map_bs
        gdim = V.mesh.geometry.dim
        if state.shape[0] != len(fs) or state.shape[2] != bs or x.shape[1] != gdim:
            raise CheckpointError(f"body {i}: the checkpoint's fields do not fit the model")
        n_global = V.dofmap.index_map.size_global
        if len(x) != n_global:
            raise CheckpointError(f"body {i}: the checkpoint has {len(x)} nodes, the mesh "
                                  f"{n_global}")
        scale = max(float(np.ptp(x, axis=0).max()), 1e-300)
        local = V.tabulate_dof_coordinates()[:, :gdim]
        index = match_nodes(x, local, _MATCH_TOL * scale)
        for f, values in zip(fs, state, strict=True):
            f.x.array[:] = values[index].ravel()


# --- the file -----------------------------------------------------------------------

def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"{type(obj).__name__} is not JSON serialisable")


def write(path: str | pathlib.Path, meta: Mapping[str, Any],
          arrays: Mapping[str, np.ndarray]) -> pathlib.Path:
    """Write a checkpoint atomically (call on rank 0 only).

    Uncompressed: a checkpoint is written often and read once.
    """
    buffer = io.BytesIO()
    np.savez(buffer, meta=np.array(json.dumps({"format": FORMAT, **meta},
                                               default=_json_default)),
             **arrays)  # type: ignore[arg-type]
    return atomic_write_bytes(path, buffer.getvalue())


def check(directory: str | pathlib.Path, fingerprint: str | None = None) -> dict[str, Any]:
    """Whether the run of a folder can be resumed; its checkpoint's ``meta``.

    Reads the checkpoint's metadata, checks the CRC-32 of its every entry (a damaged
    file is refused here, not half-way through a resume), and reads the folder's
    ``summary.json``.

    Args:
        directory: The output folder.
        fingerprint: When given, the checkpoint's case fingerprint must equal it.

    Raises:
        CheckpointError: No checkpoint, an unreadable one, another format, another
            case, or a run that finished.
    """
    directory = pathlib.Path(directory)
    if (read_json(directory / SUMMARY) or {}).get("status") == "finished":
        raise CheckpointError(f"nothing to resume: the run in {directory} finished")
    return _read(directory / CHECKPOINT, fingerprint, meta_only=True)[0]


def read(path: str | pathlib.Path, fingerprint: str | None = None
         ) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """Read a checkpoint: ``(meta, arrays)``.

    Args:
        path: The checkpoint file.
        fingerprint: When given, the checkpoint's case fingerprint must equal it.

    Raises:
        CheckpointError: No file, an unreadable file, another format, or another case.
    """
    return _read(path, fingerprint, meta_only=False)


def _read(path: str | pathlib.Path, fingerprint: str | None, meta_only: bool
          ) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    path = pathlib.Path(path)
    if not path.is_file():
        raise CheckpointError(f"nothing to resume: no checkpoint {path} (was the run "
                              "started with output.checkpoint_interval > 0?)")
    try:
        with np.load(path, allow_pickle=False) as data:
            bad = data.zip.testzip() if meta_only else None  # every entry's CRC-32
            if bad is not None:
                raise zipfile.BadZipFile(f"bad CRC-32 for '{bad}'")
            names = ["meta"] if meta_only else data.files
            arrays = {k: data[k] for k in names}
        meta = json.loads(str(arrays.pop("meta")))
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as e:
        # A torn or damaged file (a node that died while a file system without ordered
        # writes held it, a copy cut short) is an unreadable checkpoint, not a traceback.
        raise CheckpointError(f"cannot read the checkpoint {path}: "
                              f"{e or type(e).__name__} (run it without --resume)") from e
    if meta.get("format") != FORMAT:
        raise CheckpointError(f"{path}: checkpoint format {meta.get('format')} is not "
                              f"this version's ({FORMAT})")
    if fingerprint is not None and meta.get("fingerprint") != fingerprint:
        raise CaseMismatch.of(path)
    return meta, arrays
