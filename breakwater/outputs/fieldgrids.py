"""A run's ParaView fields as pyvista grids, for a notebook.

The fields are written as VTX (ADIOS2 ``.bp``, :class:`~breakwater.outputs.writers.
FieldWriter`), which ParaView reads and pyvista (VTK's pip wheel, without ADIOS2) does
not. :func:`read_fields` reads one time of ``fields_<body>.bp`` or ``contact_<pair>.bp``
with ADIOS2's Python module and returns a ``pyvista.UnstructuredGrid``: the P2 cells
(VTK's Lagrange triangles, tetrahedra, hexahedra, curves), in the reference
configuration, with every field of the file as point data (``displacement``,
``velocity``, ``stress``, ``von_mises``, ``stress_yy``; a pair's ``pressure``, ``gap``,
``slip``, ``slip_velocity``, ``friction_traction``), vectors with three components
(``grid.warp_by_vector("displacement", factor=20)``), and the time read in
``grid.field_data["time"]``. Nothing more is written during the run: the files are the
ParaView ones.

A file written on several ranks holds one block per rank, each with the rank's cells
and its ghost cells; the blocks are joined and the ghost copies dropped (a cell is kept
once, by the position of its nodes), so the grid is the one of a serial run; a rank
that holds no cell of the body or pair wrote an empty block, left out. The
earlier parts of a resumed run (``fields_<body>.part<k>.bp``) are read as well; where
two files hold one time, the later file's is read.
"""

from __future__ import annotations

import pathlib
from dataclasses import dataclass
from typing import Any

import numpy as np

from breakwater.outputs.bpcheck import BPDamaged, check_bp

__all__ = ["field_names", "field_times", "read_fields"]

_GEOMETRY = ("geometry", "connectivity", "types", "NumberOfNodes", "NumberOfEntities",
             "NumberOfCells", "step", "vtkGhostType", "vtkOriginalPointIds")


@dataclass(frozen=True)
class _Stored:
    """One time of a field file: its time, the file and the ADIOS2 step."""

    time: float
    path: pathlib.Path
    step: int


def field_names(directory: str | pathlib.Path) -> list[str]:
    """The field files of a run's folder, by stem (``fields_caisson``, ``contact_interface``)."""
    folder = pathlib.Path(directory)
    return sorted(p.name.removesuffix(".bp") for p in folder.glob("*.bp")
                  if p.name.startswith(("fields_", "contact_")) and ".part" not in p.name)


def _files(directory: str | pathlib.Path, name: str) -> list[pathlib.Path]:
    """The files of ``name`` (a body, a pair or a file's stem), earlier parts first."""
    folder = pathlib.Path(directory)
    if not isinstance(name, str):  # (None: 'NoneType' object has no attribute ...)
        raise ValueError(f"name: expected a body's or a contact pair's name (a str), got "
                         f"{type(name).__name__} {name!r}")
    names = field_names(folder)
    stem = name.removesuffix(".bp")
    if stem not in names:
        matches = [n for n in (f"fields_{stem}", f"contact_{stem}") if n in names]
        if not matches:
            raise ValueError(f"{folder}: no field file of '{name}' (the run's: "
                             f"{', '.join(names) or 'none'})")
        if len(matches) > 1:
            raise ValueError(f"{folder}: '{name}' is a body and a pair: name the file, "
                             f"{' or '.join(repr(m) for m in matches)}")
        stem = matches[0]

    def part(p: pathlib.Path) -> int:
        return int(p.name.removesuffix(".bp").rsplit(".part", 1)[1])

    parts = sorted((p for p in folder.glob(f"{stem}.part*.bp")
                    if p.name.removesuffix(".bp").rsplit(".part", 1)[1].isdigit()), key=part)
    return [*parts, folder / f"{stem}.bp"]


#: Why a file's index can list more than its data files hold.
_CUT = ("a copy of a run still running, or a run killed, stopped by a full disk or a "
        "power loss")
#: What to do about a file that cannot be read.
_AGAIN = "copy the folder again once the run has ended, or run the case again"


class _CutShort(Exception):
    """ADIOS2 failed to read what the file's index lists (a data or metadata file cut)."""


class _Damaged(Exception):
    """A data file holds cells that are none (zeros: a power loss's zero-filled blocks)."""


def _reader(path: pathlib.Path) -> Any:
    """An ADIOS2 reader of ``path`` that fails at once on a file cut short.

    ADIOS2's default (POSIX) transport retries a read past the end of a data file
    forever, waiting for a writer to append (a data file shorter than its index: a copy
    of a running run, a run killed in a write, a power loss): a notebook hung. The
    ``stdio`` transport for the data files (engine parameter ``DataFileTransport``)
    raises instead; ``OpenTimeoutSecs`` bounds the wait for a metadata file shorter
    than its index (10 s by default). The metadata files are checked first
    (:func:`~breakwater.outputs.bpcheck.check_bp`): ADIOS2 crashed the process on an
    ``mmd.0`` cut short or zero-filled and on an empty ``md.idx``.

    Raises:
        _CutShort: ADIOS2 cannot open it.
        ValueError: A metadata file missing, empty, cut short or damaged, in one line.
    """
    # dolfinx first: with the pip module's ADIOS2 library loaded before it, dolfinx's own
    # (the dolfinx wheel's) fails to load ("undefined symbol ... HDF5Common_MPI_API").
    import dolfinx  # noqa: F401

    try:
        import adios2
    except ImportError:
        raise ImportError("reading the .bp fields needs ADIOS2's Python module: "
                          "pip install adios2 (or breakwater's 'viz' extra)") from None
    try:
        check_bp(path)
    except BPDamaged as damaged:
        raise ValueError(f"{path}: cannot be read, its {damaged} ({_CUT}); {_AGAIN}"
                         ) from None
    io = adios2.Adios().declare_io(f"breakwater:{path}")
    io.set_parameters({"DataFileTransport": "stdio", "OpenTimeoutSecs": "1"})
    try:
        return adios2.FileReader(io, str(path))
    except RuntimeError as error:
        raise _CutShort(str(error)) from None


def _stored(directory: str | pathlib.Path, name: str) -> list[_Stored]:
    """Every time stored for ``name``, in order; a later file's where two hold one.

    Raises:
        ValueError: A file whose metadata is cut short (ADIOS2 cannot open it).
    """
    by_time: dict[float, _Stored] = {}
    for path in _files(directory, name):
        try:
            with _reader(path) as f:
                for k in range(f.num_steps()):
                    t = float(np.asarray(f.read("step", step_selection=[k, 1])).ravel()[0])
                    by_time[t] = _Stored(t, path, k)
        except (_CutShort, RuntimeError):
            raise ValueError(f"{path}: cannot be read, its metadata is cut short or damaged "
                             f"({_CUT}); {_AGAIN}") from None
    return [by_time[t] for t in sorted(by_time)]


def field_times(directory: str | pathlib.Path, name: str) -> np.ndarray:
    """The times (s) at which the fields of ``name`` (a body or a pair) were written."""
    return np.array([s.time for s in _stored(directory, name)])


def _choose(stored: list[_Stored], time: float | None, name: str) -> _Stored:
    if not stored:
        raise ValueError(f"the fields of '{name}' hold no time yet")
    if time is None:
        return stored[-1]
    if isinstance(time, bool) or not isinstance(time, int | float | np.integer | np.floating):
        # ("0.1" failed in numpy: ufunc 'less_equal' did not contain a loop ...)
        raise ValueError(f"time: expected a number (s) or None (the last), got "
                         f"{type(time).__name__} {time!r}")
    times = np.array([s.time for s in stored])
    slack = 1e-9 * max(abs(times[-1]), abs(times[0]), 1e-300)
    if not times[0] - slack <= time <= times[-1] + slack:
        raise ValueError(f"no fields of '{name}' at t = {time:g} s: written from t = "
                         f"{times[0]:g} s to {times[-1]:g} s ({len(times)} times)")
    return stored[int(np.argmin(np.abs(times - time)))]


def _blocks(f: Any, step: int, names: list[str]) -> dict[str, np.ndarray]:
    """The blocks of each variable at ``step``, joined (connectivity renumbered).

    A rank that holds no cell of the body or pair wrote an empty block: skipped (ADIOS2's
    reader fails on one, dividing its size by its count of zero).
    """
    blocks = f.all_blocks_info("connectivity")[0]
    points, cells, data = [], [], {n: [] for n in names}  # type: ignore[var-annotated]
    offset = 0
    for b, block in enumerate(blocks):
        if 0 in [int(c) for c in str(block["Count"]).split(",") if c.strip()]:
            continue
        x = np.asarray(f.read("geometry", step_selection=[0, 1], block_id=b), float)
        c = np.asarray(f.read("connectivity", step_selection=[0, 1], block_id=b), np.int64)
        per = int(c.ravel()[0]) if c.size else 0  # the nodes of a cell
        if per < 1 or c.size % (per + 1):
            raise _Damaged
        c = c.reshape(-1, per + 1)
        if (c[:, 0] != per).any() or c[:, 1:].min() < 0 or c[:, 1:].max() >= x.size // 3:
            raise _Damaged
        points.append(x.reshape(-1, 3))
        cells.append(np.column_stack([c[:, 0], c[:, 1:] + offset]))
        offset += len(points[-1])
        for n in names:
            data[n].append(np.asarray(f.read(n, step_selection=[step, 1], block_id=b)))
    out = {n: np.concatenate(v).reshape(offset, -1) for n, v in data.items()}
    out["geometry"], out["connectivity"] = np.concatenate(points), np.concatenate(cells)
    return out


def _read_step(stored: _Stored) -> tuple[int, dict[str, np.ndarray]]:
    """The cell type and the joined blocks of one stored time.

    Raises:
        _CutShort: A data file holds fewer bytes than the index lists for this time.
        _Damaged: Its cells are none (zeros where the index lists them).
    """
    try:
        with _reader(stored.path) as f:
            names = [n for n in f.available_variables() if n not in _GEOMETRY]
            cell_type = int(np.asarray(f.read("types", step_selection=[0, 1])).ravel()[0])
            if cell_type <= 0:
                raise _Damaged
            return cell_type, _blocks(f, stored.step, names)
    except RuntimeError as error:  # ADIOS2's: "read size of 600 is not equal to ..."
        raise _CutShort(str(error)) from None


def _cut_message(stored: _Stored, every: list[_Stored]) -> str:
    """The line refusing a time cut short, naming the last whole time before it."""
    whole = "no earlier time of it is whole"
    for earlier in reversed([s for s in every if s.time < stored.time]):
        try:
            _read_step(earlier)
        except _CutShort:
            continue
        whole = f"the last whole time before it is t = {earlier.time:g} s"
        break
    size = sum(p.stat().st_size for p in stored.path.glob("data.*"))
    return (f"{stored.path}: the fields at t = {stored.time:g} s are cut short, its data "
            f"files hold {size} bytes, fewer than its index lists ({_CUT}); {whole}")


def read_fields(directory: str | pathlib.Path, name: str, time: float | None = None
                ) -> Any:
    """The fields of a body or a contact pair at one time, as a pyvista grid.

    Args:
        directory: The run's output folder (``output.directory``).
        name: A body (``fields_<name>.bp``) or a contact pair (``contact_<name>.bp``),
            or the file's stem.
        time: The time (s): the stored time nearest to it is read (the fields are
            written every ``output.field_interval`` steps); None: the last one.

    Returns:
        A ``pyvista.UnstructuredGrid`` in the reference configuration, the fields as
        point data (vectors and the stress tensor with 3 and 9 components), the time
        read in ``field_data["time"]``.

    Raises:
        ValueError: No such file in the folder, a name not a str or a time not a
            number, a time outside the ones written, or a
            file whose data or metadata is cut short at that time (its index lists more
            than its files hold: a copy of a running run, a run killed, a full disk); the
            line names the last whole time before it.
    """
    from breakwater.common.wholeimport import whole_imports

    with whole_imports():  # (an interrupt in its import broke it for the process)
        import pyvista

    every = _stored(directory, name)
    stored = _choose(every, time, name)
    try:
        cell_type, joined = _read_step(stored)
    except _CutShort:
        raise ValueError(_cut_message(stored, every)) from None
    except _Damaged:
        raise ValueError(f"{stored.path}: the fields at t = {stored.time:g} s are damaged, "
                         f"its data files hold no cells where its index lists them (zeros: "
                         f"{_CUT}); {_AGAIN}") from None
    x, cells = joined.pop("geometry"), joined.pop("connectivity")
    # One copy of each cell (a rank's ghost cells are another rank's), by its nodes' mean.
    scale = max(float(np.abs(x).max(initial=0.0)), 1e-300)
    centres = np.round(x[cells[:, 1:]].mean(axis=1) / scale, 10)
    _, first = np.unique(centres, axis=0, return_index=True)
    cells = cells[np.sort(first)]
    used = np.unique(cells[:, 1:])
    renumber = np.full(len(x), -1, np.int64)
    renumber[used] = np.arange(len(used))
    cells[:, 1:] = renumber[cells[:, 1:]]
    grid = pyvista.UnstructuredGrid(cells.ravel(), np.full(len(cells), cell_type, np.uint8),
                                    x[used])
    for n, values in joined.items():
        v = values[used]
        grid.point_data[n] = v[:, 0] if v.shape[1] == 1 else v
    grid.field_data["time"] = np.array([stored.time])
    return grid
