"""Case files: a whole breakwater computation described in TOML, SI units.

A case file names the mesh (the built-in Goda generator or a gmsh file with named
physical groups), the bodies and their materials, the boundary conditions, the
contact pairs, the loads, damping, the optional stiffness calibration, the time
integration and the outputs. :func:`load_case` reads it into typed, validated, frozen
dataclasses (:class:`Case`); :meth:`Case.build` turns it into what the run layer
needs (a :class:`~breakwater.model.ContactModel`, a
:class:`~breakwater.runspec.TimeSpec` and an :class:`~breakwater.runspec.OutputSpec`).

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

import dataclasses
import difflib
import math
import pathlib
import tomllib
import types
import typing
from collections.abc import Mapping, Sequence
from dataclasses import MISSING, dataclass, field, fields
from typing import TYPE_CHECKING, Any, Literal

from .errors import BreakwaterError, MeshError
from .loads import STANDARD_GRAVITY, Pulse, PulseShape, impact_velocity, pendulum_impulse
from .meshes.goda import PHYSICAL_GROUPS, GodaGeometry
from .runspec import OutputSpec, PairProbeSpec, ProbeSpec, TimeSpec

if TYPE_CHECKING:
    from dolfinx.io import gmsh as gmshio
    from mpi4py import MPI

    from .calibrate import CalibrationResult
    from .model import ContactModel, Material

__all__ = [
    "BUILTIN_CASES",
    "BodyCase",
    "CalibrationCase",
    "Case",
    "CaseError",
    "ContactCase",
    "DampingCase",
    "FixedCase",
    "LoadCase",
    "MeshCase",
    "OutputCase",
    "PairProbeCase",
    "PendulumCase",
    "ProbeCase",
    "TimeCase",
    "builtin_case",
    "case_reference",
    "load_case",
]

BUILTIN_CASES = pathlib.Path(__file__).parent / "cases"
"""Folder of the built-in case files (package data)."""
DEFAULT_CASE = "goda"
GODA = "goda"
"""``mesh.source`` value selecting the built-in Goda mesh generator."""
_OVERRIDE = "--set"


class CaseError(BreakwaterError):
    """A case file (or an override) is invalid: one line, naming the field."""


class _Invalid(CaseError):
    """A field's value is invalid; ``field`` is relative to the object that raised."""

    def __init__(self, field_path: str, problem: str) -> None:
        super().__init__(f"{field_path}: {problem}" if field_path else problem)
        self.field = field_path
        self.problem = problem

    def within(self, prefix: str) -> _Invalid:
        """The same error with the field path prefixed."""
        path = ".".join(p for p in (prefix, self.field) if p)
        return _Invalid(path, self.problem)


def _f(default: Any = MISSING, *, unit: str = "-", doc: str = "", key: bool = False) -> Any:
    """A dataclass field documented with its unit (and marked as the key of a table)."""
    return field(default=default, metadata={"unit": unit, "doc": doc, "key": key})


def _positive(value: float, name: str, strict: bool = True) -> None:
    if not (value > 0 if strict else value >= 0):
        raise _Invalid(name, f"must be {'>' if strict else '>='} 0 (got {value:g})")


# --- the sections of a case -------------------------------------------------------

_GODA_GEOMETRY = GodaGeometry()


@dataclass(frozen=True)
class MeshCase:
    """``[mesh]``: where the mesh comes from."""

    source: str = _f(GODA, doc='"goda" (the built-in generator, [mesh.goda]) or a gmsh '
                     '.msh/.geo file with named physical groups, relative to the case file')
    refinement: float = _f(1.0, doc="goda only: element sizes are divided by this "
                           "(cell counts grow as refinement²)")
    degree: int = _f(2, doc="polynomial degree of the displacement (2: six-node "
                     "triangles, as the paper)")
    goda: GodaGeometry = _f(_GODA_GEOMETRY, unit="m",  # noqa: RUF009 (a field() with docs)
                            doc="goda only: dimensions of the model (see below)")

    def __post_init__(self) -> None:
        if not (self.refinement > 0 and math.isfinite(self.refinement)):
            raise _Invalid("refinement", f"must be > 0 (got {self.refinement:g})")
        if self.degree not in (1, 2):
            raise _Invalid("degree", f"must be 1 or 2 (got {self.degree})")
        if not self.source:
            raise _Invalid("source", 'must be "goda" or a mesh file')

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

    name: str = _f(key=True, doc="cell (2D) physical group of the body")
    density: float = _f(unit="kg/m³", doc="mass density ρ")
    poisson: float = _f(doc="Poisson's ratio ν, in (−1, 0.5)")
    shear_modulus: float | None = _f(None, unit="Pa", doc="shear modulus G")
    young_modulus: float | None = _f(None, unit="Pa", doc="Young's modulus E")

    def __post_init__(self) -> None:
        _positive(self.density, "density")
        if not -1.0 < self.poisson < 0.5:
            raise _Invalid("poisson", f"Poisson's ratio must be in (-1, 0.5) (got "
                           f"{self.poisson:g})")
        for name in ("shear_modulus", "young_modulus"):
            value = getattr(self, name)
            if value is not None:
                _positive(value, name)
        if self.shear_modulus is not None and self.young_modulus is not None:
            raise _Invalid("young_modulus", "give shear_modulus or young_modulus, not both")

    @property
    def has_modulus(self) -> bool:
        """True when the body gives its elastic modulus."""
        return self.shear_modulus is not None or self.young_modulus is not None

    def material(self, shear_modulus: float | None = None) -> Material:
        """The model material; ``shear_modulus`` replaces the case's (calibration)."""
        from .model import Material

        if shear_modulus is not None:
            return Material(self.density, self.poisson, shear_modulus=shear_modulus)
        if not self.has_modulus:
            raise _Invalid(f"bodies.{self.name}.shear_modulus", "missing")
        return Material(self.density, self.poisson, shear_modulus=self.shear_modulus,
                        young_modulus=self.young_modulus)


@dataclass(frozen=True)
class ContactCase:
    """``[contact.<interface>]``: penalty contact with regularised Coulomb friction."""

    name: str = _f(key=True, doc="interface facet (1D) physical group, shared by the "
                   "two bodies (conforming)")
    slave: str = _f(doc="body whose nodes are penalised (the paper: the caisson)")
    master: str = _f(doc="body whose outward normal defines the gap (the mound)")
    penalty: float = _f(unit="N/m³", doc="normal penalty ε_n")
    friction: float = _f(0.0, doc="Coulomb friction coefficient μ (0: frictionless)")
    regularisation: float = _f(1e-10, unit="m/s", doc="regularisation velocity χ of "
                               "the friction law (eq. 15)")
    gap: float = _f(0.0, unit="m", doc="initial normal gap g₀")

    def __post_init__(self) -> None:
        _positive(self.penalty, "penalty")
        _positive(self.friction, "friction", strict=False)
        _positive(self.regularisation, "regularisation")
        if self.slave == self.master:
            raise _Invalid("master", "slave and master must be different bodies")


@dataclass(frozen=True)
class FixedCase:
    """``[fixed.<group>]``: zero displacement on a facet group."""

    name: str = _f(key=True, doc="facet (1D) physical group")
    components: tuple[int, ...] = _f((0, 1), doc="fixed displacement components "
                                     "(0: x, 1: y)")

    def __post_init__(self) -> None:
        if not self.components:
            raise _Invalid("components", "fix at least one component")
        if any(c not in (0, 1) for c in self.components) or \
                len(set(self.components)) != len(self.components):
            raise _Invalid("components", f"must be distinct values among 0 (x) and 1 (y) "
                           f"(got {list(self.components)})")


@dataclass(frozen=True)
class PendulumCase:
    """``[loads.<name>.pendulum]``: the impulse of a pendulum, I = M ω (1 + e₀) (eq. 29)."""

    mass: float = _f(unit="kg", doc="pendulum mass M")
    cord_length: float = _f(unit="m", doc="cord length l₀")
    release_distance: float = _f(unit="m", doc="release distance s₀ from the struck face")
    restitution: float = _f(doc="coefficient of restitution e₀, in [0, 1]")
    gravity: float = _f(STANDARD_GRAVITY, unit="m/s²", doc="g in ω = s₀ sqrt(g/l₀)")

    def __post_init__(self) -> None:
        for name in ("mass", "cord_length", "release_distance", "gravity"):
            _positive(getattr(self, name), name)
        if not 0.0 <= self.restitution <= 1.0:
            raise _Invalid("restitution", f"must be in [0, 1] (got {self.restitution:g})")

    @property
    def velocity(self) -> float:
        """Impact velocity ω (m/s)."""
        return impact_velocity(self.cord_length, self.release_distance, self.gravity)

    @property
    def impulse(self) -> float:
        """Impulse I (N s)."""
        return pendulum_impulse(self.mass, self.cord_length, self.release_distance,
                                self.restitution, self.gravity)


@dataclass(frozen=True)
class LoadCase:
    """``[loads.<name>]``: an impulse applied as a traction pulse on a facet group.

    The traction is ``I / (out_of_plane_length · patch length) · shape(t)`` along
    ``direction``, with ∫ shape dt = 1, so the force per metre out of plane
    integrates to ``I / out_of_plane_length``. Give exactly one of ``impulse`` and
    ``[loads.<name>.pendulum]``.
    """

    name: str = _f(key=True, doc="name of the load")
    group: str = _f(doc="facet (1D) physical group loaded (the struck patch)")
    direction: tuple[float, ...] = _f((1.0, 0.0), doc="direction of the traction "
                                      "(normalised)")
    impulse: float | None = _f(None, unit="N s", doc="impulse I of the real (3D) "
                               "structure; divided by out_of_plane_length")
    pendulum: PendulumCase | None = _f(None, doc="the impulse from a pendulum (eq. 29)")  # noqa: RUF009 (a field() with docs)
    shape: PulseShape = _f("triangular", doc="force-time shape of the pulse")  # noqa: RUF009 (a field() with docs)
    duration: float = _f(2e-3, unit="s", doc="pulse duration")
    start: float = _f(0.0, unit="s", doc="time the pulse starts")
    peak: float = _f(0.5, doc="triangular: time of the peak as a fraction of the "
                     "duration, in [0, 1]")

    def __post_init__(self) -> None:
        if len(self.direction) != 2 or not any(self.direction):
            raise _Invalid("direction", f"must be a non-zero 2-vector (got "
                           f"{list(self.direction)})")
        norm = math.hypot(*self.direction)
        object.__setattr__(self, "direction", tuple(c / norm for c in self.direction))
        if (self.impulse is None) == (self.pendulum is None):
            raise _Invalid("impulse", "give either impulse or a [pendulum] table (exactly "
                           "one)")
        if self.impulse is not None:
            _positive(self.impulse, "impulse")
        _positive(self.duration, "duration")
        _positive(self.start, "start", strict=False)
        if not 0.0 <= self.peak <= 1.0:
            raise _Invalid("peak", f"must be in [0, 1] (got {self.peak:g})")

    @property
    def total_impulse(self) -> float:
        """The impulse I of the real structure (N s)."""
        if self.pendulum is not None:
            return self.pendulum.impulse
        assert self.impulse is not None
        return self.impulse

    def pulse(self, out_of_plane_length: float, patch_length: float) -> Pulse:
        """The traction amplitude (Pa) on a patch of the given length (m)."""
        per_area = self.total_impulse / (out_of_plane_length * patch_length)
        return Pulse(per_area, self.duration, self.shape, self.start, self.peak)


@dataclass(frozen=True)
class DampingCase:
    """``[damping]``: Rayleigh damping C = αM + βK of every body."""

    alpha: float = _f(0.0, unit="1/s", doc="mass-proportional coefficient α")
    beta: float = _f(0.0, unit="s", doc="stiffness-proportional coefficient β")

    def __post_init__(self) -> None:
        _positive(self.alpha, "alpha", strict=False)
        _positive(self.beta, "beta", strict=False)


@dataclass(frozen=True)
class CalibrationCase:
    """``[calibration]``: the shear modulus of ``body`` from a horizontal stiffness.

    See :mod:`breakwater.calibrate`: a uniform horizontal acceleration of
    ``structure`` on bonded interfaces; K = load / mean displacement.
    """

    enabled: bool = _f(False, doc="calibrate when building the model (the body then "
                       "gives no modulus)")
    body: str = _f("", doc="body whose shear modulus is calibrated (its ν is kept)")
    structure: str = _f("", doc="body whose horizontal stiffness is matched")
    stiffness: float | None = _f(None, unit="N/m", doc="target stiffness K_x of the "
                                 "real structure; divided by out_of_plane_length")
    tolerance: float = _f(1e-4, doc="relative tolerance on K_x")
    tangential_penalty: float = _f(1e3, doc="tangential stiffness of the bonded "
                                   "interface, as a multiple of ε_n")
    initial_guess: float = _f(1e7, unit="Pa", doc="first shear modulus tried")
    max_iterations: int = _f(30, doc="largest number of stiffness solves")

    def __post_init__(self) -> None:
        if self.stiffness is not None:
            _positive(self.stiffness, "stiffness")
        for name in ("tolerance", "tangential_penalty", "initial_guess"):
            _positive(getattr(self, name), name)
        if self.max_iterations < 2:
            raise _Invalid("max_iterations", f"must be >= 2 (got {self.max_iterations})")


@dataclass(frozen=True)
class TimeCase:
    """``[time]``: GN22 time integration and Newton settings."""

    dt: float = _f(unit="s", doc="time step Δt")
    end_time: float = _f(unit="s", doc="final time")
    beta1: float = _f(0.6, doc="GN22 β₁ (Newmark γ)")
    beta2: float = _f(0.605, doc="GN22 β₂ (2 × Newmark β)")
    allow_conditional: bool = _f(False, doc="accept β₁ < ½ or β₂ < β₁ (not "
                                 "unconditionally stable)")
    max_cutbacks: int = _f(4, doc="a failing step is retried with Δt/2, up to this many "
                           "times")
    newton_rtol: float = _f(1e-9, doc="Newton relative residual tolerance")
    newton_atol: float = _f(1e-9, doc="Newton absolute tolerance, as a fraction of the "
                            "load-vector norm")
    newton_max_it: int = _f(40, doc="Newton iterations per step")

    def __post_init__(self) -> None:
        _positive(self.dt, "dt")
        _positive(self.end_time, "end_time")
        if self.dt >= self.end_time:
            raise _Invalid("dt", f"must be smaller than end_time ({self.dt:g} >= "
                           f"{self.end_time:g})")
        _positive(self.beta1, "beta1")
        _positive(self.beta2, "beta2")
        if not self.allow_conditional:
            if self.beta1 < 0.5:
                raise _Invalid("beta1", f"beta1 = {self.beta1:g} < 0.5 is not "
                               "unconditionally stable (set time.allow_conditional = true "
                               "to insist)")
            if self.beta2 < self.beta1:
                raise _Invalid("beta2", f"beta2 = {self.beta2:g} < beta1 = {self.beta1:g} is "
                               "not unconditionally stable (set time.allow_conditional = "
                               "true to insist)")
        _positive(self.max_cutbacks, "max_cutbacks", strict=False)
        _positive(self.newton_rtol, "newton_rtol")
        _positive(self.newton_atol, "newton_atol")
        _positive(self.newton_max_it, "newton_max_it")

    def spec(self) -> TimeSpec:
        """The run layer's time settings."""
        return TimeSpec(**{f.name: getattr(self, f.name) for f in fields(self)})


def _one_location(obj: ProbeCase | PairProbeCase) -> None:
    if (obj.group is None) == (obj.point is None):
        raise _Invalid("group", "give either group (a point group) or point "
                       "(coordinates), exactly one")
    if obj.point is not None and len(obj.point) != 2:
        raise _Invalid("point", f"must have 2 coordinates (got {list(obj.point)})")


@dataclass(frozen=True)
class ProbeCase:
    """``[output.probes.<name>]``: displacement history of a point of a body."""

    name: str = _f(key=True, doc="probe name (output column prefix)")
    body: str = _f(doc="body the point belongs to")
    group: str | None = _f(None, doc="point (0D) physical group holding the point")
    point: tuple[float, ...] | None = _f(None, unit="m", doc="coordinates of the point "
                                         "(instead of group)")

    def __post_init__(self) -> None:
        _one_location(self)


@dataclass(frozen=True)
class PairProbeCase:
    """``[output.pair_probes.<name>]``: slip and opening of an interface point."""

    name: str = _f(key=True, doc="probe name (output column prefix)")
    pair: str = _f(doc="contact pair (its interface name)")
    group: str | None = _f(None, doc="point (0D) physical group holding the point")
    point: tuple[float, ...] | None = _f(None, unit="m", doc="coordinates of the point "
                                         "(instead of group)")

    def __post_init__(self) -> None:
        _one_location(self)


@dataclass(frozen=True)
class OutputCase:
    """``[output]``: what to write and where."""

    directory: str = _f("", doc='output folder, relative to the working directory '
                        '("": results/<name>)')
    field_interval: int = _f(10, doc="write the fields every N steps (0: never)")
    figures: bool = _f(True, doc="draw the figures at the end of the run")
    checkpoint_interval: int = _f(0, doc="checkpoint every N steps for run --resume (0: never)")
    probes: tuple[ProbeCase, ...] = _f((), doc="point displacement probes")
    pair_probes: tuple[PairProbeCase, ...] = _f((), doc="interface slip/opening probes")

    def __post_init__(self) -> None:
        _positive(self.field_interval, "field_interval", strict=False)
        _positive(self.checkpoint_interval, "checkpoint_interval", strict=False)


_DEFAULT_MESH = MeshCase()
_NO_DAMPING = DampingCase()
_NO_CALIBRATION = CalibrationCase()
_DEFAULT_OUTPUT = OutputCase()


@dataclass(frozen=True, kw_only=True)
class Case:
    """A whole case (see the module docstring and :func:`case_reference`)."""

    name: str = _f("case", doc="case name (default: the file name); default output "
                   "folder results/<name>")
    description: str = _f("", doc="free text")
    out_of_plane_length: float = _f(1.0, unit="m", doc="length of the real structure "
                                    "out of plane: impulses and target stiffnesses of "
                                    "the real structure are divided by it")
    gravity: tuple[float, ...] = _f((0.0, -9.81), unit="m/s²", doc="acceleration of "
                                    "gravity")
    mesh: MeshCase = _f(_DEFAULT_MESH, doc="the mesh")  # noqa: RUF009 (a field() with docs)
    bodies: tuple[BodyCase, ...] = _f((), doc="the bodies")
    contact: tuple[ContactCase, ...] = _f((), doc="contact pairs")
    fixed: tuple[FixedCase, ...] = _f((), doc="fixed boundaries")
    loads: tuple[LoadCase, ...] = _f((), doc="impulse loads")
    damping: DampingCase = _f(_NO_DAMPING, doc="Rayleigh damping")  # noqa: RUF009 (a field() with docs)
    calibration: CalibrationCase = _f(_NO_CALIBRATION, doc="stiffness calibration")  # noqa: RUF009 (a field() with docs)
    time: TimeCase = _f(doc="time integration")  # noqa: RUF009 (a field() with docs)
    output: OutputCase = _f(_DEFAULT_OUTPUT, doc="outputs")  # noqa: RUF009 (a field() with docs)

    def __post_init__(self) -> None:
        self._check()

    # --- validation ----------------------------------------------------------------

    def _check(self) -> None:
        if not self.name or any(c in self.name for c in '/\\:'):
            raise _Invalid("name", f"must be a non-empty name without path separators "
                           f"(got {self.name!r})")
        _positive(self.out_of_plane_length, "out_of_plane_length")
        if len(self.gravity) != 2:
            raise _Invalid("gravity", f"must have 2 components (got {list(self.gravity)})")
        if not self.bodies:
            raise _Invalid("bodies", "the case needs at least one body ([bodies.<name>])")
        names = [b.name for b in self.bodies]

        def body(value: str, where: str) -> None:
            if value not in names:
                raise _Invalid(where, f"no body named '{value}'{_suggest(value, names)} "
                               f"(bodies: {', '.join(names)})")

        for c in self.contact:
            body(c.slave, f"contact.{c.name}.slave")
            body(c.master, f"contact.{c.name}.master")
        cal = self.calibration
        if cal.enabled:
            body(cal.body, "calibration.body")
            body(cal.structure, "calibration.structure")
            if cal.body == cal.structure:
                raise _Invalid("calibration.structure", "must differ from calibration.body")
            if cal.stiffness is None:
                raise _Invalid("calibration.stiffness", "missing (the target stiffness, N/m)")
        for b in self.bodies:
            calibrated = cal.enabled and b.name == cal.body
            if calibrated and b.has_modulus:
                raise _Invalid(f"bodies.{b.name}.shear_modulus",
                               "the calibrated body must not give a modulus (remove it or "
                               "set calibration.enabled = false)")
            if not calibrated and not b.has_modulus:
                raise _Invalid(f"bodies.{b.name}.shear_modulus",
                               "missing: give shear_modulus or young_modulus (or calibrate "
                               "it with [calibration])")
        for p in self.output.probes:
            body(p.body, f"output.probes.{p.name}.body")
        pairs = [c.name for c in self.contact]
        for q in self.output.pair_probes:
            if q.pair not in pairs:
                raise _Invalid(f"output.pair_probes.{q.name}.pair",
                               f"no contact pair '{q.pair}'{_suggest(q.pair, pairs)} "
                               f"(pairs: {', '.join(pairs) or 'none'})")

    # --- derived values ------------------------------------------------------------

    @property
    def output_directory(self) -> pathlib.Path:
        """The output folder (``results/<name>`` unless set)."""
        return pathlib.Path(self.output.directory or f"results/{self.name}")

    @property
    def calibration_target(self) -> float | None:
        """Target stiffness per metre out of plane (N/m per m), if any."""
        k = self.calibration.stiffness
        return None if k is None else k / self.out_of_plane_length

    def body(self, name: str) -> BodyCase:
        """The body of that name."""
        for b in self.bodies:
            if b.name == name:
                return b
        raise KeyError(name)

    def resolved(self) -> dict[str, Any]:
        """The fully resolved case as TOML-ready data (defaults filled).

        After :meth:`build` has calibrated a modulus, the calibrated value is written
        into the body and ``calibration.enabled`` is false: the result reproduces the
        run without calibrating again. ``load_case`` of a file holding this gives back
        the same resolved data.
        """
        data = _unbuild(self)
        if not self.mesh.generated:
            del data["mesh"]["goda"]
            del data["mesh"]["refinement"]
        data["output"]["directory"] = str(self.output_directory)
        result: CalibrationResult | None = getattr(self, "_calibration", None)
        if result is not None:
            data["bodies"][result.body]["shear_modulus"] = result.shear_modulus
            data["calibration"]["enabled"] = False
        return data

    # --- building ------------------------------------------------------------------

    def mesh_file(self, comm: MPI.Comm, directory: str | pathlib.Path | None = None
                  ) -> pathlib.Path:
        """The gmsh file of the case (generated for the built-in generator).

        The Goda mesh is written to ``<directory>/mesh/goda.msh`` (default: the output
        folder); a user mesh is the case's file.
        """
        if not self.mesh.generated:
            return pathlib.Path(self.mesh.source)
        from . import meshes  # type: ignore[attr-defined]  # breakwater.meshes maps to meshes/

        folder = pathlib.Path(directory) if directory is not None else self.output_directory
        return meshes.generate(folder / "mesh" / "goda.msh", self.mesh.goda,
                               refinement=self.mesh.refinement, comm=comm)

    def read_mesh(self, comm: MPI.Comm, directory: str | pathlib.Path | None = None
                  ) -> gmshio.MeshData:
        """Generate (or find) and read the mesh, distributed over ``comm``."""
        from .mesh import read_mesh

        path = self.mesh_file(comm, directory)
        try:
            return read_mesh(path, comm)
        except MeshError as e:
            raise CaseError(f"mesh.source: {e}") from e

    def build_model(self, data: gmshio.MeshData,
                    shear_moduli: Mapping[str, float] | None = None,
                    dynamic: bool = True) -> ContactModel:
        """The contact model of the case on a mesh.

        Args:
            data: The mesh (see :meth:`read_mesh`).
            shear_moduli: Shear moduli (Pa) replacing the case's, by body name (the
                calibrated body gives none: it must be here).
            dynamic: Include the loads, gravity and damping (False: the bare elastic
                bodies, contact pairs and fixed boundaries, for the calibration).

        """
        from .model import Body, ContactModel, ContactPair, Damping, Fixed, SurfaceLoad

        moduli = shear_moduli or {}
        bodies = [Body(b.name, b.material(moduli.get(b.name))) for b in self.bodies]
        pairs = [ContactPair(c.name, c.slave, c.master, c.penalty, c.friction,
                             c.regularisation, c.gap) for c in self.contact]
        fixed = [Fixed(f.name, tuple(f.components)) for f in self.fixed]
        loads = []
        if dynamic:
            for ld in self.loads:
                pulse = ld.pulse(self.out_of_plane_length, _group_length(data, ld.group))
                loads.append(SurfaceLoad(ld.group, ld.direction, pulse))
        return ContactModel(data, bodies, pairs, fixed, loads,
                            gravity=self.gravity if dynamic else None,
                            damping=Damping(self.damping.alpha, self.damping.beta)
                            if dynamic else None,
                            degree=self.mesh.degree)

    def calibrate(self, data: gmshio.MeshData, target: float | None = None
                  ) -> CalibrationResult:
        """Calibrate the shear modulus of ``calibration.body`` (see :mod:`.calibrate`).

        Args:
            data: The mesh.
            target: Target stiffness of the real structure (N/m), divided by
                ``out_of_plane_length``; ``calibration.stiffness`` if None.

        """
        from .calibrate import calibrate_shear_modulus

        cal = self.calibration
        names = [b.name for b in self.bodies]
        for key in ("body", "structure"):
            if getattr(cal, key) not in names:
                raise CaseError(f"calibration.{key}: no body named '{getattr(cal, key)}' "
                                f"(bodies: {', '.join(names)})")
        k = cal.stiffness if target is None else target
        if k is None:
            raise CaseError("calibration.stiffness: missing (the target stiffness, N/m)")
        if not k > 0:
            raise CaseError(f"calibration target stiffness must be > 0 (got {k:g})")
        model = self.build_model(data, {cal.body: cal.initial_guess}, dynamic=False)
        return calibrate_shear_modulus(model, cal.body, cal.structure,
                                       k / self.out_of_plane_length, cal.tolerance,
                                       cal.initial_guess, cal.tangential_penalty,
                                       cal.max_iterations)

    def build(self, comm: MPI.Comm | None = None
              ) -> tuple[ContactModel, TimeSpec, OutputSpec, dict[str, Any]]:
        """Mesh, calibrate (if asked) and build what the run layer needs (collective).

        The Goda mesh is generated into ``<output directory>/mesh/goda.msh``.

        Returns:
            ``(model, time, output, extra_summary)``; ``extra_summary`` holds the mesh,
            the loads and the calibration (if any) for the run's summary.

        Raises:
            CaseError: The mesh does not fit the case.
            CalibrationError: The calibration failed.

        """
        from mpi4py import MPI

        from .mesh import group_points

        comm = MPI.COMM_WORLD if comm is None else comm
        data = self.read_mesh(comm)
        extra: dict[str, Any] = {"mesh": _mesh_summary(self, data)}
        moduli: dict[str, float] = {}
        if self.calibration.enabled:
            result = self.calibrate(data)
            object.__setattr__(self, "_calibration", result)
            moduli[result.body] = result.shear_modulus
            extra["calibration"] = result.summary()
        try:
            model = self.build_model(data, moduli, dynamic=True)
        except MeshError as e:
            raise CaseError(f"{self._source_label()}: {e}") from e
        extra["loads"] = {ld.name: _load_summary(self, ld, data) for ld in self.loads}

        def where(name: str, group: str | None, point: tuple[float, ...] | None
                  ) -> tuple[float, ...]:
            if point is not None:
                return tuple(point)
            assert group is not None
            try:
                x = group_points(data, group)
            except MeshError as e:
                raise CaseError(f"{name}: {e}") from e
            if len(x) != 1:
                raise CaseError(f"{name}: point group '{group}' holds {len(x)} points, "
                                "expected one")
            return tuple(float(c) for c in x[0, :model.gdim])

        pair_index = {c.name: k for k, c in enumerate(self.contact)}
        o = self.output
        probes = tuple(ProbeSpec(p.name, p.body,
                                 where(f"output.probes.{p.name}", p.group, p.point))
                       for p in o.probes)
        pair_probes = tuple(PairProbeSpec(q.name, pair_index[q.pair],
                                          where(f"output.pair_probes.{q.name}", q.group,
                                                q.point))
                            for q in o.pair_probes)
        output = OutputSpec(directory=self.output_directory, field_interval=o.field_interval,
                            probes=probes, pair_probes=pair_probes, figures=o.figures,
                            case_name=self.name, checkpoint_interval=o.checkpoint_interval)
        return model, self.time.spec(), output, extra

    def _source_label(self) -> str:
        return "mesh" if self.mesh.generated else self.mesh.source


def _group_length(data: gmshio.MeshData, group: str) -> float:
    """Length (m) of a facet group, summed over the ranks."""
    import dolfinx
    import ufl
    from dolfinx import fem
    from mpi4py import MPI

    from .mesh import group_tag

    msh = data.mesh
    tag = group_tag(data, group, msh.topology.dim - 1)
    ds = ufl.Measure("ds", domain=msh, subdomain_data=data.facet_tags)(tag)
    one = fem.Constant(msh, dolfinx.default_scalar_type(1.0))
    length = msh.comm.allreduce(fem.assemble_scalar(fem.form(one * ds)), op=MPI.SUM)
    if not length > 0:
        raise CaseError(f"facet group '{group}' has zero length on the boundary")
    return float(length)


def _load_summary(case: Case, load: LoadCase, data: gmshio.MeshData) -> dict[str, Any]:
    h = _group_length(data, load.group)
    pulse = load.pulse(case.out_of_plane_length, h)
    info: dict[str, Any] = {
        "group": load.group,
        "impulse": load.total_impulse,
        "impulse_per_length": load.total_impulse / case.out_of_plane_length,
        "patch_length": h,
        "shape": load.shape,
        "duration": load.duration,
        "start": load.start,
        "peak_traction": pulse.maximum,
        "peak_force_per_length": pulse.maximum * h,
    }
    if load.pendulum is not None:
        info["impact_velocity"] = load.pendulum.velocity
    return info


def _mesh_summary(case: Case, data: gmshio.MeshData) -> dict[str, Any]:
    from .mesh import group_tag

    msh = data.mesh
    tdim = msh.topology.dim
    nlocal = msh.topology.index_map(tdim).size_local
    cells = {}
    assert data.cell_tags is not None
    for b in case.bodies:
        found = data.cell_tags.find(group_tag(data, b.name, tdim))
        cells[b.name] = int(msh.comm.allreduce(int((found < nlocal).sum())))
    info: dict[str, Any] = {"source": case.mesh.source, "degree": case.mesh.degree,
                            "cells": cells}
    if case.mesh.generated:
        info["refinement"] = case.mesh.refinement
    return info


# --- generic conversion between TOML data and the dataclasses -----------------------

def _suggest(word: str, choices: Sequence[str]) -> str:
    """`` (did you mean 'x'?)`` with the closest choice, or nothing without choices."""
    if not choices:
        return ""
    best = difflib.get_close_matches(word, choices, n=1, cutoff=0.0)
    return f" (did you mean '{best[0]}'?)" if best else ""


def _suggest_key(word: str, valid: Sequence[str]) -> str:
    """The closest key of the table, unless the key belongs to (or is near) another one."""
    elsewhere = {k.rsplit(".", 1)[-1]: k for k in reversed(_schema_keys(Case))}
    if word in elsewhere:
        return f" (did you mean '{elsewhere[word]}'?)"
    if difflib.get_close_matches(word, valid, n=1, cutoff=0.6):
        return _suggest(word, valid)
    near = difflib.get_close_matches(word, list(elsewhere), n=1, cutoff=0.8)
    if near:
        return f" (did you mean '{elsewhere[near[0]]}'?)"
    return _suggest(word, valid)


def _schema_keys(cls: type, prefix: str = "") -> list[str]:
    """Every dotted key of the schema (``<name>`` for the entries of named tables)."""
    keys = []
    hints = _hints(cls)
    for f in fields(cls):
        if f.metadata.get("key"):
            continue
        key = f"{prefix}.{f.name}" if prefix else f.name
        keys.append(key)
        item = _keyed_item(hints[f.name])
        nested = _optional(hints[f.name]) or hints[f.name]
        if item is not None:
            keys += _schema_keys(item, f"{key}.<name>")
        elif dataclasses.is_dataclass(nested):
            keys += _schema_keys(nested, key)  # type: ignore[arg-type]
    return keys


def _hints(cls: Any) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _key_field(cls: Any) -> str | None:
    for f in fields(cls):
        if f.metadata.get("key"):
            return f.name
    return None


def _keyed_item(tp: Any) -> type | None:
    """The item class of a ``tuple[Item, ...]`` keyed collection, else None."""
    if typing.get_origin(tp) is tuple:
        args = typing.get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis and dataclasses.is_dataclass(args[0]) \
                and _key_field(args[0]) is not None:
            return args[0]  # type: ignore[return-value]
    return None


def _optional(tp: Any) -> Any:
    """``X`` for ``X | None``, else None."""
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if len(args) == 1:
            return args[0]
    return None


def _type_name(tp: Any) -> str:
    inner = _optional(tp)
    if inner is not None:
        return _type_name(inner)
    if tp is float:
        return "number"
    if tp is int:
        return "integer"
    if tp is bool:
        return "boolean"
    if tp is str:
        return "string"
    if typing.get_origin(tp) is Literal:
        return " | ".join(f'"{a}"' for a in typing.get_args(tp))
    if typing.get_origin(tp) is tuple:
        return f"array of {_type_name(typing.get_args(tp)[0])}"
    if dataclasses.is_dataclass(tp):
        return "table"
    return str(tp)


def _describe(value: Any) -> str:
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        return "an array"
    return repr(value)


def _convert(tp: Any, value: Any, path: str) -> Any:
    """Check and convert one TOML value to the annotated type."""
    inner = _optional(tp)
    if inner is not None:
        return _convert(inner, value, path)
    want = _type_name(tp)
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise _Invalid(path, f"expected a number, got {_describe(value)}")
        if not math.isfinite(value):
            raise _Invalid(path, f"must be finite (got {value})")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise _Invalid(path, f"expected an integer, got {_describe(value)}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise _Invalid(path, f"expected true or false, got {_describe(value)}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise _Invalid(path, f"expected a string, got {_describe(value)}")
        return value
    if typing.get_origin(tp) is Literal:
        choices = [str(a) for a in typing.get_args(tp)]
        if value not in choices:
            hint = _suggest(value, choices) if isinstance(value, str) else ""
            raise _Invalid(path, f"must be one of {want}, got {_describe(value)}{hint}")
        return value
    item = _keyed_item(tp)
    if item is not None:
        if not isinstance(value, dict):
            raise _Invalid(path, f"expected a table of named tables, got {_describe(value)}")
        return tuple(_build(item, v, f"{path}.{k}", key=k) for k, v in value.items())
    if typing.get_origin(tp) is tuple:
        if not isinstance(value, list):
            raise _Invalid(path, f"expected an array ({want}), got {_describe(value)}")
        elem = typing.get_args(tp)[0]
        return tuple(_convert(elem, v, f"{path}[{i}]") for i, v in enumerate(value))
    if dataclasses.is_dataclass(tp):
        return _build(tp, value, path)  # type: ignore[arg-type]
    raise TypeError(f"unsupported field type {tp!r}")  # pragma: no cover


def _build(cls: type, table: Any, path: str, key: str | None = None) -> Any:
    """Build a dataclass from a TOML table, rejecting unknown keys."""
    if not isinstance(table, dict):
        raise _Invalid(path, f"expected a table, got {_describe(table)}")
    key_name = _key_field(cls)
    valid = [f.name for f in fields(cls) if f.init and f.name != key_name]
    for k in table:
        if k not in valid:
            raise _Invalid(f"{path}.{k}" if path else k,
                           f"unknown key{_suggest_key(k, valid)} (valid keys: "
                           f"{', '.join(valid)})")
    hints = _hints(cls)
    kwargs: dict[str, Any] = {}
    for f in fields(cls):
        where = f"{path}.{f.name}" if path else f.name
        if f.name == key_name:
            kwargs[f.name] = key
        elif f.name in table:
            kwargs[f.name] = _convert(hints[f.name], table[f.name], where)
        elif f.default is MISSING and f.default_factory is MISSING:
            raise _Invalid(where, "missing required key")
    try:
        return cls(**kwargs)
    except _Invalid as e:
        raise e.within(path) from None
    except ValueError as e:  # e.g. GodaGeometry's own checks
        raise _Invalid(path, str(e)) from None


def _unbuild(obj: Any) -> Any:
    """TOML-ready data of a dataclass (None fields left out)."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        key_name = _key_field(type(obj))
        out: dict[str, Any] = {}
        for f in fields(obj):
            value = getattr(obj, f.name)
            if f.name == key_name or value is None:
                continue
            if _keyed_item(_hints(type(obj))[f.name]) is not None:
                out[f.name] = {item.name: _unbuild(item) for item in value}
            else:
                out[f.name] = _unbuild(value)
        return out
    if isinstance(obj, tuple):
        return [_unbuild(v) for v in obj]
    return obj


# --- reading files ------------------------------------------------------------------

def builtin_case(name: str) -> pathlib.Path:
    """The path of a built-in case (e.g. ``"goda"``)."""
    path = BUILTIN_CASES / f"{name}.toml"
    if not path.is_file():
        known = ", ".join(sorted(p.stem for p in BUILTIN_CASES.glob("*.toml")))
        raise CaseError(f"no built-in case '{name}' (built-in: {known})")
    return path


def _display(path: pathlib.Path) -> str:
    try:
        return str(path.resolve().relative_to(pathlib.Path.cwd()))
    except ValueError:
        return str(path)


def _read_toml(path: pathlib.Path) -> dict[str, Any]:
    try:
        with path.open("rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as e:
        raise CaseError(f"{_display(path)}: invalid TOML: {e}") from None
    except OSError as e:
        raise CaseError(f"{_display(path)}: cannot read the case file "
                        f"({e.strerror or e})") from None


def _record(data: Any, label: str, prefix: str, origins: dict[str, str]) -> None:
    """Note the file every key (and table) comes from."""
    if isinstance(data, dict):
        for k, v in data.items():
            p = f"{prefix}.{k}" if prefix else k
            origins[p] = label
            _record(v, label, p, origins)


def _merge(base: dict[str, Any], top: Mapping[str, Any]) -> dict[str, Any]:
    """``top`` merged over ``base``, table by table."""
    out = dict(base)
    for k, v in top.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = _merge(out[k], v)
        else:
            out[k] = v
    return out


def _load_raw(path: pathlib.Path, chain: tuple[pathlib.Path, ...],
              origins: dict[str, str]) -> dict[str, Any]:
    label = _display(path)
    raw = _read_toml(path)
    mesh = raw.get("mesh")
    if isinstance(mesh, dict) and isinstance(mesh.get("source"), str) \
            and mesh["source"] != GODA:
        mesh["source"] = str((path.parent / mesh["source"]).resolve())
    if "name" not in raw and not chain:
        raw["name"] = path.stem
    base = raw.pop("extends", None)
    if base is None:
        _record(raw, label, "", origins)
        return raw
    if not isinstance(base, str):
        raise CaseError(f"{label}: extends: expected a case name or file, got "
                        f"{_describe(base)}")
    candidate = path.parent / base
    if candidate.is_file():
        base_path = candidate.resolve()
    elif "/" not in base and not base.endswith(".toml"):
        try:
            base_path = builtin_case(base)
        except CaseError as e:
            raise CaseError(f"{label}: extends: {e}") from None
    else:
        raise CaseError(f"{label}: extends: case file not found: {base}")
    if base_path in chain or base_path == path.resolve():
        raise CaseError(f"{label}: extends: circular ({base})")
    merged = _merge(_load_raw(base_path, (*chain, path.resolve()), origins), raw)
    _record(raw, label, "", origins)
    return merged


def _parse_value(text: str) -> Any:
    """A TOML value, or the bare text as a string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text.strip()


def _apply_override(raw: dict[str, Any], spec: str, origins: dict[str, str]) -> None:
    """Apply one ``key=value`` override to the raw data, checking the key path."""
    if "=" not in spec:
        raise CaseError(f"{_OVERRIDE} {spec}: expected key=value")
    key, text = (s.strip() for s in spec.split("=", 1))
    parts = key.split(".")
    if not key or not all(parts):
        raise CaseError(f"{_OVERRIDE} {spec}: empty key")
    value = _parse_value(text)
    cls: Any = Case
    node = raw
    done: list[str] = []
    i = 0
    while i < len(parts):
        part = parts[i]
        here = ".".join([*done, part])
        if not (dataclasses.is_dataclass(cls)):
            raise CaseError(f"{_OVERRIDE} {key}: '{'.'.join(done)}' is not a table")
        key_name = _key_field(cls)
        valid = [f.name for f in fields(cls) if f.init and f.name != key_name]
        if part not in valid:
            raise CaseError(f"{_OVERRIDE} {key}: unknown key '{here}'{_suggest_key(part, valid)} "
                            f"(valid keys: {', '.join(valid)})")
        tp = _hints(cls)[part]
        item = _keyed_item(tp)
        last = i == len(parts) - 1
        if item is not None and not last:
            table = node.setdefault(part, {})
            if not isinstance(table, dict):
                raise CaseError(f"{_OVERRIDE} {key}: '{here}' is not a table")
            names = list(table)
            entry = parts[i + 1]
            if entry not in table and entry.isdigit() and int(entry) < len(names):
                entry = names[int(entry)]
            whole = i + 1 == len(parts) - 1  # the whole entry is set (or created)
            if entry not in table and not (whole and isinstance(value, dict)):
                raise CaseError(f"{_OVERRIDE} {key}: no entry '{parts[i + 1]}' in "
                                f"{here}{_suggest(parts[i + 1], names)} "
                                f"(entries: {', '.join(names) or 'none'})")
            done += [part, entry]
            if whole:
                node, part, here = table, entry, ".".join(done)
                break
            node, cls = table[entry], item
            i += 2
            continue
        target = _optional(tp) or tp
        if not last:
            if not dataclasses.is_dataclass(target):
                raise CaseError(f"{_OVERRIDE} {key}: '{here}' is not a table")
            sub = node.setdefault(part, {})
            if not isinstance(sub, dict):
                raise CaseError(f"{_OVERRIDE} {key}: '{here}' is not a table")
            done.append(part)
            node, cls = sub, target
            i += 1
            continue
        break
    if here == "mesh.source" and isinstance(value, str) and value != GODA:
        value = str(pathlib.Path(value).resolve())
    node[part] = value
    for p in [p for p in origins if p == here or p.startswith(here + ".")]:
        del origins[p]
    origins[here] = _OVERRIDE
    _record(value, _OVERRIDE, here, origins)


def _origin(path: str, origins: Mapping[str, str], default: str) -> str:
    parts = path.replace("[", ".[").split(".")
    for n in range(len(parts), 0, -1):
        p = ".".join(parts[:n]).replace(".[", "[")
        if p in origins:
            return origins[p]
    return default


# --- physical groups of the mesh ------------------------------------------------------

def _msh_groups(path: pathlib.Path) -> dict[str, int]:
    """Physical group names -> dimension, from the header of a gmsh ``.msh`` file."""
    groups: dict[str, int] = {}
    with path.open("rb") as fh:
        if fh.readline().strip() != b"$MeshFormat":
            raise ValueError("not a gmsh .msh file (no $MeshFormat header)")
        for line in fh:
            s = line.strip()
            if s == b"$PhysicalNames":
                for _ in range(int(fh.readline())):
                    dim, _tag, name = fh.readline().decode().split(maxsplit=2)
                    groups[name.strip().strip('"')] = int(dim)
                break
            if s in (b"$Entities", b"$Nodes", b"$Elements", b"$PartitionedEntities"):
                break
    return groups


def _geo_groups(path: pathlib.Path) -> dict[str, int]:
    """Physical group names -> dimension of a gmsh ``.geo`` script (not meshed)."""
    import gmsh

    owner = not gmsh.isInitialized()
    if owner:
        gmsh.initialize(readConfigFiles=False, interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.open(str(path))
        return {gmsh.model.getPhysicalName(d, t): d for d, t in gmsh.model.getPhysicalGroups()
                if gmsh.model.getPhysicalName(d, t)}
    finally:
        if owner:
            gmsh.finalize()
        else:
            gmsh.model.remove()


def _mesh_groups(mesh: MeshCase) -> dict[str, int]:
    """The named physical groups of the case's mesh (name -> dimension)."""
    if mesh.generated:
        return {name: dim for name, (dim, _) in PHYSICAL_GROUPS.items()}
    path = pathlib.Path(mesh.source)
    if not path.is_file():
        raise _Invalid("mesh.source", f"mesh file not found: {path}")
    if path.suffix not in (".msh", ".geo"):
        raise _Invalid("mesh.source", f"expected a gmsh .msh or .geo file: {path}")
    try:
        groups = _msh_groups(path) if path.suffix == ".msh" else _geo_groups(path)
    except Exception as e:  # unreadable: any parse error (gmsh raises bare Exceptions)
        raise _Invalid("mesh.source", f"cannot read the mesh {path} ({e})") from None
    if not groups:
        raise _Invalid("mesh.source", f"the mesh {path} has no named physical groups")
    return groups


_DIM_NAMES = {0: "point", 1: "facet", 2: "cell"}


def _check_groups(case: Case, groups: Mapping[str, int]) -> None:
    """Every group the case names exists in the mesh with the right dimension."""
    where = "the goda mesh" if case.mesh.generated else case.mesh.source

    def need(name: str, dim: int, field_path: str) -> None:
        if groups.get(name) == dim:
            return
        have = sorted(n for n, d in groups.items() if d == dim)
        raise _Invalid(field_path, f"no {_DIM_NAMES[dim]} ({dim}D) physical group "
                       f"'{name}' in {where}{_suggest(name, have)} (it has: "
                       f"{', '.join(have) or 'none'})")

    for b in case.bodies:
        need(b.name, 2, f"bodies.{b.name}")
    for c in case.contact:
        need(c.name, 1, f"contact.{c.name}")
    for f in case.fixed:
        need(f.name, 1, f"fixed.{f.name}")
    for ld in case.loads:
        need(ld.group, 1, f"loads.{ld.name}.group")
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
    if path is None:
        file = builtin_case(DEFAULT_CASE)
    else:
        file = pathlib.Path(path)
        if not file.exists() and file.suffix == "" and "/" not in str(path):
            file = builtin_case(str(path))
        elif not file.is_file():
            raise CaseError(f"{path}: case file not found")
    origins: dict[str, str] = {}
    raw = _load_raw(file, (), origins)
    for spec in overrides:
        _apply_override(raw, spec, origins)
    label = _display(file)
    try:
        case = _build(Case, raw, "")
        _check_groups(case, _mesh_groups(case.mesh))
    except _Invalid as e:
        origin = _origin(e.field, origins, label)
        if origin not in (label, _OVERRIDE):  # a key of a case this one extends
            origin = f"{label} (extends {origin})"
        raise CaseError(f"{origin}: {e}") from None
    return case


def case_reference() -> str:
    """A Markdown table of every case key: type, unit, default, meaning."""
    rows = ["| key | type | unit | default | meaning |", "|---|---|---|---|---|"]

    def default_text(f: dataclasses.Field[Any]) -> str:
        if f.metadata.get("key"):
            return "(table name)"
        if f.default is MISSING:
            return "required"
        if f.default is None:
            return "—"
        if dataclasses.is_dataclass(f.default) or f.default == ():
            return ""
        return f"`{_toml_value(_unbuild(f.default))}`"

    def walk(cls: Any, prefix: str, goda: bool = False) -> None:
        hints = _hints(cls)
        docs = _attribute_docs(cls) if goda else {}
        for f in fields(cls):
            tp = hints[f.name]
            key = f"{prefix}.{f.name}" if prefix else f.name
            if f.metadata.get("key"):
                continue
            item = _keyed_item(tp)
            nested = _optional(tp) or tp
            unit = f.metadata.get("unit", "m" if goda and f.name != "slope" else "-")
            doc = f.metadata.get("doc", docs.get(f.name, ""))
            if item is not None:
                key_doc = next(g.metadata["doc"] for g in fields(item) if g.metadata["key"])
                rows.append(f"| `[{key}.<name>]` | table | | | {doc}; `<name>`: {key_doc} |")
                walk(item, f"{key}.<name>")
            elif dataclasses.is_dataclass(nested):
                rows.append(f"| `[{key}]` | table | | | {doc} |")
                walk(nested, key, goda=nested is GodaGeometry)
            else:
                kind = _type_name(tp).replace("|", "\\|")
                rows.append(f"| `{key}` | {kind} | {unit} | {default_text(f)} | {doc} |")

    rows.append('| `extends` | string | - | — | start from another case: a built-in name '
                '("goda") or a file (relative to this one); this file is merged over it, '
                'table by table |')
    walk(Case, "")
    return "\n".join(rows)


def _toml_value(value: Any) -> str:
    """A short TOML rendering of a default value."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return repr(value)


def _attribute_docs(cls: type) -> dict[str, str]:
    """``Attributes:`` entries of a Google-style class docstring."""
    docs: dict[str, str] = {}
    lines = (cls.__doc__ or "").splitlines()
    current = None
    inside = False
    for line in lines:
        s = line.strip()
        if s == "Attributes:":
            inside = True
            continue
        if not inside:
            continue
        if not s:
            if docs:
                break
            continue
        if ":" in s and s.split(":", 1)[0].isidentifier():
            current, text = s.split(":", 1)
            docs[current] = text.strip()
        elif current is not None:
            docs[current] += " " + s
    return docs
