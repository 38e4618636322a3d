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

Named collections (``bodies``, ``contact``, ``fixed``, ``loads``, ``output.probes``,
``output.pair_probes``) are TOML tables keyed by name, e.g. ``[bodies.caisson]``; a
body's name is its cell group, a contact pair's name its interface facet group, a
fixed boundary's name its facet group. ``extends = "goda"`` (a built-in case) or
``extends = "other.toml"`` starts from another case and merges this file over it,
table by table. ``--set key=value`` overrides (:func:`load_case`'s ``overrides``)
change any field by its dotted path, e.g. ``time.dt=5e-5``,
``bodies.mound.density=1800``, ``contact.interface.friction=0.5`` (an entry of a
named collection may also be given by its index: ``contact.0.friction=0.5``); values
are TOML values (a bare word is taken as a string).

Every problem with a case is a :class:`CaseError` with one line naming the file (or
``--set``), the field and the problem; :func:`case_reference` lists every key with its
type, unit and default.
"""

from __future__ import annotations

import math
import pathlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Literal, get_args

from breakwater.casefile import build as casebuild
from breakwater.casefile.loads import GodaCase, LoadCase, PendulumCase, ProfileCase, TableCase
from breakwater.common.errors import CaseError
from breakwater.common.files import name_problem, path_problem
from breakwater.common.gmshtools import physical_groups
from breakwater.config.runspec import TimeSpec
from breakwater.config.schema import InvalidField, Schema, positive, setting, suggest, to_toml
from breakwater.meshes.goda import GodaGeometry
from breakwater.statics.initial import InitialCase

if TYPE_CHECKING:
    from dolfinx.io import gmsh as gmshio
    from mpi4py import MPI

    from breakwater.model.model import ContactModel, Material
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
]

BUILTIN_CASES = pathlib.Path(__file__).parent.parent / "cases"
"""Folder of the built-in case files (package data)."""
DEFAULT_CASE = "goda"
GODA = "goda"
"""``mesh.source`` value selecting the built-in Goda mesh generator."""


# --- the sections of a case -------------------------------------------------------

_GODA_GEOMETRY = GodaGeometry()


@dataclass(frozen=True)
class MeshCase:
    """``[mesh]``: where the mesh comes from."""

    source: str = setting(GODA, doc='"goda" (the built-in generator, [mesh.goda]) or a gmsh '
                          '.msh/.geo file with named physical groups, relative to the case file')
    refinement: float = setting(1.0, doc="goda only: element sizes are divided by this "
                                "(cell counts grow as refinement²)")
    degree: int = setting(2, doc="polynomial degree of the displacement (2: six-node "
                          "triangles, as the paper)")
    goda: GodaGeometry = setting(_GODA_GEOMETRY, unit="m",  # noqa: RUF009 (a field() with docs)
                                 doc="goda only: dimensions of the model (see below)")
    max_elements: int = setting(1_000_000, doc="goda only: refuse a mesh of more triangles "
                                "(estimated before meshing: each body's area over its "
                                "element's); refinement 9 makes about 49000")

    def __post_init__(self) -> None:
        if not (self.refinement > 0 and math.isfinite(self.refinement)):
            raise InvalidField("refinement", f"must be > 0 (got {self.refinement:g})")
        if self.degree not in (1, 2):
            raise InvalidField("degree", f"must be 1 or 2 (got {self.degree})")
        if not self.source:
            raise InvalidField("source", 'must be "goda" or a mesh file')
        positive(self.max_elements, "max_elements")
        if self.generated:
            coarse = self.goda.coarse_elements(self.refinement)
            if coarse is not None:
                raise InvalidField("refinement", f"{self.refinement:g}: {coarse}")
            estimate = self.goda.estimated_elements(self.refinement)
            if estimate > self.max_elements:
                raise InvalidField("max_elements", f"refinement {self.refinement:g} with "
                                   "the mesh.goda dimensions and element sizes makes "
                                   f"about {estimate:.3g} triangles, above the limit "
                                   f"{self.max_elements} (raise mesh.max_elements to mesh "
                                   "it)")

    @property
    def generated(self) -> bool:
        """True for the built-in Goda generator."""
        return self.source == GODA


@dataclass(frozen=True)
class BodyCase:
    """``[bodies.<name>]``: a deformable body, its cell group and its material.

    Give exactly one of ``shear_modulus`` and ``young_modulus``, or neither for the
    body whose shear modulus ``[calibration]`` finds.
    """

    name: str = setting(key=True, doc="cell (2D) physical group of the body")
    density: float = setting(unit="kg/m³", doc="mass density ρ")
    poisson: float = setting(doc="Poisson's ratio ν, in (−1, 0.5)")
    shear_modulus: float | None = setting(None, unit="Pa", doc="shear modulus G")
    young_modulus: float | None = setting(None, unit="Pa", doc="Young's modulus E")
    initial_velocity: tuple[float, ...] = setting((0.0, 0.0), unit="m/s", doc="uniform "
                                                  "velocity of the body at t = 0")

    def __post_init__(self) -> None:
        positive(self.density, "density")
        if len(self.initial_velocity) != 2 or not all(map(math.isfinite, self.initial_velocity)):
            raise InvalidField("initial_velocity", f"must be 2 finite numbers (got "
                               f"{list(self.initial_velocity)})")
        if not -1.0 < self.poisson < 0.5:
            raise InvalidField("poisson", f"Poisson's ratio must be in (-1, 0.5) (got "
                               f"{self.poisson:g})")
        for name in ("shear_modulus", "young_modulus"):
            value = getattr(self, name)
            if value is not None:
                positive(value, name)
        if self.shear_modulus is not None and self.young_modulus is not None:
            raise InvalidField("young_modulus", "give shear_modulus or young_modulus, not both")

    @property
    def has_modulus(self) -> bool:
        """True when the body gives its elastic modulus."""
        return self.shear_modulus is not None or self.young_modulus is not None

    def material(self, shear_modulus: float | None = None) -> Material:
        """The model material; ``shear_modulus`` replaces the case's (calibration)."""
        from breakwater.model.model import Material

        if shear_modulus is not None:
            return Material(self.density, self.poisson, shear_modulus=shear_modulus)
        if not self.has_modulus:
            raise InvalidField(f"bodies.{self.name}.shear_modulus", "missing")
        return Material(self.density, self.poisson, shear_modulus=self.shear_modulus,
                        young_modulus=self.young_modulus)


@dataclass(frozen=True)
class ContactCase:
    """``[contact.<interface>]``: penalty contact with regularised Coulomb friction.

    With ``slave_surface`` and ``master_surface`` the pair is general (surfaces that
    need not match, finite sliding: :mod:`breakwater.contact.general`) and ``<interface>``
    is just its name.
    """

    name: str = setting(key=True, doc="interface facet (1D) physical group, shared by the "
                        "two bodies (conforming); with slave_surface/master_surface, the "
                        "pair's name")
    slave: str = setting(doc="body whose nodes are penalised (the paper: the caisson)")
    master: str = setting(doc="body whose outward normal defines the gap (the mound)")
    penalty: float = setting(unit="N/m³", doc="normal penalty ε_n")
    friction: float = setting(0.0, doc="Coulomb friction coefficient μ (0: frictionless)")
    regularisation: float = setting(1e-10, unit="m/s", doc="regularisation velocity χ of "
                                    "the friction law (eq. 15)")
    gap: float = setting(0.0, unit="m", doc="initial normal gap g₀ (conforming pairs)")
    slave_surface: str | None = setting(None, doc="general pair: facet group on the slave's "
                                        "boundary (its integration points are projected)")
    master_surface: str | tuple[str, ...] | None = setting(
        None, doc="general pair: facet group on the master's boundary, or an array of "
        "them (one surface, e.g. a shared interface and the crest beyond it)")
    points: int = setting(3, doc="general pair: Gauss points per integration segment")
    integration: Literal["segments", "gauss", "nodes"] = setting(
        "segments", doc="general pair: the slave's integration points: segments "
        "(segment-to-segment, `points` Gauss points per segment), gauss (`points` per "
        "slave facet) or nodes (the slave nodes, Simpson weights: the conforming pair's "
        "quadrature)")
    rotations: Literal["finite", "small"] = setting(
        "finite", doc="general pair: the normal of the current master surface at the "
        "projection (finite, eq. 7) or of the reference one (small: the linear bodies' "
        "small rotations, as a conforming pair; finite sliding kept)")

    def __post_init__(self) -> None:
        if (self.slave_surface is None) != (self.master_surface is None):
            raise InvalidField("master_surface" if self.master_surface is None
                               else "slave_surface", "a general pair needs both "
                               "slave_surface and master_surface")
        if self.general and self.gap:
            raise InvalidField("gap", "a general pair takes its gap from the geometry "
                               "(remove gap)")
        if self.points < 1:
            raise InvalidField("points", f"must be >= 1 (got {self.points})")
        if self.master_surface == ():
            raise InvalidField("master_surface", "needs at least one facet group")
        positive(self.penalty, "penalty")
        positive(self.friction, "friction", strict=False)
        positive(self.regularisation, "regularisation")
        if self.slave == self.master:
            raise InvalidField("master", "slave and master must be different bodies")

    @property
    def general(self) -> bool:
        """A pair between two surfaces that need not match (not one shared group)."""
        return self.slave_surface is not None


@dataclass(frozen=True)
class FixedCase:
    """``[fixed.<group>]``: zero displacement on a facet group."""

    name: str = setting(key=True, doc="facet (1D) physical group")
    components: tuple[int, ...] = setting((0, 1), doc="fixed displacement components "
                                          "(0: x, 1: y)")

    def __post_init__(self) -> None:
        if not self.components:
            raise InvalidField("components", "fix at least one component")
        if any(c not in (0, 1) for c in self.components) or \
                len(set(self.components)) != len(self.components):
            raise InvalidField("components", f"must be distinct values among 0 (x) and 1 (y) "
                               f"(got {list(self.components)})")


@dataclass(frozen=True)
class DampingCase:
    """``[damping]``: Rayleigh damping C = αM + βK of every body."""

    alpha: float = setting(0.0, unit="1/s", doc="mass-proportional coefficient α")
    beta: float = setting(0.0, unit="s", doc="stiffness-proportional coefficient β")

    def __post_init__(self) -> None:
        positive(self.alpha, "alpha", strict=False)
        positive(self.beta, "beta", strict=False)


StiffnessBasis = Literal["block", "metre"]
"""How ``calibration.stiffness`` is read: the whole block's K_x, or per metre."""


@dataclass(frozen=True)
class CalibrationCase:
    """``[calibration]``: the shear modulus of ``body`` from a horizontal stiffness.

    See :mod:`breakwater.statics.calibrate`: a uniform horizontal acceleration of
    ``structure`` on bonded interfaces; K = load / mean displacement.
    """

    enabled: bool = setting(False, doc="calibrate when building the model (the body then "
                            "gives no modulus)")
    body: str = setting("", doc="body whose shear modulus is calibrated (its ν is kept)")
    structure: str = setting("", doc="body whose horizontal stiffness is matched")
    stiffness: float | None = setting(None, unit="N/m", doc="target stiffness K_x of the "
                                      "real structure (see stiffness_basis)")
    stiffness_basis: StiffnessBasis = setting("block", doc='"block": K_x is the whole '  # noqa: RUF009 (a field() with docs)
                                              "block's, divided by out_of_plane_length; "
                                              '"metre": K_x is already per metre of plane '
                                              "strain")
    tolerance: float = setting(1e-4, doc="relative tolerance on K_x")
    tangential_penalty: float = setting(1e3, doc="tangential stiffness of the bonded "
                                        "interface, as a multiple of ε_n")
    initial_guess: float = setting(1e7, unit="Pa", doc="first shear modulus tried")
    max_iterations: int = setting(30, doc="largest number of stiffness solves")

    def __post_init__(self) -> None:
        if self.stiffness is not None:
            positive(self.stiffness, "stiffness")
        if self.stiffness_basis not in get_args(StiffnessBasis):
            raise InvalidField("stiffness_basis", f'must be "block" or "metre" (got '
                               f"{self.stiffness_basis!r})")
        for name in ("tolerance", "tangential_penalty", "initial_guess"):
            positive(getattr(self, name), name)
        if self.max_iterations < 2:
            raise InvalidField("max_iterations", f"must be >= 2 (got {self.max_iterations})")

    def per_metre(self, stiffness: float, out_of_plane_length: float) -> float:
        """The target stiffness per metre of plane strain (N/m per m) of a K_x (N/m)."""
        return stiffness / out_of_plane_length if self.stiffness_basis == "block" \
            else stiffness


TimeCase = TimeSpec
"""``[time]``: the run layer's :class:`~breakwater.config.runspec.TimeSpec` itself (documented
and checked there)."""


def _one_location(obj: ProbeCase | PairProbeCase) -> None:
    if (obj.group is None) == (obj.point is None):
        raise InvalidField("group", "give either group (a point group) or point "
                           "(coordinates), exactly one")
    if obj.point is not None and len(obj.point) != 2:
        raise InvalidField("point", f"must have 2 coordinates (got {list(obj.point)})")


@dataclass(frozen=True)
class ProbeCase:
    """``[output.probes.<name>]``: displacement history of a point of a body."""

    name: str = setting(key=True, doc="probe name (output column prefix)")
    body: str = setting(doc="body the point belongs to")
    group: str | None = setting(None, doc="point (0D) physical group holding the point")
    point: tuple[float, ...] | None = setting(None, unit="m", doc="coordinates of the point "
                                              "(instead of group)")

    def __post_init__(self) -> None:
        _one_location(self)


@dataclass(frozen=True)
class PairProbeCase:
    """``[output.pair_probes.<name>]``: slip and opening of an interface point."""

    name: str = setting(key=True, doc="probe name (output column prefix)")
    pair: str = setting(doc="contact pair (its interface name; for a general pair the "
                        "point lies on its slave surface)")
    group: str | None = setting(None, doc="point (0D) physical group holding the point")
    point: tuple[float, ...] | None = setting(None, unit="m", doc="coordinates of the point "
                                              "(instead of group)")

    def __post_init__(self) -> None:
        _one_location(self)


@dataclass(frozen=True)
class OutputCase:
    """``[output]``: what to write and where."""

    directory: str = setting("", doc='output folder, relative to the working directory '
                             '("": results/<name>)')
    field_interval: int = setting(10, doc="write the fields every N steps (0: never)")
    figures: bool = setting(True, doc="draw the figures at the end of the run")
    checkpoint_interval: int = setting(0, doc="checkpoint every N steps for run --resume "
                                       "(0: never)")
    probes: tuple[ProbeCase, ...] = setting((), doc="point displacement probes")
    pair_probes: tuple[PairProbeCase, ...] = setting((), doc="interface slip/opening probes")

    def __post_init__(self) -> None:
        positive(self.field_interval, "field_interval", strict=False)
        positive(self.checkpoint_interval, "checkpoint_interval", strict=False)


_DEFAULT_MESH = MeshCase()
_NO_DAMPING = DampingCase()
_NO_CALIBRATION = CalibrationCase()
_DEFAULT_OUTPUT = OutputCase()
_DEFAULT_INITIAL = InitialCase()


@dataclass(frozen=True, kw_only=True)
class Case:
    """A whole case (see the module docstring and :func:`case_reference`)."""

    name: str = setting("case", doc="case name (default: the file name); default output "
                        "folder results/<name>, so a folder name of its own: not . or .., "
                        "no / \\ : or control characters, at most 255 bytes")
    description: str = setting("", doc="free text")
    out_of_plane_length: float = setting(1.0, unit="m", doc="length of the real structure "
                                         "out of plane: impulses, forces and target "
                                         "stiffnesses of the real structure are divided "
                                         "by it")
    gravity: tuple[float, ...] = setting((0.0, -9.81), unit="m/s²", doc="acceleration of "
                                         "gravity")
    mesh: MeshCase = setting(_DEFAULT_MESH, doc="the mesh")  # noqa: RUF009 (a field() with docs)
    bodies: tuple[BodyCase, ...] = setting((), doc="the bodies")
    contact: tuple[ContactCase, ...] = setting((), doc="contact pairs")
    fixed: tuple[FixedCase, ...] = setting((), doc="fixed boundaries")
    loads: tuple[LoadCase, ...] = setting((), doc="surface loads (see breakwater.casefile.loads)")
    initial: InitialCase = setting(_DEFAULT_INITIAL, doc="the initial state")  # noqa: RUF009 (a field() with docs)
    damping: DampingCase = setting(_NO_DAMPING, doc="Rayleigh damping")  # noqa: RUF009 (a field() with docs)
    calibration: CalibrationCase = setting(_NO_CALIBRATION, doc="stiffness calibration")  # noqa: RUF009 (a field() with docs)
    time: TimeCase = setting(doc="time integration")  # noqa: RUF009 (a field() with docs)
    output: OutputCase = setting(_DEFAULT_OUTPUT, doc="outputs")  # noqa: RUF009 (a field() with docs)

    def __post_init__(self) -> None:
        self._check()

    # --- validation ----------------------------------------------------------------

    def _check(self) -> None:
        problem = name_problem(self.name)
        if problem is not None:  # the name is the default output folder results/<name>
            raise InvalidField("name", problem)
        positive(self.out_of_plane_length, "out_of_plane_length")
        if len(self.gravity) != 2:
            raise InvalidField("gravity", f"must have 2 components (got {list(self.gravity)})")
        gx, gy = self.gravity
        if not math.isfinite(gx * gx + gy * gy):  # |g|² of the energy and the weights
            raise InvalidField("gravity", f"[{gx:g}, {gy:g}] m/s²: gx² + gy² overflows")
        for b in self.bodies:  # the body force ρ g of the run
            if not math.isfinite(b.density * max(abs(gx), abs(gy))):
                raise InvalidField(f"bodies.{b.name}.density", f"{b.density:g} kg/m³ times "
                                   f"gravity [{gx:g}, {gy:g}] m/s² overflows")
        if not self.bodies:
            raise InvalidField("bodies", "the case needs at least one body ([bodies.<name>])")
        names = [b.name for b in self.bodies]
        # The ParaView files fields_<body>.bp and contact_<pair>.bp are named after them.
        for where, file in [*((f"bodies.{b.name}", f"fields_{b.name}.bp") for b in self.bodies),
                            *((f"contact.{c.name}", f"contact_{c.name}.bp")
                              for c in self.contact)]:
            problem = name_problem(file)
            if problem is not None:
                raise InvalidField(where, f"the name cannot name the output file {file[:40]}"
                                   f"{'...' if len(file) > 40 else ''}: it {problem}")

        def body(value: str, where: str) -> None:
            if value not in names:
                raise InvalidField(where, f"no body named '{value}'{suggest(value, names)} "
                                   f"(bodies: {', '.join(names)})")

        for c in self.contact:
            body(c.slave, f"contact.{c.name}.slave")
            body(c.master, f"contact.{c.name}.master")
            if c.general and self.time.solver != "fast":
                raise InvalidField("time.solver", f"contact.{c.name} is a general pair "
                                   '(slave_surface/master_surface): it needs "fast"')
        cal = self.calibration
        if cal.enabled and any(c.general for c in self.contact):
            raise InvalidField("calibration.enabled", "the calibration bonds conforming "
                               "pairs only; a case with general pairs cannot calibrate")
        if cal.enabled:
            body(cal.body, "calibration.body")
            body(cal.structure, "calibration.structure")
            if cal.body == cal.structure:
                raise InvalidField("calibration.structure", "must differ from calibration.body")
            if cal.stiffness is None:
                raise InvalidField("calibration.stiffness", "missing (the target stiffness, N/m)")
        for b in self.bodies:
            calibrated = cal.enabled and b.name == cal.body
            if calibrated and b.has_modulus:
                raise InvalidField(f"bodies.{b.name}.shear_modulus",
                                   "the calibrated body must not give a modulus (remove it or "
                                   "set calibration.enabled = false)")
            if not calibrated and not b.has_modulus:
                raise InvalidField(f"bodies.{b.name}.shear_modulus",
                                   "missing: give shear_modulus or young_modulus (or calibrate "
                                   "it with [calibration])")
        for p in self.output.probes:
            body(p.body, f"output.probes.{p.name}.body")
        for ld in self.loads:
            if ld.body is not None:
                body(ld.body, f"loads.{ld.name}.body")
            if ld.kind == "pulse" and not math.isfinite(ld.total_impulse
                                                        / self.out_of_plane_length):
                raise InvalidField("out_of_plane_length", f"the impulse of loads.{ld.name} "
                                   f"per metre, {ld.total_impulse:g} N s / "
                                   f"{self.out_of_plane_length:g} m, overflows")
            ld.check_time(self.time.end_time, self.time.dt)
        loads = [ld.name for ld in self.loads]
        for name in self.initial.loads or ():
            if name not in loads:
                raise InvalidField("initial.loads", f"no load named '{name}'"
                                   f"{suggest(name, loads)} (loads: {', '.join(loads) or 'none'})")
        pairs = [c.name for c in self.contact]
        for q in self.output.pair_probes:
            if q.pair not in pairs:
                raise InvalidField(f"output.pair_probes.{q.name}.pair",
                                   f"no contact pair '{q.pair}'{suggest(q.pair, pairs)} "
                                   f"(pairs: {', '.join(pairs) or 'none'})")

    # --- derived values ------------------------------------------------------------

    @property
    def output_directory(self) -> pathlib.Path:
        """The output folder (``results/<name>`` unless set)."""
        return pathlib.Path(self.output.directory or f"results/{self.name}")

    def body(self, name: str) -> BodyCase:
        """The body of that name."""
        for b in self.bodies:
            if b.name == name:
                return b
        raise KeyError(name)

    def resolved(self) -> dict[str, Any]:
        """The fully resolved case as TOML-ready data (defaults filled).

        ``load_case`` of a file holding this gives back the same resolved data. The case
        a run used (:attr:`BuiltCase.case <breakwater.casefile.build.BuiltCase.case>`) has
        the calibrated modulus written into the body and ``calibration.enabled`` false:
        its resolved data reproduce the run without calibrating again.
        """
        data = to_toml(self)
        if not self.mesh.generated:
            del data["mesh"]["goda"]
            del data["mesh"]["refinement"]
            del data["mesh"]["max_elements"]
        data["output"]["directory"] = str(self.output_directory)
        return data

    def calibrated(self, body: str, shear_modulus: float) -> Case:
        """A new case: the body's shear modulus given (Pa), the calibration off."""
        bodies = tuple(replace(b, shear_modulus=shear_modulus) if b.name == body else b
                       for b in self.bodies)
        return replace(self, bodies=bodies,
                       calibration=replace(self.calibration, enabled=False))

    # --- building (see breakwater.casefile.build) -----------------------------------------

    def mesh_file(self, comm: MPI.Comm, directory: str | pathlib.Path | None = None
                  ) -> pathlib.Path:
        """The gmsh ``.msh`` file of the case (see :func:`.casebuild.mesh_file`)."""
        return casebuild.mesh_file(self, comm, directory)

    def read_mesh(self, comm: MPI.Comm, directory: str | pathlib.Path | None = None
                  ) -> gmshio.MeshData:
        """Generate (or find) and read the mesh (see :func:`.casebuild.read_mesh`)."""
        return casebuild.read_mesh(self, comm, directory)

    def build_model(self, data: gmshio.MeshData,
                    shear_moduli: Mapping[str, float] | None = None,
                    dynamic: bool = True) -> ContactModel:
        """The contact model of the case on a mesh (see :func:`.casebuild.build_model`)."""
        return casebuild.build_model(self, data, shear_moduli, dynamic)

    def calibrate(self, data: gmshio.MeshData, target: float | None = None
                  ) -> CalibrationResult:
        """Calibrate a shear modulus (see :func:`.casebuild.calibrate`)."""
        return casebuild.calibrate(self, data, target)

    def build(self, comm: MPI.Comm | None = None) -> casebuild.BuiltCase:
        """Mesh, calibrate and build the run's inputs (see :func:`.casebuild.build`).

        Returns:
            A :class:`~breakwater.casefile.build.BuiltCase`, which unpacks as
            ``model, time, output, extra``; its ``case`` is the case as run.

        """
        return casebuild.build(self, comm)


# --- reading files ------------------------------------------------------------------

def builtin_case(name: str) -> pathlib.Path:
    """The path of a built-in case (e.g. ``"goda"``)."""
    path = BUILTIN_CASES / f"{name}.toml"
    if not path.is_file():
        known = ", ".join(sorted(p.stem for p in BUILTIN_CASES.glob("*.toml")))
        raise CaseError(f"no built-in case '{name}' (built-in: {known})")
    return path


_SCHEMA = Schema(Case, builtin=builtin_case, paths={"mesh.source": (GODA,),
                                                   "loads.*.table.file": ()})
"""The TOML form of a case (``mesh.source`` is a path unless it is "goda"; so is a load
table's ``file``)."""


def is_file_value(key: str, value: Any) -> bool:
    """Whether ``value`` of the dotted case key ``key`` names a file.

    Such values (``mesh.source`` unless "goda", a load table's ``file``) are resolved
    against the file that gives them.
    """
    names = _SCHEMA._path_key(key)
    return names is not None and isinstance(value, str) and value not in names


# --- physical groups of the mesh ------------------------------------------------------

def _mesh_groups(mesh: MeshCase) -> dict[str, int]:
    """The named physical groups of the case's mesh (name -> dimension)."""
    if mesh.generated:
        return {name: dim for name, (dim, _) in mesh.goda.physical_groups.items()}
    problem = path_problem(mesh.source)  # a whole [mesh] table given by --set
    if problem is not None:
        raise InvalidField("mesh.source", problem)
    path = pathlib.Path(mesh.source)
    if not path.is_file():
        raise InvalidField("mesh.source", f"mesh file not found: {path}")
    if path.suffix not in (".msh", ".geo"):
        raise InvalidField("mesh.source", f"expected a gmsh .msh or .geo file: {path}")
    try:
        groups = physical_groups(path)
    except Exception as e:  # unreadable: any parse error (gmsh raises bare Exceptions)
        raise InvalidField("mesh.source", f"cannot read the mesh {path} ({e})") from None
    if not groups:
        raise InvalidField("mesh.source", f"the mesh {path} has no named physical groups")
    return groups


_DIM_NAMES = {0: "point", 1: "facet", 2: "cell"}


def _check_groups(case: Case, groups: Mapping[str, int]) -> None:
    """Every group the case names exists in the mesh with the right dimension."""
    where = "the goda mesh" if case.mesh.generated else case.mesh.source

    def need(name: str, dim: int, field_path: str) -> None:
        if groups.get(name) == dim:
            return
        have = sorted(n for n, d in groups.items() if d == dim)
        raise InvalidField(field_path, f"no {_DIM_NAMES[dim]} ({dim}D) physical group "
                           f"'{name}' in {where}{suggest(name, have)} (it has: "
                           f"{', '.join(have) or 'none'})")

    for b in case.bodies:
        need(b.name, 2, f"bodies.{b.name}")
    for c in case.contact:
        if c.general:
            need(c.slave_surface or "", 1, f"contact.{c.name}.slave_surface")
            if isinstance(c.master_surface, tuple):
                for k, group in enumerate(c.master_surface):
                    need(group, 1, f"contact.{c.name}.master_surface[{k}]")
            else:
                need(c.master_surface or "", 1, f"contact.{c.name}.master_surface")
        else:
            need(c.name, 1, f"contact.{c.name}")
    for f in case.fixed:
        need(f.name, 1, f"fixed.{f.name}")
    for ld in case.loads:
        need(ld.group, 1, f"loads.{ld.name}.group")
        for k, extra in enumerate(ld.groups):
            need(extra, 1, f"loads.{ld.name}.groups[{k}]")
        if ld.goda is not None and ld.goda.uplift_group is not None:
            need(ld.goda.uplift_group, 1, f"loads.{ld.name}.goda.uplift_group")
    for p in case.output.probes:
        if p.group is not None:
            need(p.group, 0, f"output.probes.{p.name}.group")
    for q in case.output.pair_probes:
        if q.group is not None:
            need(q.group, 0, f"output.pair_probes.{q.name}.group")


# --- the entry point --------------------------------------------------------------------

def load_case(path: str | pathlib.Path | None = None, overrides: Sequence[str] = ()) -> Case:
    """Read, override and validate a case.

    Args:
        path: A case file; a built-in case name (``"goda"``); None for the default
            (Goda) case.
        overrides: ``key=value`` strings (dotted paths, TOML values).

    Returns:
        The validated case.

    Raises:
        CaseError: One line naming the file (or ``--set``), the field and the problem.

    """
    case: Case = _SCHEMA.load(_case_file(path), overrides,
                              check=lambda c: _check_groups(c, _mesh_groups(c.mesh)))
    return case


def _case_file(path: str | pathlib.Path | None) -> pathlib.Path:
    """The file of a case argument: a file, a built-in name, or None (the default)."""
    if path is None:
        return builtin_case(DEFAULT_CASE)
    file = pathlib.Path(path)
    if not file.exists() and file.suffix == "" and "/" not in str(path):
        return builtin_case(str(path))
    if not file.is_file():
        raise CaseError(f"{path}: case file not found")
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
    inputs += [pathlib.Path(ld.table.file) for ld in case.loads
               if ld.table is not None and ld.table.file is not None]
    return inputs


def case_reference() -> str:
    """A Markdown table of every case key: type, unit, default, meaning."""
    return _SCHEMA.reference()
