"""Parametric gmsh geometry of Goda's (1994) pendulum-test scale model.

Plane strain, SI units (metres), ``x`` horizontal, ``y`` up, origin at the centre
of the mound base. A rectangular caisson sits centred on the crest of a
trapezoidal gravel mound; the caisson base and the middle part of the crest are
one shared gmsh curve (``interface``), so the two bodies have conforming nodes
there. With ``GodaGeometry(conforming=False)`` the two bodies are meshed apart: the
caisson base (``caisson_base``) and the whole mound crest (``mound_crest``) are
distinct curves, coincident in space, with no shared nodes (for a general contact
pair, :mod:`breakwater.contact.general`), and each body has its own element size. The
struck (seaward) face is the caisson's left face; the pendulum pushes in ``+x``.

Physical groups are referred to by name (the module constants below); their
integer tags are fixed by :data:`PHYSICAL_GROUPS` so that files written by
formats that drop the names (VTU, XDMF) can still be decoded.
"""

from __future__ import annotations

import itertools
import math
import pathlib
from collections.abc import Callable, Mapping
from contextlib import AbstractContextManager
from dataclasses import dataclass, field, fields
from types import MappingProxyType

import gmsh  # type: ignore[import-untyped]
from mpi4py import MPI

from breakwater.common.gmshtools import gmsh_session as _session
from breakwater.common.parallel import on_rank_zero

# Surfaces (dim 2).
CAISSON = "caisson"
MOUND = "mound"
# Curves (dim 1).
INTERFACE = "interface"
BASE = "base"
IMPACT = "impact"
CAISSON_FRONT = "caisson_front"
CAISSON_REAR = "caisson_rear"
CAISSON_TOP = "caisson_top"
MOUND_SURFACE = "mound_surface"
CAISSON_BASE = "caisson_base"  # the separately meshed model only
MOUND_CREST = "mound_crest"  # the separately meshed model only
# Points (dim 0).
GAUGE_TOP = "gauge_top"
GAUGE_BOTTOM = "gauge_bottom"
CORNER_FRONT = "corner_front"
CORNER_REAR = "corner_rear"

#: Physical group name -> (dimension, tag) of the conforming model; the same shape as
#: ``dolfinx.io.gmsh.MeshData.physical_groups``. Tags are unique across dimensions.
PHYSICAL_GROUPS: Mapping[str, tuple[int, int]] = MappingProxyType(
    {
        CAISSON: (2, 1),
        MOUND: (2, 2),
        INTERFACE: (1, 11),
        BASE: (1, 12),
        IMPACT: (1, 13),
        CAISSON_FRONT: (1, 14),
        CAISSON_REAR: (1, 15),
        CAISSON_TOP: (1, 16),
        MOUND_SURFACE: (1, 17),
        GAUGE_TOP: (0, 21),
        GAUGE_BOTTOM: (0, 22),
        CORNER_FRONT: (0, 23),
        CORNER_REAR: (0, 24),
    }
)

#: The groups of the separately meshed model (``conforming=False``): no ``interface``;
#: the caisson base and the mound crest are groups of their own (tags not used by
#: :data:`PHYSICAL_GROUPS`). ``mound_surface`` is then the two slopes: the crest beside
#: the caisson belongs to ``mound_crest``, the surface a sliding caisson can reach.
SEPARATE_PHYSICAL_GROUPS: Mapping[str, tuple[int, int]] = MappingProxyType(
    {
        **{k: v for k, v in PHYSICAL_GROUPS.items() if k != INTERFACE},
        CAISSON_BASE: (1, 18),
        MOUND_CREST: (1, 19),
    }
)

# gmsh options used while building and writing; restored afterwards.
_OPTIONS: Mapping[str, float] = MappingProxyType(
    {
        "General.Terminal": 0,
        "Mesh.Algorithm": 6,  # Frontal-Delaunay
        "Mesh.MeshSizeFromPoints": 1,
        "Mesh.MeshSizeFromCurvature": 0,
        "Mesh.MeshSizeExtendFromBoundary": 1,
        "Mesh.MeshSizeFactor": 1.0,
        "Mesh.MeshSizeMin": 0.0,
        "Mesh.MeshSizeMax": 1e22,
        "Mesh.RandomFactor": 1e-9,
        "Mesh.MshFileVersion": 4.1,
        "Mesh.Binary": 0,
        "Mesh.SaveAll": 0,
    }
)
_MODEL_NAME = "breakwater-goda"

SLOPE_RANGE = (0.5, 20.0)
"""Mound side slopes accepted (horizontal run per unit rise): no gravel mound stands
steeper than 1:0.5 (63°), and 1:20 is no mound; gmsh took 7 s to mesh slope 300 and did
not finish slope 600 in minutes (the mound 230 m wide, 0.19 m high)."""


@dataclass(frozen=True)
class GodaGeometry:
    """Dimensions of the scale model (metres) and the mesh resolution.

    Defaults are those of Goda (1994) as used by Stickle et al. (2011); the
    element size reproduces their mesh (about 156 triangles in the caisson and
    558 in the mound).

    Attributes:
        mound_height: Height of the mound (crest above the floor).
        crest_width: Width of the mound crest.
        slope: Mound side slope, horizontal run per unit rise (1:2 V:H -> 2.0).
        caisson_width: Width of the caisson (along x).
        caisson_height: Height of the caisson.
        bolt_height: Height of the struck bolt above the caisson base.
        impact_patch_height: Length of the loaded segment centred on the bolt.
        gauge_offset_top: Distance of the upper gauge below the caisson top.
        gauge_offset_bottom: Distance of the lower gauge above the caisson base.
        mound_element_size: Target triangle edge length in the mound at refinement 1.
        caisson_element_size: Target triangle edge length in the caisson (and on
            the interface) at refinement 1.
        conforming: True: the caisson base and the crest under it are one shared
            curve (group ``interface``, shared nodes). False: the bodies are meshed
            apart, each with its own element size, no shared nodes: the caisson
            base (``caisson_base``) on the whole crest (``mound_crest``), for a
            general contact pair; ``mound_surface`` is then the slopes.

    """

    mound_height: float = 0.190
    crest_width: float = 0.400
    slope: float = field(default=2.0, metadata={"unit": "-"})  # the others are lengths (m)
    caisson_width: float = 0.205
    caisson_height: float = 0.202
    bolt_height: float = 0.168
    impact_patch_height: float = 0.010
    gauge_offset_top: float = 0.041
    gauge_offset_bottom: float = 0.041
    mound_element_size: float = 0.0265
    caisson_element_size: float = 0.029
    conforming: bool = field(default=True, metadata={"unit": "-"})

    def __post_init__(self) -> None:
        """Reject impossible geometries at construction."""
        self.validate()

    def validate(self) -> None:
        """Check that the dimensions describe a buildable model.

        Raises:
            ValueError: Naming the offending field, if a dimension is not a
                positive finite number, the caisson does not fit on the crest,
                or the impact patch or a gauge is not inside the front face.

        """
        if not isinstance(self.conforming, bool):
            raise ValueError(f"conforming must be true or false, got {self.conforming!r}")
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "conforming" or (value is None and f.default is None):
                continue  # a flag, or an optional dimension left out (a subclass's)
            if not (
                isinstance(value, int | float) and math.isfinite(value) and value > 0
            ):
                raise ValueError(
                    f"{f.name} must be a positive finite number, got {value!r}"
                )
        low_slope, high_slope = SLOPE_RANGE
        if not low_slope <= self.slope <= high_slope:
            raise ValueError(
                f"slope must be between {low_slope:g} and {high_slope:g} (horizontal run "
                f"per unit rise; got {self.slope:g})"
            )
        if self.caisson_width >= self.crest_width:
            raise ValueError(
                f"caisson_width ({self.caisson_width}) must be smaller than "
                f"crest_width ({self.crest_width}) for the caisson to sit on the crest"
            )
        low, high = self.impact_range
        if low <= self.caisson_base_y or high >= self.caisson_top_y:
            raise ValueError(
                f"bolt_height ({self.bolt_height}) with impact_patch_height "
                f"({self.impact_patch_height}) puts the impact patch outside "
                f"the front face: it must lie within (0, {self.caisson_height})"
            )
        for name in ("gauge_offset_top", "gauge_offset_bottom"):
            if getattr(self, name) >= self.caisson_height:
                raise ValueError(
                    f"{name} ({getattr(self, name)}) must be smaller than "
                    f"caisson_height ({self.caisson_height})"
                )

    def estimated_elements(self, refinement: float = 1.0) -> float:
        """The number of triangles gmsh makes at this refinement, estimated before meshing.

        Each body's area over the area of an equilateral triangle of its element size:
        within 0.6 to 1.3 of gmsh's count (measured: 715 against 601 at refinement 1,
        48764 against 48687 at refinement 9, 1732 against 1551 at slope 10).
        """
        mound = 0.5 * (self.crest_width + self.base_width) * self.mound_height
        caisson = self.caisson_width * self.caisson_height
        triangle = math.sqrt(3.0) / 4.0
        # Divided then multiplied in turn: (size / refinement) ** 2 underflows to 0 at a
        # refinement of 1e300 (ZeroDivisionError), refinement ** 2 raises OverflowError;
        # here a huge count is inf, which the case refuses (mesh.max_elements).
        return (mound / triangle / self.mound_element_size * refinement
                / self.mound_element_size * refinement
                + caisson / triangle / self.caisson_element_size * refinement
                / self.caisson_element_size * refinement)

    def coarse_elements(self, refinement: float = 1.0) -> str | None:
        """Why the element sizes at this refinement are too large, or None.

        An element larger than its body's height (or the caisson's width) leaves the
        body one element across: no bending, no contact pressure distribution.
        """
        for name, size, body, extent in (
            ("mound_element_size", self.mound_element_size, "mound height",
             self.mound_height),
            ("caisson_element_size", self.caisson_element_size, "caisson's smaller side",
             min(self.caisson_width, self.caisson_height)),
        ):
            if size / refinement > extent:
                return (f"{name} / refinement = {size / refinement:.4g} m is larger than "
                        f"the {body} ({extent:g} m)")
        return None

    @property
    def physical_groups(self) -> Mapping[str, tuple[int, int]]:
        """The model's physical groups: name -> (dimension, tag)."""
        return PHYSICAL_GROUPS if self.conforming else SEPARATE_PHYSICAL_GROUPS

    @property
    def base_width(self) -> float:
        """Width of the mound base."""
        return self.crest_width + 2.0 * self.slope * self.mound_height

    @property
    def caisson_base_y(self) -> float:
        """Elevation of the caisson base (= mound crest)."""
        return self.mound_height

    @property
    def caisson_top_y(self) -> float:
        """Elevation of the caisson top."""
        return self.mound_height + self.caisson_height

    @property
    def front_x(self) -> float:
        """Abscissa of the struck (seaward) caisson face."""
        return -0.5 * self.caisson_width

    @property
    def rear_x(self) -> float:
        """Abscissa of the rear caisson face."""
        return 0.5 * self.caisson_width

    @property
    def impact_range(self) -> tuple[float, float]:
        """Elevations ``(low, high)`` of the ends of the impact patch."""
        centre = self.caisson_base_y + self.bolt_height
        return (
            centre - 0.5 * self.impact_patch_height,
            centre + 0.5 * self.impact_patch_height,
        )

    @property
    def impact_point(self) -> tuple[float, float]:
        """The bolt: centre of the impact patch."""
        return self.front_x, self.caisson_base_y + self.bolt_height

    @property
    def gauge_top(self) -> tuple[float, float]:
        """Upper displacement gauge on the front face."""
        return self.front_x, self.caisson_top_y - self.gauge_offset_top

    @property
    def gauge_bottom(self) -> tuple[float, float]:
        """Lower displacement gauge on the front face."""
        return self.front_x, self.caisson_base_y + self.gauge_offset_bottom

    @property
    def corner_front(self) -> tuple[float, float]:
        """Caisson base corner on the struck side."""
        return self.front_x, self.caisson_base_y

    @property
    def corner_rear(self) -> tuple[float, float]:
        """Caisson base corner on the rear side."""
        return self.rear_x, self.caisson_base_y

    def named_points(self) -> dict[str, tuple[float, float]]:
        """Coordinates of the dim-0 physical groups, by group name."""
        return {
            GAUGE_TOP: self.gauge_top,
            GAUGE_BOTTOM: self.gauge_bottom,
            CORNER_FRONT: self.corner_front,
            CORNER_REAR: self.corner_rear,
        }


def _check_mesh_args(refinement: float, order: int) -> None:
    """Refuse a refinement that is not a positive finite number, an order not 1 or 2."""
    if not (isinstance(refinement, int | float) and math.isfinite(refinement)
            and refinement > 0):
        raise ValueError(f"refinement must be a positive finite number, got {refinement!r}")
    if order not in (1, 2):
        raise ValueError(f"order must be 1 or 2, got {order!r}")


def gmsh_session() -> AbstractContextManager[None]:
    """A quiet gmsh session with this module's meshing options.

    See :func:`breakwater.common.gmshtools.gmsh_session`: nested in the caller's session,
    the caller's model and options are restored on exit.
    """
    return _session(_OPTIONS, _MODEL_NAME)


def build_model(
    geometry: GodaGeometry | None = None, refinement: float = 1.0, order: int = 1
) -> None:
    """Build and mesh the model in gmsh's current model.

    gmsh must be initialised (see :func:`gmsh_session`). The result can be
    written with ``gmsh.write`` or passed to ``dolfinx.io.gmsh.model_to_mesh``.

    Args:
        geometry: Dimensions; Goda's model if None.
        refinement: Element sizes are ``(mound|caisson)_element_size / refinement``.
        order: Geometric order of the elements, 1 (3-node) or 2 (6-node triangles).

    The physical groups are ``geometry.physical_groups`` (:data:`PHYSICAL_GROUPS`,
    or :data:`SEPARATE_PHYSICAL_GROUPS` for ``conforming=False``).

    Raises:
        ValueError: For a non-positive refinement or an order other than 1 or 2.

    """
    g = GodaGeometry() if geometry is None else geometry
    g.validate()
    _check_mesh_args(refinement, order)
    geo = gmsh.model.geo

    def point(x: float, y: float, size: float = g.caisson_element_size) -> int:
        return int(geo.addPoint(x, y, 0.0, size / refinement))

    half_base, half_crest = 0.5 * g.base_width, 0.5 * g.crest_width
    y0, y1, y2 = 0.0, g.caisson_base_y, g.caisson_top_y
    mound_size = g.mound_element_size
    base_left = point(-half_base, y0, mound_size)
    base_right = point(half_base, y0, mound_size)
    crest_left = point(-half_crest, y1, mound_size)
    crest_right = point(half_crest, y1, mound_size)
    corner_front, corner_rear = point(*g.corner_front), point(*g.corner_rear)
    top_front, top_rear = point(g.front_x, y2), point(g.rear_x, y2)

    # Front face, split at the gauges and at the ends of the impact patch
    # (stations closer than `tol` are merged).
    low, high = g.impact_range
    tol = 1e-9 * g.caisson_height
    stations: list[float] = []
    for y in sorted((g.gauge_bottom[1], low, high, g.gauge_top[1])):
        if not stations or y - stations[-1] > tol:
            stations.append(y)
    front_ids = {y: point(g.front_x, y) for y in stations}
    chain = [
        (y2, top_front),
        *((y, front_ids[y]) for y in reversed(stations)),
        (y1, corner_front),
    ]

    line = geo.addLine
    base = line(base_left, base_right)
    slopes = [line(base_right, crest_right), line(crest_left, base_left)]
    # Conforming: the crest beside the caisson, and the caisson base shared with it.
    # Separate: the whole crest, and the caisson base apart from it.
    crest = ([line(crest_right, corner_rear), line(corner_front, crest_left)]
             if g.conforming else [line(crest_right, crest_left)])
    bottom = line(corner_front, corner_rear)  # the caisson base
    crest_loop = [crest[0], -bottom, crest[1]] if g.conforming else crest
    rear, top = line(corner_rear, top_rear), line(top_rear, top_front)
    segments = list(itertools.pairwise(chain))  # top -> down
    front_chain = [line(pa, pb) for (_, pa), (_, pb) in segments]
    on_patch = [yb >= low - tol and ya <= high + tol for (ya, _), (yb, _) in segments]
    impact = [c for c, hit in zip(front_chain, on_patch, strict=True) if hit]
    front = [c for c, hit in zip(front_chain, on_patch, strict=True) if not hit]

    mound_loop = [base, slopes[0], *crest_loop, slopes[1]]
    caisson_loop = [bottom, rear, top, *front_chain]
    caisson = geo.addPlaneSurface([geo.addCurveLoop(caisson_loop)])
    mound = geo.addPlaneSurface([geo.addCurveLoop(mound_loop)])
    geo.synchronize()

    contact_groups = (
        {INTERFACE: [bottom], MOUND_SURFACE: [*crest, *slopes]}
        if g.conforming
        else {CAISSON_BASE: [bottom], MOUND_CREST: crest, MOUND_SURFACE: slopes}
    )
    entities = {
        CAISSON: [caisson],
        MOUND: [mound],
        BASE: [base],
        IMPACT: impact,
        CAISSON_FRONT: front,
        CAISSON_REAR: [rear],
        CAISSON_TOP: [top],
        **contact_groups,
        GAUGE_TOP: [front_ids[_nearest(stations, g.gauge_top[1])]],
        GAUGE_BOTTOM: [front_ids[_nearest(stations, g.gauge_bottom[1])]],
        CORNER_FRONT: [corner_front],
        CORNER_REAR: [corner_rear],
    }
    for name, (dim, tag) in g.physical_groups.items():
        gmsh.model.addPhysicalGroup(dim, entities[name], tag=tag, name=name)

    gmsh.model.mesh.generate(2)
    if order == 2:
        gmsh.model.mesh.setOrder(2)


def _nearest(stations: list[float], y: float) -> float:
    return min(stations, key=lambda s: abs(s - y))


def generate(
    path: str | pathlib.Path,
    geometry: GodaGeometry | None = None,
    refinement: float = 1.0,
    order: int = 1,
    comm: MPI.Comm | None = None,
) -> pathlib.Path:
    """Mesh the model and write it as a gmsh 4.1 ``.msh`` file.

    Only rank 0 of ``comm`` builds and writes; every rank returns once the file
    exists. The path of rank 0 is used (and returned) on all ranks.

    Args:
        path: Output file; parent folders are created.
        geometry: Dimensions; Goda's model if None.
        refinement: Element sizes are ``(mound|caisson)_element_size / refinement``
            (cell counts grow about as ``refinement**2``).
        order: Geometric order, 1 (3-node) or 2 (6-node triangles).
        comm: MPI communicator; ``MPI.COMM_WORLD`` if None.

    Returns:
        The path of the written file.

    Raises:
        ValueError: For invalid geometry, refinement or order (on all ranks).
        Exception: What gmsh raised on rank 0, on every rank (see
            :func:`breakwater.common.parallel.on_rank_zero`).

    """
    g = GodaGeometry() if geometry is None else geometry
    g.validate()
    _check_mesh_args(refinement, order)
    return write_mesh(path, comm, gmsh_session, lambda: build_model(g, refinement, order))


def write_mesh(path: str | pathlib.Path, comm: MPI.Comm | None,
               session: Callable[[], AbstractContextManager[None]],
               build: Callable[[], None]) -> pathlib.Path:
    """Build a gmsh model in ``session`` on rank 0 and write it to rank 0's ``path``.

    Every rank returns the path once the file exists; what rank 0 raised is raised on
    every rank (:func:`breakwater.common.parallel.on_rank_zero`).
    """
    comm = MPI.COMM_WORLD if comm is None else comm
    out = pathlib.Path(on_rank_zero(comm, lambda: str(path)))  # rank 0's path

    def write() -> None:
        out.parent.mkdir(parents=True, exist_ok=True)
        with session():
            build()
            gmsh.write(str(out))

    on_rank_zero(comm, write)
    return out
