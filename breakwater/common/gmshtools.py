"""gmsh helpers: a quiet session that always cleans up, and the named groups of a file.

Every use of gmsh in breakwater (reading and generating meshes, meshing ``.geo``
scripts, reading their group names) goes through :func:`gmsh_session`: it initialises
gmsh without reading the user's configuration files and without a terminal, and
finalises it on exit, even on errors. Inside a session the caller already opened, it
works in a fresh model and leaves the caller's model and options as it found them.

``gmsh.initialize`` installs gmsh's own C-level handlers of SIGTERM and SIGINT (even
with ``interruptible=False``), and ``gmsh.finalize`` leaves them: a SIGTERM then
killed the process outright instead of reaching Python's handler (a run or a study
stopping cleanly, :class:`~breakwater.common.console.StopSignal`). The session reinstalls
Python's handlers after initialising gmsh. Only the first initialisation of a process
touches the handlers: :func:`settle_signal_handlers` does it before a study starts
catching the signals.
"""

from __future__ import annotations

import pathlib
import signal
import threading
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from types import MappingProxyType

import gmsh  # type: ignore[import-untyped]

__all__ = ["MESH_SUFFIXES", "QUIET", "UNNAMED", "GroupNameError", "gmsh_session",
           "named_groups", "physical_groups", "restore_python_handlers",
           "settle_signal_handlers", "unsupported_format"]

STOP_SIGNALS = (signal.SIGTERM, signal.SIGINT)
"""The signals whose handlers gmsh replaces and the session gives back to Python."""

QUIET: Mapping[str, float] = MappingProxyType({"General.Terminal": 0})
"""gmsh options of a session that prints nothing."""


@contextmanager
def gmsh_session(options: Mapping[str, float] = QUIET, model: str = "breakwater"
                 ) -> Iterator[None]:
    """Work in a new gmsh model, quiet, with the given (numeric) options.

    Initialises gmsh if needed and then finalises it on exit; inside a session the
    caller opened, it removes its model and restores the options and the caller's
    current model instead.

    Args:
        options: gmsh options set for the session, over :data:`QUIET`.
        model: Name of the model added for the session.

    """
    options = {**QUIET, **options}
    owner = not gmsh.isInitialized()
    if owner:
        _initialize()
    previous = None if owner else gmsh.model.getCurrent()
    saved = {name: gmsh.option.getNumber(name) for name in options}
    for name, value in options.items():
        gmsh.option.setNumber(name, value)
    gmsh.model.add(model)
    try:
        yield
    finally:
        if owner:
            gmsh.finalize()
        else:
            gmsh.model.remove()
            for name, value in saved.items():
                gmsh.option.setNumber(name, value)
            if previous is not None:
                gmsh.model.setCurrent(previous)


_initialised_once = False


def _initialize() -> None:
    """``gmsh.initialize``, then Python's handlers of the stop signals back."""
    global _initialised_once
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    _initialised_once = True
    restore_python_handlers()


def settle_signal_handlers() -> None:
    """Initialise gmsh once in this process, before SIGTERM and SIGINT are caught.

    Only the first ``gmsh.initialize`` of a process touches the signal handlers (its
    own, then the default action, for about 10 ms); a signal then, even blocked in
    the main thread, reaches another thread (OpenBLAS's) and kills the process. Called
    before a study starts catching the signals; later sessions leave them alone.
    """
    if not _initialised_once and not gmsh.isInitialized():
        _initialize()
        gmsh.finalize()
        restore_python_handlers()


def restore_python_handlers() -> None:
    """Reinstall Python's handlers of SIGTERM and SIGINT (after gmsh replaced them).

    ``signal.getsignal`` still reports Python's handler after gmsh replaced it in C;
    setting it again puts Python's C-level handler back. Only the main thread can.
    """
    if threading.current_thread() is not threading.main_thread():
        return
    for sig in STOP_SIGNALS:
        handler = signal.getsignal(sig)
        if handler is not None:
            signal.signal(sig, handler)


UNNAMED = ("the mesh has no named physical groups (breakwater finds bodies and boundaries "
           "by name): name them in gmsh (Physical Surface(\"block\") = {1};) or, writing "
           "with meshio, give field_data = {\"block\": [tag, dim]}")
"""The error of a mesh whose physical groups have tags only (meshio's without field_data)."""

_FORMATS = {".xdmf": "XDMF", ".h5": "XDMF", ".bp": "ADIOS2", ".vtu": "VTK", ".vtk": "VTK",
            ".inp": "Abaqus", ".med": "MED", ".unv": "I-DEAS", ".stl": "STL", ".mesh": "Medit"}


MESH_SUFFIXES = (".geo", ".msh", *_FORMATS)
"""The suffixes of mesh files (gmsh's, XDMF and the formats :func:`unsupported_format` refuses):
not case files."""


def unsupported_format(path: pathlib.Path) -> str:
    """The message (naming the file) refusing a mesh that is not a ``.msh``, ``.geo`` or XDMF.

    breakwater's own XDMF (``breakwater mesh --out x.xdmf``) is read
    (:mod:`breakwater.common.xdmfinfo`); its ``.h5`` is named as its data file.
    """
    if path.suffix.lower() == ".h5":
        return (f"{path}: an HDF5 data file: give the .xdmf written with it (by "
                "`python -m breakwater mesh CASE --out x.xdmf`), or the gmsh .msh")
    kind = _FORMATS.get(path.suffix.lower())
    if kind is None:
        return f"expected a gmsh .msh or .geo file (or breakwater's .xdmf): {path}"
    return (f"{path}: breakwater reads gmsh .msh or .geo files, not {kind}: save the mesh "
            "from gmsh as .msh with its physical groups named (meshio's conversions keep "
            "integer tags only; docs/inputs.md)")


class GroupNameError(ValueError):
    """A mesh file's physical names cannot be told apart or decoded."""


def physical_groups(path: pathlib.Path) -> dict[str, int]:
    """Named physical groups (name -> dimension) of a gmsh ``.msh`` or ``.geo`` file.

    A ``.msh`` file is not read beyond its ``$PhysicalNames`` header; a ``.geo``
    script is opened by gmsh but not meshed.

    Raises:
        ValueError: A ``.msh`` file without a gmsh header.
        GroupNameError: A name given to groups of two dimensions, or names that are not
            UTF-8.
        Exception: What gmsh raises on a script it cannot read.

    """
    if path.suffix == ".msh":
        return named_groups(_msh_groups(path))
    with gmsh_session():
        gmsh.merge(str(path))  # into the session's model (open would make another)
        return named_groups([(gmsh.model.getPhysicalName(d, t), d)
                       for d, t in gmsh.model.getPhysicalGroups()
                       if gmsh.model.getPhysicalName(d, t)])


def named_groups(pairs: list[tuple[str, int]]) -> dict[str, int]:
    """Name -> dimension, refusing a name given to two dimensions (dolfinx keeps one)."""
    groups: dict[str, int] = {}
    for name, dim in pairs:
        if groups.setdefault(name, dim) != dim:
            which = " and a ".join(f"{d}D" for d in sorted({dim, groups[name]}, reverse=True))
            raise GroupNameError(f"the name '{name}' is given to a {which} physical group; "
                                 "breakwater finds groups by name: rename one of them in gmsh")
    return groups


def _msh_groups(path: pathlib.Path) -> list[tuple[str, int]]:
    """Physical group names and dimensions, from the header of a gmsh ``.msh`` file."""
    groups: list[tuple[str, int]] = []
    with path.open("rb") as fh:
        first = fh.readline().strip()
        if first == b"\xef\xbb\xbf$MeshFormat":  # gmsh: "line 1: syntax error ($)"
            raise ValueError("it begins with a byte-order mark, which gmsh does not read: "
                             "save it as UTF-8 without BOM")
        if first in (b"$NOD", b"$NOE"):  # format 1: no names, no header
            raise ValueError("gmsh format 1, which cannot name physical groups: write it in "
                             "format 4.1 (gmsh -format msh41, or Mesh.MshFileVersion = 4.1)")
        if first.startswith(b"("):  # Fluent's "(0 ...)" or "(1 ...)" sections
            raise ValueError("an ANSYS Fluent mesh (the same .msh suffix), not gmsh's: "
                             "export the mesh from gmsh, with named physical groups")
        if first != b"$MeshFormat":
            raise ValueError("not a gmsh .msh file (no $MeshFormat header)")
        for line in fh:
            s = line.strip()
            if s == b"$PhysicalNames":
                for _ in range(int(fh.readline())):
                    raw = fh.readline()
                    try:
                        dim, _tag, name = raw.decode().split(maxsplit=2)
                    except UnicodeDecodeError:
                        shown = raw.decode(errors="replace").split(maxsplit=2)[-1].strip()
                        raise GroupNameError(f"the physical name {shown} is not UTF-8 text: "
                                             "save the .geo (or the names) in UTF-8") from None
                    groups.append((name.strip().strip('"'), int(dim)))
                break
            if s in (b"$Entities", b"$Nodes", b"$Elements", b"$PartitionedEntities"):
                break
    return groups
