"""The tables of a case file, one frozen dataclass each (the ``[loads.*]`` tables aside).

``[mesh]`` (:class:`MeshCase`), ``[bodies.<name>]`` (:class:`BodyCase`),
``[contact.<name>]`` (:class:`ContactCase`), ``[fixed.<name>]`` (:class:`FixedCase`),
``[initial]`` (:class:`InitialCase`), ``[damping]`` (:class:`DampingCase`),
``[calibration]`` (:class:`CalibrationCase`), ``[time]`` (:data:`TimeCase`, the run
layer's :class:`~breakwater.config.runspec.TimeSpec`) and ``[output]``
(:class:`OutputCase`, with its ``probes`` and ``pair_probes``). Each checks its own
values in ``__post_init__`` (:class:`~breakwater.config.fields.InvalidField`); the
checks across tables are the whole case's
(:class:`~breakwater.casefile.settings.CaseSettings`). The ``[loads.<name>]`` tables
are :mod:`breakwater.casefile.loads`. Nothing here needs the solver stack.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, get_args

from breakwater.config.fields import InvalidField, column_name, positive, setting
from breakwater.config.runspec import TimeSpec
from breakwater.config.typecheck import check_fields
from breakwater.meshes.goda import GodaGeometry
from breakwater.meshes.goda3d import Goda3DGeometry

if TYPE_CHECKING:
    from breakwater.model.model import Material

__all__ = ["GODA", "GODA3D", "BodyCase", "CalibrationCase", "ContactCase", "DampingCase",
           "FixedCase", "InitialCase", "MeshCase", "OutputCase", "PairProbeCase", "ProbeCase",
           "StiffnessBasis", "TimeCase"]

GODA = "goda"
"""``mesh.source`` value selecting the built-in Goda mesh generator."""
GODA3D = "goda3d"
"""``mesh.source`` value selecting the built-in 3D Goda mesh generator (hexahedra)."""


MAX_POINTS = 20
"""Gauss points per integration segment of a general pair at most: on a segment the
integrand is smooth (a P2 shape function times the penalty of a quadratic gap), which 3
points integrate to degree 5; 20000 points took 6.5 GB and 20 minutes before the first
time step of a block on a base (1e9: a MemoryError of leggauss's 1e9 x 1e9 matrix)."""
GENERAL_ONLY = {"points": 3, "integration": "segments", "rotations": "finite"}
"""A general pair's keys and their defaults: a conforming pair (one shared group) is
integrated at its shared nodes with the reference normal, so another value on it would be
ignored (``integration = "gauss"`` on goda's interface ran silently as before)."""
REGULARISATION_RANGE = (1e-100, 1e100)
"""Regularisation velocities χ (m/s) the friction law's arithmetic takes: its Jacobian and
the slip guard use χ² and χ³, which underflow below 3e-103 and overflow above 6e102 (χ =
1e-300 stopped a run with "ZeroDivisionError: division by zero", χ = 1e300 a conforming
pair's with an OverflowError's traceback). The paper's χ is 1e-10 m/s."""

_GODA_GEOMETRY = GodaGeometry()
_GODA3D_GEOMETRY = Goda3DGeometry()


@dataclass(frozen=True)
class MeshCase:
    """``[mesh]``: where the mesh comes from."""

    source: str = setting(GODA, doc='"goda" (the built-in generator, [mesh.goda]), "goda3d" '
                          '(its 3D block on the mound, hexahedra, [mesh.goda3d]) or a gmsh '
                          '.msh/.geo file with named physical groups, or the .xdmf that '
                          '`breakwater mesh --out x.xdmf` wrote (with its .h5), relative to '
                          'the case file')
    refinement: float = setting(1.0, doc="goda, goda3d only: element sizes are divided by "
                                "this (cell counts grow as refinement², refinement³ in 3D; "
                                "with a mesh file, refused unless 1)")
    degree: int = setting(2, doc="polynomial degree of the displacement (2: six-node "
                          "triangles, as the paper; a .geo with a curved curve is then "
                          "meshed second order, curved cells)")
    goda: GodaGeometry = setting(_GODA_GEOMETRY, unit="m",  # noqa: RUF009 (a field() with docs)
                                 doc="goda only: dimensions of the model (see below)")
    goda3d: Goda3DGeometry = setting(_GODA3D_GEOMETRY, unit="m",  # noqa: RUF009 (a field() with docs)
                                     doc="goda3d only: dimensions of the 3D model (goda's "
                                     "and the block's length, the flume's width)")
    max_elements: int = setting(1_000_000, doc="goda, goda3d only: refuse a mesh of more "
                                "cells (estimated before meshing: each body's area over its "
                                "element's; exact in 3D); refinement 9 makes about 49000 "
                                "triangles")

    def __post_init__(self) -> None:
        check_fields(self)
        if not (self.refinement > 0 and math.isfinite(self.refinement)):
            raise InvalidField("refinement", f"must be > 0 (got {self.refinement:g})")
        if self.degree not in (1, 2):
            raise InvalidField("degree", f"must be 1 or 2 (got {self.degree})")
        if not self.source:
            raise InvalidField("source", 'must be "goda", "goda3d" or a mesh file')
        positive(self.max_elements, "max_elements")
        if not self.generated and self.refinement != 1.0:  # it was left unused, silently
            raise InvalidField("refinement", f"{self.refinement:g} refines the built-in goda "
                               "and goda3d meshes only: a mesh file is used as it is "
                               f"({self.source}); refine it in gmsh (its MeshSize, or "
                               f"Mesh.MeshSizeFactor = {1 / self.refinement:g} in a .geo), "
                               "and leave refinement at 1")
        if self.generated:
            coarse = self.geometry.coarse_elements(self.refinement)
            if coarse is not None:
                raise InvalidField("refinement", f"{self.refinement:g}: {coarse}",
                                   others=(self.source,))
            estimate = self.geometry.estimated_elements(self.refinement)
            if estimate > self.max_elements:
                cells = "hexahedra" if self.source == GODA3D else "triangles"
                raise InvalidField("max_elements", f"refinement {self.refinement:g} with "
                                   f"the mesh.{self.source} dimensions and element sizes "
                                   f"makes about {estimate:.3g} {cells}, above the limit "
                                   f"{self.max_elements} (raise mesh.max_elements to mesh "
                                   "it)", others=("refinement", self.source))

    @property
    def generated(self) -> bool:
        """True for the built-in Goda generators (2D and 3D)."""
        return self.source in (GODA, GODA3D)

    @property
    def geometry(self) -> GodaGeometry:
        """The built-in generator's geometry: ``goda3d`` for "goda3d", else ``goda``."""
        return self.goda3d if self.source == GODA3D else self.goda


@dataclass(frozen=True)
class BodyCase:
    """``[bodies.<name>]``: a deformable body, its cell group and its material.

    Give exactly one of ``shear_modulus`` and ``young_modulus``, or neither for the
    body whose shear modulus ``[calibration]`` finds.
    """

    name: str = setting(key=True, doc="cell (2D) or volume (3D) physical group of the body "
                        "(it heads history.csv columns: no comma, double quote or control "
                        "character)")
    density: float = setting(unit="kg/m³", doc="mass density ρ")
    poisson: float = setting(doc="Poisson's ratio ν, in (−1, 0.5)")
    shear_modulus: float | None = setting(None, unit="Pa", doc="shear modulus G")
    young_modulus: float | None = setting(None, unit="Pa", doc="Young's modulus E")
    initial_velocity: tuple[float, ...] = setting((0.0, 0.0), unit="m/s", doc="uniform "
                                                  "velocity of the body at t = 0")

    def __post_init__(self) -> None:
        check_fields(self)
        column_name(self.name)  # <name>_rotation: a comma split history.csv's header
        positive(self.density, "density")
        if len(self.initial_velocity) not in (2, 3) \
                or not all(map(math.isfinite, self.initial_velocity)):
            raise InvalidField("initial_velocity", f"must be 2 or 3 (3D) finite numbers (got "
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
                        "pair's name (it heads history.csv columns: no comma, double "
                        "quote or control character)")
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
    points: int = setting(3, doc="general pair: Gauss points per integration segment (2 to "
                          "20; in 3D a triangle rule of degree 2 points - 1 per segment)")
    integration: Literal["segments", "gauss", "nodes"] = setting(
        "segments", doc="general pair: the slave's integration points: segments "
        "(segment-to-segment, `points` Gauss points per segment), gauss (`points` per "
        "slave facet) or nodes (the slave nodes, Simpson weights: the conforming pair's "
        "quadrature; refused in 3D: a 6-node triangle's vertex weights integrate to zero)")
    rotations: Literal["finite", "small"] = setting(
        "finite", doc="general pair: the normal of the current master surface at the "
        "projection (finite, eq. 7) or of the reference one (small: the linear bodies' "
        "small rotations, as a conforming pair; finite sliding kept)")

    def __post_init__(self) -> None:
        check_fields(self)
        column_name(self.name)  # <name>_normal_force ...: a comma split history.csv's header
        if (self.slave_surface is None) != (self.master_surface is None):
            raise InvalidField("master_surface" if self.master_surface is None
                               else "slave_surface", "a general pair needs both "
                               "slave_surface and master_surface")
        if self.general and self.gap:
            raise InvalidField("gap", "a general pair takes its gap from the geometry "
                               "(remove gap)")
        for key, default in GENERAL_ONLY.items():
            if not self.general and getattr(self, key) != default:
                raise InvalidField(key, f"{key} = {getattr(self, key)!r} is a general "
                                   "pair's setting (with slave_surface and master_surface):"
                                   " a conforming pair is integrated at its shared nodes "
                                   "with its reference normals, and would not apply it "
                                   f"(remove {key})")
        if self.points < 2:  # at one point (a segment's middle) the P2 end nodes' N is 0
            raise InvalidField("points", f"must be >= 2 (got {self.points}): one Gauss point "
                               "per segment gives the facets' end nodes no contact force")
        if self.points > MAX_POINTS:
            raise InvalidField("points", f"must be <= {MAX_POINTS} (got {self.points}): "
                               "the integrand is smooth on each segment, where 3 points "
                               "integrate it to degree 5")
        if self.master_surface == ():
            raise InvalidField("master_surface", "needs at least one facet group")
        positive(self.penalty, "penalty")
        positive(self.friction, "friction", strict=False)
        positive(self.regularisation, "regularisation")
        low, high = REGULARISATION_RANGE
        if not low <= self.regularisation <= high:
            raise InvalidField("regularisation", f"must be between {low:g} and {high:g} m/s "
                               f"(got {self.regularisation:g}): the friction law's χ² and "
                               "χ³ under- or overflow (the paper's χ is 1e-10 m/s)")
        if self.slave == self.master:
            raise InvalidField("master", "slave and master must be different bodies")

    @property
    def general(self) -> bool:
        """A pair between two surfaces that need not match (not one shared group)."""
        return self.slave_surface is not None


@dataclass(frozen=True)
class FixedCase:
    """``[fixed.<group>]``: zero displacement on a facet group or at a point group's nodes."""

    name: str = setting(key=True, doc="facet (1D; 2D in 3D) or point (0D) physical group")
    components: tuple[int, ...] | None = setting(None, doc="fixed displacement components "
                                                 "(0: x, 1: y, 2: z in 3D); default all")

    def __post_init__(self) -> None:
        check_fields(self)
        if self.components is None:
            return
        if not self.components:
            raise InvalidField("components", "fix at least one component")
        if any(c not in (0, 1, 2) for c in self.components) or \
                len(set(self.components)) != len(self.components):
            raise InvalidField("components", f"must be distinct values among 0 (x), 1 (y) "
                               f"and 2 (z, 3D) (got {list(self.components)})")


@dataclass(frozen=True)
class InitialCase:
    """``[initial]``: the static initial state: its loads, how they are applied, its tolerance.

    The load names are checked by :class:`~breakwater.casefile.settings.CaseSettings`; a
    body's initial velocity is ``bodies.<name>.initial_velocity``. The run layer
    receives them as an :class:`~breakwater.config.runspec.InitialSpec`.
    """

    loads: tuple[str, ...] | None = setting(None, doc="names of the loads in the static "
                                            "initial state, at their values at t = 0 (default: "
                                            "every load; [] none: gravity only)")
    loading: Literal["frictional", "frictionless"] = setting(
        "frictional", doc="how gravity and the initial loads are applied where a pair has "
        "friction: frictional (friction active on the way, as if the loads were applied "
        "slowly: no frictionless slide) or frictionless (the frictionless equilibrium "
        "where one exists, friction only where none does)")
    tolerance: float = setting(1e-9, doc="the static state's residual ‖f − K u − f_c(u)‖ "
                               "as a fraction of the load norm ‖f‖ (a time step's Newton: "
                               "1e-9)")
    undeformed: bool = setting(False, doc="start from the undeformed state at rest (no "
                               "static state: the bodies start unloaded under the loads); "
                               "otherwise a static state that cannot be found is an error")

    def __post_init__(self) -> None:
        check_fields(self)
        if not 0 < self.tolerance < 1:
            raise InvalidField("tolerance", f"must be in (0, 1) (got {self.tolerance:g})")


@dataclass(frozen=True)
class DampingCase:
    """``[damping]``: Rayleigh damping C = αM + βK of every body."""

    alpha: float = setting(0.0, unit="1/s", doc="mass-proportional coefficient α")
    beta: float = setting(0.0, unit="s", doc="stiffness-proportional coefficient β")

    def __post_init__(self) -> None:
        check_fields(self)
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
        check_fields(self)
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
    if obj.point is not None and len(obj.point) not in (2, 3):
        raise InvalidField("point", f"must have 2 or 3 (3D) coordinates (got "
                           f"{list(obj.point)})")


@dataclass(frozen=True)
class ProbeCase:
    """``[output.probes.<name>]``: displacement history of a point of a body."""

    name: str = setting(key=True, doc="probe name (output column prefix: no comma, double "
                        "quote or control character)")
    body: str = setting(doc="body the point belongs to")
    group: str | None = setting(None, doc="point (0D) physical group holding the point")
    point: tuple[float, ...] | None = setting(None, unit="m", doc="coordinates of the point "
                                              "(instead of group)")

    def __post_init__(self) -> None:
        check_fields(self)
        column_name(self.name)
        _one_location(self)


@dataclass(frozen=True)
class PairProbeCase:
    """``[output.pair_probes.<name>]``: slip and opening of an interface point."""

    name: str = setting(key=True, doc="probe name (output column prefix: no comma, double "
                        "quote or control character)")
    pair: str = setting(doc="contact pair (its interface name; for a general pair the "
                        "point lies on its slave surface)")
    group: str | None = setting(None, doc="point (0D) physical group holding the point")
    point: tuple[float, ...] | None = setting(None, unit="m", doc="coordinates of the point "
                                              "(instead of group)")

    def __post_init__(self) -> None:
        check_fields(self)
        column_name(self.name)
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
        check_fields(self)
        positive(self.field_interval, "field_interval", strict=False)
        positive(self.checkpoint_interval, "checkpoint_interval", strict=False)
