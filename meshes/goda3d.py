"""Parametric gmsh geometry of Goda's (1994) pendulum test in three dimensions.

SI units (metres), ``x`` horizontal (the pendulum pushes in ``+x``), ``y`` up, ``z``
across the flume, from ``z = 0`` to ``z = flume_width``: ``x = 0`` at the middle of the
mound and ``y = 0`` on its base, as in 2-D, ``z = 0`` on one flume wall. The mound is
the 2-D trapezoid (:mod:`breakwater.meshes.goda`) extruded across the whole flume; the
caisson is the 2-D rectangle extruded over ``caisson_length``, centred across the flume.
A flume wider than the block leaves free crest on both sides of it (part of
``mound_surface``).

The mesh is structured: hexahedral blocks of gmsh's geo kernel, each meshed transfinite
with recombined faces, so every cell is a hexahedron (27-node at order 2, straight
edges). The blocks share their points, curves and faces, so the caisson base and the
crest under it have the same nodes (``interface``, conforming). The cross-section is cut
into rectangles (the caisson, the mound under it and the crest beside it) and, under
each slope, three quadrilaterals that split the slope's triangle; node planes run
through the model at the caisson's faces, at the gauges' heights and the impact patch's
edges (in the caisson), and across the flume at the block's ends, at the patch's edges
and at mid-length. Cells in the slope triangles are general quadrilateral prisms (a
trilinear map); the others are boxes.

Physical groups are referred to by name (the module constants below, the 2-D ones where
the meaning is the same); their integer tags are fixed by :data:`PHYSICAL_GROUPS`.
"""

from __future__ import annotations

import itertools
import math
import pathlib
from collections.abc import Mapping, Sequence
from contextlib import AbstractContextManager
from dataclasses import dataclass
from types import MappingProxyType

import gmsh  # type: ignore[import-untyped]
from mpi4py import MPI

from breakwater.common.gmshtools import gmsh_session as _session

from .goda import (
    BASE,
    CAISSON,
    CAISSON_FRONT,
    CAISSON_REAR,
    CAISSON_TOP,
    CORNER_FRONT,
    CORNER_REAR,
    GAUGE_BOTTOM,
    GAUGE_TOP,
    IMPACT,
    INTERFACE,
    MOUND,
    MOUND_SURFACE,
    GodaGeometry,
    _check_mesh_args,
    write_mesh,
)
from .goda import PHYSICAL_GROUPS as PHYSICAL_GROUPS_2D

# Volumes (dim 3): CAISSON, MOUND. Surfaces (dim 2): INTERFACE, BASE, IMPACT,
# CAISSON_FRONT, CAISSON_REAR, CAISSON_TOP, MOUND_SURFACE and:
CAISSON_SIDES = "caisson_sides"
"""The block's two faces normal to ``z`` (at its ends across the flume)."""
MOUND_SIDES = "mound_sides"
"""The mound's faces at ``z = 0`` and ``z = flume_width`` (the flume's side walls)."""
# Points (dim 0): GAUGE_TOP, GAUGE_BOTTOM, CORNER_FRONT, CORNER_REAR, at mid-length.

#: Physical group name -> (dimension, tag); the same shape as
#: ``dolfinx.io.gmsh.MeshData.physical_groups``: the 2-D model's groups one dimension up
#: (points stay points) with their tags, and the two pairs of faces across the flume;
#: tags are unique across dimensions.
PHYSICAL_GROUPS: Mapping[str, tuple[int, int]] = MappingProxyType(
    {
        **{name: (dim + 1 if dim else 0, tag)
           for name, (dim, tag) in PHYSICAL_GROUPS_2D.items()},
        CAISSON_SIDES: (2, 31),
        MOUND_SIDES: (2, 32),
    }
)

# gmsh options used while building and writing; restored afterwards.
_OPTIONS: Mapping[str, float] = MappingProxyType(
    {
        "General.Terminal": 0,
        "Mesh.SecondOrderIncomplete": 0,  # 27-node hexahedra, 9-node quadrilaterals
        "Mesh.RecombineAll": 0,
        "Mesh.Recombine3DAll": 0,
        "Mesh.MshFileVersion": 4.1,
        "Mesh.Binary": 0,
        "Mesh.SaveAll": 0,
    }
)
_MODEL_NAME = "breakwater-goda3d"

THINNEST_STRIP = 1e-3
"""Node planes closer than this fraction of the body's extent are refused (a flume wider
than the block by less than this fraction of ``caisson_length``, a gauge beside a patch
edge, ...): they would make a layer of needle-thin cells through the body."""


@dataclass(frozen=True)
class Goda3DGeometry(GodaGeometry):
    """Dimensions of the 3-D scale model (metres) and the mesh resolution.

    The cross-section's dimensions are :class:`~breakwater.meshes.goda.GodaGeometry`'s
    (the element sizes are the hexahedra's edge lengths, coarser by default than the
    2-D triangles': the default mesh has 1032 hexahedra, 7896 at refinement 2); only
    the conforming model exists in 3-D. Goda's block was 205 mm long across a flume of its width.

    Attributes:
        caisson_length: Length of the caisson across the flume (along z).
        flume_width: Width of the flume (the mound's length along z); None: the
            caisson's length (the block spans the flume, the 2-D model's slice).
        impact_patch_width: Width (along z) of the struck patch, centred on the block.
        across_element_size: Target hexahedron edge length along z at refinement 1.

    """

    mound_element_size: float = 0.04
    caisson_element_size: float = 0.04
    caisson_length: float = 0.205
    flume_width: float | None = None
    impact_patch_width: float = 0.010
    across_element_size: float = 0.04

    def validate(self) -> None:
        """Check that the dimensions describe a buildable 3-D model.

        Raises:
            ValueError: Naming the offending field: GodaGeometry's checks; the model
                is not conforming; the flume is narrower than the block or wider by
                a sliver; the impact patch is not inside the front face.

        """
        super().validate()
        if not self.conforming:
            raise ValueError("conforming must be true: the 3-D model is meshed with "
                             "shared nodes on the interface only")
        width, length = self.flume, self.caisson_length
        if width < length:
            raise ValueError(f"flume_width ({width}) must not be smaller than "
                             f"caisson_length ({length}): the block must fit in the flume")
        if 0 < width - length < THINNEST_STRIP * length:
            raise ValueError(f"flume_width ({width}) exceeds caisson_length ({length}) by "
                             f"less than {THINNEST_STRIP:g} of it: make them equal or the "
                             "flume wider")
        if self.impact_patch_width >= length:
            raise ValueError(f"impact_patch_width ({self.impact_patch_width}) must be "
                             f"smaller than caisson_length ({length}) for the patch to "
                             "lie within the front face")
        self._check_layers()

    def _check_layers(self) -> None:
        """Refuse node planes closer than :data:`THINNEST_STRIP` of the body's extent.

        The mesh is structured: two close stations (a gauge beside a patch edge, a
        patch almost as wide as the block) make a layer of needle-thin cells through
        the whole body, which no later check of the 3-D mesh catches.
        """
        low, high = self.impact_range
        p0, p1 = self.impact_z
        z0, z1 = self.caisson_z
        half_b, half_c = 0.5 * self.caisson_width, 0.5 * self.crest_width
        for axis, extent, values, names in (
            ("y", self.caisson_height,
             (self.caisson_base_y, self.gauge_bottom[1], low, high, self.gauge_top[1],
              self.caisson_top_y),
             "bolt_height, impact_patch_height, gauge_offset_top and gauge_offset_bottom"),
            ("z", self.caisson_length, (z0, p0, self.mid_z, p1, z1),
             "impact_patch_width and caisson_length"),
            ("x", self.crest_width, (-half_c, -half_b, half_b, half_c),
             "caisson_width and crest_width"),
        ):
            merge = 1e-9 * extent  # stations this close are one (as in 2-D)
            ordered = sorted(values)
            for a, b in itertools.pairwise(ordered):
                if merge < b - a < THINNEST_STRIP * extent:
                    raise ValueError(
                        f"{names} put node planes {1e3 * (b - a):.3g} mm apart at "
                        f"{axis} = {a:.6g} m (under {THINNEST_STRIP:g} of {extent:g} m: a "
                        "layer of needle-thin hexahedra): move them apart")

    def estimated_elements(self, refinement: float = 1.0) -> float:
        """The number of hexahedra at this refinement: exact (the mesh is structured).

        Infinite where the count overflows (an absurd refinement).
        """
        try:
            return float(_plan(self, refinement).cells())
        except OverflowError:
            return math.inf

    def coarse_elements(self, refinement: float = 1.0) -> str | None:
        """Why the element sizes at this refinement are too large, or None."""
        coarse = super().coarse_elements(refinement)
        if coarse is None and self.across_element_size / refinement > self.caisson_length:
            return (f"across_element_size / refinement = "
                    f"{self.across_element_size / refinement:.4g} m is larger than the "
                    f"caisson_length ({self.caisson_length:g} m)")
        return coarse

    @property
    def physical_groups(self) -> Mapping[str, tuple[int, int]]:
        """The model's physical groups: name -> (dimension, tag)."""
        return PHYSICAL_GROUPS

    @property
    def flume(self) -> float:
        """Width of the flume: ``flume_width``, or the caisson's length if None."""
        return self.caisson_length if self.flume_width is None else self.flume_width

    @property
    def mid_z(self) -> float:
        """The flume's (and the block's) mid-length."""
        return 0.5 * self.flume

    @property
    def caisson_z(self) -> tuple[float, float]:
        """The block's ends ``(z0, z1)`` across the flume."""
        if self.flume_width is None or self.flume_width == self.caisson_length:
            return 0.0, self.flume
        half = 0.5 * self.caisson_length
        return self.mid_z - half, self.mid_z + half

    @property
    def impact_z(self) -> tuple[float, float]:
        """The impact patch's edges ``(z0, z1)`` across the flume."""
        half = 0.5 * self.impact_patch_width
        return self.mid_z - half, self.mid_z + half

    def named_points_3d(self) -> dict[str, tuple[float, float, float]]:
        """Coordinates of the dim-0 physical groups (at mid-length), by group name."""
        return {name: (x, y, self.mid_z) for name, (x, y) in self.named_points().items()}


def _divisions(length: float, size: float) -> int:
    """Cells of about ``size`` along ``length``: at least one."""
    return max(1, math.floor(length / size + 0.5))


def _stations(values: Sequence[float], tol: float) -> list[float]:
    """Sorted values, those closer than ``tol`` to the previous merged into it."""
    out: list[float] = []
    for v in sorted(values):
        if not out or v - out[-1] > tol:
            out.append(v)
    return out


@dataclass(frozen=True)
class _Plan:
    """The structured mesh's node stations and cell counts (refinement applied).

    Each slope's triangle (its foot ``A``, the crest's corner above the floor ``B``,
    the crest's end ``C``) is split into three quadrilaterals meeting at a point
    ``G``: ``n1`` cells along ``A``-``pAB`` and ``pBC``-``C``, ``n2`` along
    ``B``-``pBC`` and ``pCA``-``A``, ``n4`` along ``pAB``-``B`` and ``C``-``pCA``.
    """

    n1: int
    n2: int
    n4: int
    side: int  # the crest beside the caisson, along x
    across: int  # the caisson and the mound under it, along x
    y: tuple[float, ...]  # the caisson's node planes, base to top
    ny: tuple[int, ...]
    z: tuple[float, ...]  # node planes across the flume
    nz: tuple[int, ...]
    caisson_z: tuple[int, int]  # indices in z of the block's ends

    def cells(self) -> int:
        """The number of hexahedra."""
        n1, n2, n4 = self.n1, self.n2, self.n4
        section = (2 * (n1 * n2 + n2 * n4 + n4 * n1) + 2 * self.side * (n1 + n2)
                   + self.across * (n1 + n2))
        k0, k1 = self.caisson_z
        return section * sum(self.nz) + self.across * sum(self.ny) * sum(self.nz[k0:k1])


def _plan(g: Goda3DGeometry, refinement: float) -> _Plan:
    h_mound = g.mound_element_size / refinement
    h_caisson = g.caisson_element_size / refinement
    h_z = g.across_element_size / refinement
    height, run = g.mound_height, g.slope * g.mound_height
    hyp = math.hypot(height, run)
    n1 = _divisions(0.5 * (run + height - hyp), h_mound)
    n2 = _divisions(0.5 * (height + hyp - run), h_mound)
    n4 = _divisions(0.5 * (run + hyp - height), h_mound)
    low, high = g.impact_range
    y = _stations([g.caisson_base_y, g.gauge_bottom[1], low, high, g.gauge_top[1],
                   g.caisson_top_y], 1e-9 * g.caisson_height)
    width = g.flume
    z0, z1 = g.caisson_z
    p0, p1 = g.impact_z
    z = _stations([0.0, z0, p0, g.mid_z, p1, z1, width], 1e-9 * width)
    return _Plan(
        n1=n1, n2=n2, n4=n4,
        side=_divisions(0.5 * (g.crest_width - g.caisson_width), h_mound),
        across=_divisions(g.caisson_width, h_caisson),
        y=tuple(y), ny=tuple(_divisions(b - a, h_caisson) for a, b in itertools.pairwise(y)),
        z=tuple(z), nz=tuple(_divisions(b - a, h_z) for a, b in itertools.pairwise(z)),
        caisson_z=(_nearest(z, z0), _nearest(z, z1)),
    )


def _nearest(values: Sequence[float], v: float) -> int:
    return min(range(len(values)), key=lambda i: abs(values[i] - v))


Patch = tuple[str, str, str, str]
"""A quadrilateral of the cross-section: its corners' names, counter-clockwise."""
Key = tuple[str, int]
"""A point of the model: its cross-section point's name and its node plane in z."""


class _Blocks:
    """Hexahedral blocks in gmsh's geo kernel sharing their points, curves and faces.

    A block is a cross-section patch between two consecutive node planes in ``z``;
    every curve, face and block is transfinite, faces recombined (hexahedra).
    """

    def __init__(self, xy: Mapping[str, tuple[float, float]], z: Sequence[float],
                 nz: Sequence[int]) -> None:
        self.xy, self.z, self.nz = xy, z, nz
        self.counts: dict[frozenset[str], int] = {}  # cross-section edge -> cells
        self._points: dict[Key, int] = {}
        self._curves: dict[frozenset[Key], tuple[int, Key]] = {}
        self._faces: dict[frozenset[Key], int] = {}

    def count(self, a: str, b: str, n: int) -> None:
        """Put ``n`` cells on the cross-section edge ``a``-``b`` (checked consistent)."""
        edge = frozenset((a, b))
        if self.counts.setdefault(edge, n) != n:  # a bug of the block layout
            raise RuntimeError(f"edge {a}-{b}: {n} cells, and {self.counts[edge]} before")

    def point(self, key: Key) -> int:
        """The gmsh point at ``key``."""
        if key not in self._points:
            x, y = self.xy[key[0]]
            self._points[key] = int(gmsh.model.geo.addPoint(x, y, self.z[key[1]]))
        return self._points[key]

    def _curve(self, a: Key, b: Key) -> int:
        """The straight curve from ``a`` to ``b`` (a negative tag: reversed)."""
        edge = frozenset((a, b))
        if edge not in self._curves:
            tag = int(gmsh.model.geo.addLine(self.point(a), self.point(b)))
            n = (self.nz[min(a[1], b[1])] if a[0] == b[0]
                 else self.counts[frozenset((a[0], b[0]))])
            gmsh.model.geo.mesh.setTransfiniteCurve(tag, n + 1)
            self._curves[edge] = (tag, a)
        tag, start = self._curves[edge]
        return tag if start == a else -tag

    def face(self, corners: Sequence[Key]) -> int:
        """The plane quadrilateral face with these corners (in loop order)."""
        key = frozenset(corners)
        if key not in self._faces:
            geo = gmsh.model.geo
            loop = geo.addCurveLoop([self._curve(a, b) for a, b in
                                     zip(corners, [*corners[1:], corners[0]], strict=True)])
            tag = int(geo.addPlaneSurface([loop]))
            geo.mesh.setTransfiniteSurface(tag, cornerTags=[self.point(c) for c in corners])
            geo.mesh.setRecombine(2, tag)
            self._faces[key] = tag
        return self._faces[key]

    def side(self, a: str, b: str, k: int) -> int:
        """The face over the cross-section edge ``a``-``b`` between planes k, k+1."""
        return self.face([(a, k), (b, k), (b, k + 1), (a, k + 1)])

    def block(self, patch: Patch, k: int) -> int:
        """The hexahedral volume over ``patch`` between the node planes k and k+1."""
        bottom, top = [(c, k) for c in patch], [(c, k + 1) for c in patch]
        faces = [self.face(bottom), self.face(top)]
        faces += [self.side(a, b, k) for a, b in zip(patch, [*patch[1:], patch[0]], strict=True)]
        geo = gmsh.model.geo
        tag = int(geo.addVolume([geo.addSurfaceLoop(faces)]))
        geo.mesh.setTransfiniteVolume(tag, cornerTags=[self.point(c) for c in bottom + top])
        return tag


def _mirror(name: str) -> str:
    return name + "'"


def _section(g: Goda3DGeometry, p: _Plan) -> tuple[dict[str, tuple[float, float]],
                                                   list[tuple[Patch, int, int]],
                                                   list[tuple[Patch, int, int]]]:
    """The cross-section: its points, the mound's and the caisson's patches.

    A patch comes with its cells along its first and second edges (the opposite edges
    have as many).
    """
    half_base, half_crest, half_b = 0.5 * g.base_width, 0.5 * g.crest_width, 0.5 * g.caisson_width
    y1 = g.caisson_base_y
    n1, n2, n4 = p.n1, p.n2, p.n4
    y_split = y1 * n2 / (n1 + n2)
    xy = {"A": (-half_base, 0.0), "B": (-half_crest, 0.0), "C": (-half_crest, y1),
          "pBC": (-half_crest, y_split), "D": (-half_b, 0.0), "Ds": (-half_b, y_split),
          "E": (-half_b, y1)}
    t_ab, t_ca = n1 / (n1 + n4), n4 / (n4 + n2)
    (ax, ay), (bx, by), (cx, cy) = xy["A"], xy["B"], xy["C"]
    xy["pAB"] = (ax + t_ab * (bx - ax), ay + t_ab * (by - ay))
    xy["pCA"] = (cx + t_ca * (ax - cx), cy + t_ca * (ay - cy))
    xy["G"] = tuple(sum(xy[n][i] for n in ("pAB", "pBC", "pCA")) / 3  # type: ignore[assignment]
                    for i in range(2))
    left: list[tuple[Patch, int, int]] = [
        (("A", "pAB", "G", "pCA"), n1, n2),
        (("pAB", "B", "pBC", "G"), n4, n2),
        (("G", "pBC", "C", "pCA"), n4, n1),
        (("B", "D", "Ds", "pBC"), p.side, n2),
        (("pBC", "Ds", "E", "C"), p.side, n1),
    ]
    xy.update({_mirror(n): (-x, y) for n, (x, y) in list(xy.items())})
    right = [((_mirror(a), _mirror(d), _mirror(c), _mirror(b)), nb, na)
             for (a, b, c, d), na, nb in left]
    middle: list[tuple[Patch, int, int]] = [
        (("D", "D'", "Ds'", "Ds"), p.across, n2),
        (("Ds", "Ds'", "E'", "E"), p.across, n1),
    ]
    front = ["E", *(f"F{j}" for j in range(1, len(p.y)))]
    rear = ["E'", *(f"R{j}" for j in range(1, len(p.y)))]
    for j, y in enumerate(p.y[1:], start=1):
        xy[front[j]], xy[rear[j]] = (-half_b, y), (half_b, y)
    caisson = [((front[j], rear[j], rear[j + 1], front[j + 1]), p.across, p.ny[j])
               for j in range(len(p.ny))]
    return xy, left + middle + right, caisson


def gmsh_session() -> AbstractContextManager[None]:
    """A quiet gmsh session with this module's meshing options (see meshes.goda)."""
    return _session(_OPTIONS, _MODEL_NAME)


def build_model(geometry: Goda3DGeometry | None = None, refinement: float = 1.0,
                order: int = 2) -> None:
    """Build and mesh the 3-D model in gmsh's current model (see :func:`generate`).

    gmsh must be initialised (see :func:`gmsh_session`).

    Raises:
        ValueError: For a non-positive refinement or an order other than 1 or 2.

    """
    g = Goda3DGeometry() if geometry is None else geometry
    g.validate()
    _check_mesh_args(refinement, order)
    p = _plan(g, refinement)
    xy, mound, caisson = _section(g, p)
    blocks = _Blocks(xy, p.z, p.nz)
    for (a, b, c, d), n_ab, n_bc in mound + caisson:
        for edge, n in (((a, b), n_ab), ((b, c), n_bc), ((c, d), n_ab), ((d, a), n_bc)):
            blocks.count(*edge, n)
    k0, k1 = p.caisson_z
    last = len(p.nz)
    inside, outside = range(k0, k1), [k for k in range(last) if not k0 <= k < k1]
    volumes = {MOUND: [blocks.block(q, k) for q, _, _ in mound for k in range(last)],
               CAISSON: [blocks.block(q, k) for q, _, _ in caisson for k in inside]}

    def sides(edges: Sequence[tuple[str, str]], planes: Sequence[int]) -> list[int]:
        return [blocks.side(a, b, k) for a, b in edges for k in planes]

    slopes = [("A", "pCA"), ("pCA", "C"), ("E", "C")]
    slopes += [(_mirror(a), _mirror(b)) for a, b in slopes]
    base = [("A", "pAB"), ("pAB", "B"), ("B", "D"), ("D", "D'")]
    base += [(_mirror(a), _mirror(b)) for a, b in base[:3]]
    front = [(q[0], q[3]) for q, _, _ in caisson]
    low, high = g.impact_range
    tol = 1e-9 * g.caisson_height
    struck_y = [low - tol <= xy[a][1] and xy[b][1] <= high + tol for a, b in front]
    p0, p1 = g.impact_z
    struck_z = [p0 - tol <= p.z[k] and p.z[k + 1] <= p1 + tol for k in inside]
    impact = [blocks.side(a, b, k) for (a, b), hit_y in zip(front, struck_y, strict=True)
              for k, hit_z in zip(inside, struck_z, strict=True) if hit_y and hit_z]
    top = caisson[-1][0]
    mid = _nearest(p.z, g.mid_z)
    gauges = {name: _nearest(p.y, y) for name, y in
              ((GAUGE_TOP, g.gauge_top[1]), (GAUGE_BOTTOM, g.gauge_bottom[1]))}
    names = {j: q[0] for j, (q, _, _) in enumerate(caisson)} | {len(p.ny): top[3]}
    entities = {
        **volumes,
        INTERFACE: sides([("E", "E'")], inside),
        BASE: sides(base, range(last)),
        IMPACT: impact,
        CAISSON_FRONT: [s for s in sides(front, inside) if s not in impact],
        CAISSON_REAR: sides([(q[1], q[2]) for q, _, _ in caisson], inside),
        CAISSON_TOP: sides([(top[3], top[2])], inside),
        MOUND_SURFACE: sides(slopes, range(last)) + sides([("E", "E'")], outside),
        CAISSON_SIDES: [blocks.face([(c, k) for c in q]) for q, _, _ in caisson
                        for k in (k0, k1)],
        MOUND_SIDES: [blocks.face([(c, k) for c in q]) for q, _, _ in mound
                      for k in (0, last)],
        **{name: [blocks.point((names[j], mid))] for name, j in gauges.items()},
        CORNER_FRONT: [blocks.point(("E", mid))],
        CORNER_REAR: [blocks.point(("E'", mid))],
    }
    gmsh.model.geo.synchronize()
    for name, (dim, tag) in PHYSICAL_GROUPS.items():
        gmsh.model.addPhysicalGroup(dim, entities[name], tag=tag, name=name)
    gmsh.model.mesh.generate(3)
    if order == 2:
        gmsh.model.mesh.setOrder(2)


def generate(
    path: str | pathlib.Path,
    geometry: Goda3DGeometry | None = None,
    refinement: float = 1.0,
    order: int = 2,
    comm: MPI.Comm | None = None,
) -> pathlib.Path:
    """Mesh the 3-D model and write it as a gmsh 4.1 ``.msh`` file.

    Only rank 0 of ``comm`` builds and writes; every rank returns once the file
    exists. The path of rank 0 is used (and returned) on all ranks.

    Args:
        path: Output file; parent folders are created.
        geometry: Dimensions; Goda's model if None.
        refinement: Element sizes are ``(mound|caisson|across)_element_size /
            refinement`` (cell counts grow about as ``refinement**3``).
        order: Geometric order, 2 (27-node hexahedra) or 1 (8-node).
        comm: MPI communicator; ``MPI.COMM_WORLD`` if None.

    Returns:
        The path of the written file.

    Raises:
        ValueError: For invalid geometry, refinement or order (on all ranks).
        Exception: What gmsh raised on rank 0, on every rank (see
            :func:`breakwater.common.parallel.on_rank_zero`).

    """
    g = Goda3DGeometry() if geometry is None else geometry
    g.validate()
    _check_mesh_args(refinement, order)
    return write_mesh(path, comm, gmsh_session, lambda: build_model(g, refinement, order))
