"""Case files: a whole breakwater computation described in TOML, SI units.

A case file names the mesh (the built-in Goda generator or a gmsh file with named
physical groups), the bodies and their materials, the boundary conditions, the
contact pairs, the loads, damping, the optional stiffness calibration, the time
integration and the outputs. :func:`load_case` reads it into typed, validated, frozen
dataclasses (:class:`Case`); :meth:`Case.build` (:mod:`breakwater.casefile.build`) turns it
into what the run layer needs (a :class:`~breakwater.model.model.ContactModel`, a
:class:`~breakwater.config.runspec.TimeSpec` and an :class:`~breakwater.config.runspec.OutputSpec`).
The TOML reading itself (types, unknown keys, ``extends``, ``--set``, the reference)
is :mod:`breakwater.config.schema`.

Reading a case needs no solver stack (no dolfinx, PETSc or UFL): the tables are
:mod:`breakwater.casefile.tables` and :mod:`breakwater.casefile.loads`, the whole case's
settings and cross-checks :class:`~breakwater.casefile.settings.CaseSettings`, and this
module reads the files (and checks the groups the case names against the mesh file's).
:class:`Case` adds the building methods, which import
:mod:`breakwater.casefile.build` (and so the solver stack) when called.

Named collections (``bodies``, ``contact``, ``fixed``, ``loads``, ``output.probes``,
``output.pair_probes``) are TOML tables keyed by name, e.g. ``[bodies.caisson]``; a
body's name is its cell group, a contact pair's name its interface facet group, a
fixed boundary's name its facet group. ``extends = "goda"`` (a built-in case) or
``extends = "other.toml"`` starts from another case and merges this file over it,
table by table. ``--set key=value`` overrides (:func:`load_case`'s ``overrides``)
change any field by its dotted path, e.g. ``time.dt=5e-5``,
``bodies.mound.density=1800``, ``contact.interface.friction=0.5`` (an entry of a
named collection may also be given by its index: ``contact.0.friction=0.5``); values
are TOML values (a bare word is taken as a string); a table value merges into the
case's table, or makes a new entry of a named collection (``fixed.rear={components=[0]}``).

Every problem with a case is a :class:`CaseError` with one line naming the file (or
``--set``), the field and the problem; :func:`case_reference` lists every key with its
type, unit and default.
"""

from __future__ import annotations

import pathlib
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from breakwater.casefile.dimension import dimension, general_in_3d, mesh_problem
from breakwater.casefile.loads import GodaCase, LoadCase, PendulumCase, ProfileCase, TableCase
from breakwater.casefile.settings import CaseSettings
from breakwater.casefile.tables import (
    GODA,
    GODA3D,
    BodyCase,
    CalibrationCase,
    ContactCase,
    DampingCase,
    FixedCase,
    InitialCase,
    MeshCase,
    OutputCase,
    PairProbeCase,
    ProbeCase,
    TimeCase,
)
from breakwater.common.errors import CaseError, MeshError
from breakwater.common.files import path_problem
from breakwater.common.gmshtools import (
    MESH_SUFFIXES,
    UNNAMED,
    GroupNameError,
    physical_groups,
    unsupported_format,
)
from breakwater.common.xdmfinfo import is_xdmf, xdmf_groups
from breakwater.config.fields import InvalidField, suggest, to_toml
from breakwater.config.overrides import file_argument, override_list
from breakwater.config.schema import Schema

if TYPE_CHECKING:
    from dolfinx.io import gmsh as gmshio
    from mpi4py import MPI

    from breakwater.casefile.build import BuiltCase
    from breakwater.model.model import ContactModel
    from breakwater.statics.calibrate import CalibrationResult

__all__ = [
    "BUILTIN_CASES",
    "BodyCase",
    "CalibrationCase",
    "Case",
    "ContactCase",
    "DampingCase",
    "FixedCase",
    "GodaCase",
    "InitialCase",
    "LoadCase",
    "MeshCase",
    "OutputCase",
    "PairProbeCase",
    "PendulumCase",
    "ProbeCase",
    "ProfileCase",
    "TableCase",
    "TimeCase",
    "builtin_case",
    "case_inputs",
    "case_reference",
    "case_sources",
    "is_file_value",
    "load_case",
    "override_list",
]


BUILTIN_CASES = pathlib.Path(__file__).parent.parent / "cases"
"""Folder of the built-in case files (package data)."""
DEFAULT_CASE = "goda"


class Case(CaseSettings):
    """A whole case: its settings and the building of its run.

    The settings, their checks and derived values are
    :class:`~breakwater.casefile.settings.CaseSettings`'s. The building methods call
    :mod:`breakwater.casefile.build`, imported when they are called (reading a case
    needs no solver stack).
    """

    def mesh_file(self, comm: MPI.Comm, directory: str | pathlib.Path | None = None
                  ) -> pathlib.Path:
        """The gmsh ``.msh`` file of the case (see :func:`.build.mesh_file`)."""
        from breakwater.casefile import build as casebuild

        return casebuild.mesh_file(self, comm, directory)

    def read_mesh(self, comm: MPI.Comm, directory: str | pathlib.Path | None = None
                  ) -> gmshio.MeshData:
        """Generate (or find) and read the mesh (see :func:`.build.read_mesh`)."""
        from breakwater.casefile import build as casebuild

        return casebuild.read_mesh(self, comm, directory)

    def build_model(self, data: gmshio.MeshData,
                    shear_moduli: Mapping[str, float] | None = None,
                    dynamic: bool = True) -> ContactModel:
        """The contact model of the case on a mesh (see :func:`.build.build_model`)."""
        from breakwater.casefile import build as casebuild

        return casebuild.build_model(self, data, shear_moduli, dynamic)

    def calibrate(self, data: gmshio.MeshData, target: float | None = None
                  ) -> CalibrationResult:
        """Calibrate a shear modulus (see :func:`.build.calibrate`)."""
        from breakwater.casefile import build as casebuild

        return casebuild.calibrate(self, data, target)

    def build(self, comm: MPI.Comm | None = None) -> BuiltCase:
        """Mesh, calibrate and build the run's inputs (see :func:`.build.build`).

        Returns:
            A :class:`~breakwater.casefile.build.BuiltCase`, which unpacks as
            ``model, time, output, extra``; its ``case`` is the case as run.

        """
        from breakwater.casefile import build as casebuild

        return casebuild.build(self, comm)


# --- reading files ------------------------------------------------------------------

def builtin_case(name: str) -> pathlib.Path:
    """The path of a built-in case (e.g. ``"goda"``)."""
    path = BUILTIN_CASES / f"{name}.toml"
    if not path.is_file():
        known = ", ".join(sorted(p.stem for p in BUILTIN_CASES.glob("*.toml")))
        raise CaseError(f"no built-in case '{name}' (built-in: {known})")
    return path


_SCHEMA = Schema(Case, builtin=builtin_case, paths={"mesh.source": (GODA, GODA3D),
                                                   "loads.*.table.file": (),
                                                   "loads.*.storm.waves": ()})
"""The TOML form of a case (``mesh.source`` is a path unless it is "goda" or "goda3d"; so are a load
table's ``file`` and a storm's ``waves`` when a string)."""


def is_file_value(key: str, value: Any) -> bool:
    """Whether ``value`` of the dotted case key ``key`` names a file.

    Such values (``mesh.source`` unless "goda", a load table's ``file``) are resolved
    against the file that gives them.
    """
    names = _SCHEMA.path_key(key)
    return names is not None and isinstance(value, str) and value not in names


# --- physical groups of the mesh ------------------------------------------------------

def _mesh_groups(mesh: MeshCase) -> dict[str, int]:
    """The named physical groups of the case's mesh (name -> dimension)."""
    if mesh.generated:
        return {name: dim for name, (dim, _) in mesh.geometry.physical_groups.items()}
    problem = path_problem(mesh.source)  # a whole [mesh] table given by --set
    if problem is not None:
        raise InvalidField("mesh.source", problem)
    path = pathlib.Path(mesh.source)
    if not path.is_file():
        raise InvalidField("mesh.source", f"mesh file not found: {path}")
    if is_xdmf(path):  # breakwater's own XDMF keeps the names in a record
        try:
            return xdmf_groups(path)
        except MeshError as e:
            raise InvalidField("mesh.source", str(e)) from None
    if path.suffix not in (".msh", ".geo"):
        raise InvalidField("mesh.source", unsupported_format(path))
    try:
        groups = physical_groups(path)
    except GroupNameError as e:
        raise InvalidField("mesh.source", f"{path}: {e}") from None
    except Exception as e:  # unreadable: any parse error (gmsh raises bare Exceptions)
        raise InvalidField("mesh.source", f"cannot read the mesh {path} ({e})") from None
    if not groups:
        raise InvalidField("mesh.source", f"{path}: {UNNAMED}")
    return groups


def _check_groups(case: Case, groups: Mapping[str, int]) -> None:
    """The mesh is of the case's dimension, and every group the case names is in it.

    Each with the right dimension: cells the case's, facets one less, points 0.
    """
    where = f"the {case.mesh.source} mesh" if case.mesh.generated else case.mesh.source
    d = dimension(case)
    problem = mesh_problem(case, max(groups.values()))
    if problem is not None:
        raise InvalidField("mesh.source", problem)
    general_in_3d(case)  # after the mesh's dimension: a 2D mesh with 3 components is that
    names = {0: "point", d - 1: "facet", d: "cell" if d == 2 else "volume"}

    def need(name: str, dim: int | tuple[int, ...], field_path: str) -> None:
        dims = (dim,) if isinstance(dim, int) else dim
        if groups.get(name) in dims:
            return
        have = sorted(n for n, d in groups.items() if d in dims)
        kinds = " or ".join(f"{names.get(k, 'edge')} ({k}D)" for k in dims)
        if name in groups:  # there, of another dimension: no look-alike to suggest
            k = groups[name]
            raise InvalidField(field_path, f"'{name}' is a {names.get(k, 'edge')} ({k}D) "
                               f"physical group of {where}, where a {kinds} group is "
                               f"needed (it has: {', '.join(have) or 'none'})")
        raise InvalidField(field_path, f"no {kinds} physical group "
                           f"'{name}' in {where}{suggest(name, have)} (it has: "
                           f"{', '.join(have) or 'none'})")

    for b in case.bodies:
        need(b.name, d, f"bodies.{b.name}")
    for c in case.contact:
        if c.general:
            need(c.slave_surface or "", d - 1, f"contact.{c.name}.slave_surface")
            if isinstance(c.master_surface, tuple):
                for k, group in enumerate(c.master_surface):
                    need(group, d - 1, f"contact.{c.name}.master_surface[{k}]")
            else:
                need(c.master_surface or "", d - 1, f"contact.{c.name}.master_surface")
        else:
            need(c.name, d - 1, f"contact.{c.name}")
    interfaces = {c.name for c in case.contact if not c.general}
    slave_surfaces = {c.slave_surface: c.name for c in case.contact if c.general}
    for f in case.fixed:
        need(f.name, (d - 1, 0), f"fixed.{f.name}")  # a facet group, or points
        if f.name in slave_surfaces:  # it ran: the slave's face held, the pair carrying 0 N
            raise InvalidField(f"fixed.{f.name}", f"'{f.name}' is the slave surface of "
                               f"contact pair '{slave_surfaces[f.name]}': holding it holds "
                               "the face the pair presses, which then carries nothing; "
                               "hold a face of one body away from the contact (the "
                               "support's bottom), or leave the pair out")
        if f.name in interfaces:  # it ran: both sides held, the pair carrying nothing
            raise InvalidField(f"fixed.{f.name}", f"'{f.name}' is the interface of contact "
                               f"pair '{f.name}': holding it holds both bodies' faces there "
                               "and the pair carries nothing; hold a face of one body (the "
                               "support's bottom), or leave the pair out")
    for ld in case.loads:
        need(ld.group, d - 1, f"loads.{ld.name}.group")
        for k, extra in enumerate(ld.groups):
            need(extra, d - 1, f"loads.{ld.name}.groups[{k}]")
        if ld.goda is not None and ld.goda.uplift_group is not None:
            need(ld.goda.uplift_group, d - 1, f"loads.{ld.name}.goda.uplift_group")
    for p in case.output.probes:
        if p.group is not None:
            need(p.group, 0, f"output.probes.{p.name}.group")
    for q in case.output.pair_probes:
        if q.group is not None:
            need(q.group, 0, f"output.pair_probes.{q.name}.group")


# --- the entry point --------------------------------------------------------------------

def load_case(path: str | pathlib.Path | None = None, overrides: Sequence[str] | None = (),
              *, static: bool = False) -> Case:
    """Read, override and validate a case.

    Args:
        path: A case file; a built-in case name (``"goda"``); None for the default
            (Goda) case.
        overrides: ``key=value`` strings (dotted paths, TOML values), a list or a
            tuple (None: none; a single string is refused, see :func:`override_list`).
        static: For a static solve alone (``calibrate``): a case without ``[time]``
            is read with :data:`STATIC_TIME` and without its loads (neither is used;
            the loads' checks against the time step would refuse it). A run refuses
            it: ``time: missing required key``.

    Returns:
        The validated case.

    Raises:
        CaseError: One line naming the file (or ``--set``), the field and the problem.

    """
    case: Case = _SCHEMA.load(_case_file(path), override_list(overrides),
                              check=lambda c: _check_groups(c, _mesh_groups(c.mesh)),
                              prepare=_static_time if static else None,
                              check_raw=_unused_generator)
    return case


def _unused_generator(raw: dict[str, Any], where: Callable[[str], str],
                      order: Sequence[str]) -> None:
    """Refuse a ``[mesh.goda]``/``[mesh.goda3d]`` value that the mesh source leaves unused.

    Such a value (not the default) set where ``mesh.source`` names another mesh (the same
    file, or ``--set``) ran without a word, the mesh read as it is (a caisson 20 m wide in
    ``[mesh.goda]`` beside ``source = "my.msh"``), or set after it (a file extending
    ``goda3d`` with a ``[mesh.goda]`` caisson_width: the block stayed 0.205 m wide, as the
    ``goda3d`` mesh takes its cross-section from ``[mesh.goda3d]``). A value inherited from
    a case that the source's file extends is not refused (``examples/goda_apart``: its
    own ``.geo`` over ``goda_nonmatching.toml``), nor a default written out (a resolved
    case's tables).

    Raises:
        InvalidField: The first such key, naming the source.
    """
    mesh = raw.get("mesh")
    if not isinstance(mesh, dict) or "source" not in mesh:
        return
    source = mesh["source"]
    for table in (GODA, GODA3D):
        keys = mesh.get(table)
        if source == table or not isinstance(keys, dict):
            continue
        defaults = to_toml(MeshCase(source=GODA))
        for key, value in keys.items():
            path = f"mesh.{table}.{key}"
            if value != defaults[table].get(key, value) \
                    and order.index(where(path)) >= order.index(where("mesh.source")):
                used = f"the built-in {source} mesh" if source in (GODA, GODA3D) else \
                    f"the file {pathlib.Path(str(source)).name}"
                raise InvalidField(path, f"sets the built-in {table} mesh, but mesh.source "
                                   f"reads {used}, which it does not change: "
                                   f"{_unused_fix(source, table, key, defaults)}")


def _unused_fix(source: str, table: str, key: str, defaults: dict[str, Any]) -> str:
    """What to do with ``mesh.<table>.<key>`` that the mesh ``source`` leaves unused."""
    if source == GODA3D and key == "conforming":
        return ("remove it: the goda3d mesh is conforming only (bodies meshed apart in 3D: "
                "a tetrahedral mesh file and a general pair)")
    if source == GODA3D and key in defaults[GODA3D]:
        return f"remove it, or set mesh.{GODA3D}.{key} (the {GODA3D} mesh's own)"
    return f"remove it, or set mesh.source = \"{table}\""


STATIC_TIME = {"dt": 0.5, "end_time": 1.0}
"""The ``[time]`` of a case read for a static solve alone, when it has none (unused)."""


def _static_time(raw: dict[str, Any]) -> None:
    """A case without ``[time]`` read for a static solve: :data:`STATIC_TIME`, no loads."""
    if "time" not in raw:
        raw["time"] = dict(STATIC_TIME)
        raw["loads"] = {}


def _case_file(path: str | pathlib.Path | None) -> pathlib.Path:
    """The file of a case argument: a file, a built-in name, or None (the default)."""
    if path is None:
        return builtin_case(DEFAULT_CASE)
    file_argument(path, "a case file (or a built-in case's name, 'goda')")
    file = pathlib.Path(path)
    if not file.exists() and file.suffix == "" and "/" not in str(path):
        return builtin_case(str(path))
    if not file.is_file():
        raise CaseError(f"{path}: case file not found")
    if file.suffix.lower() in MESH_SUFFIXES:
        # (read as TOML it was "invalid TOML: Invalid statement (at line 1, column 1)")
        raise CaseError(f"{path}: a mesh, not a case file: name it in a case file "
                        f"(mesh.source = \"{file.name}\", with its bodies, contact and "
                        "loads: docs/case.md, 'Bring your own geometry')")
    return file


def case_sources(path: str | pathlib.Path | None) -> list[pathlib.Path]:
    """The case file of a case argument and the files it extends."""
    return _SCHEMA.sources(_case_file(path))


def case_inputs(path: str | pathlib.Path | None, case: Case) -> list[pathlib.Path]:
    """Every file a case reads: the case file and those it extends, the mesh, the tables.

    Args:
        path: The case argument of :func:`load_case`.
        case: The case it gave.
    """
    inputs = case_sources(path)
    if not case.mesh.generated:
        inputs.append(pathlib.Path(case.mesh.source))
        if is_xdmf(inputs[-1]):  # and its arrays, written beside it
            inputs.append(inputs[-1].with_suffix(".h5"))
    inputs += [pathlib.Path(ld.table.file) for ld in case.loads
               if ld.table is not None and ld.table.file is not None]
    inputs += [pathlib.Path(ld.storm.waves) for ld in case.loads
               if ld.storm is not None and isinstance(ld.storm.waves, str)]
    return inputs


def case_reference() -> str:
    """A Markdown table of every case key: type, unit, default, meaning."""
    return _SCHEMA.reference()
