"""Segment-to-segment integration points of a 3-D slave surface (mortar segmentation).

The 3-D counterpart of the 2-D pair's segments
(:meth:`breakwater.contact.surfacesearch.SurfaceSearch._integration`,
:func:`breakwater.contact.searchkernels.segment_points`: each slave facet cut where the
master vertices project onto it, Gauss points per segment), not yet used by a pair
(issue 25). It follows the segmentation of Puso & Laursen (2004), "A mortar
segment-to-segment contact method for large deformation solid mechanics", Comput.
Methods Appl. Mech. Engrg. 193, 601-629, on triangles. They project the slave and the
master facet onto a plane through the slave facet's centre along an averaged normal and
intersect the two there; here the plane is the slave triangle's own (the plane of its
corners: for a flat slave face the face itself, so the points need no mapping back):

1. the master triangle's corners are projected onto the plane of the slave triangle's
   corners along its unit normal, and expressed in the slave's reference coordinates
   (ξ, η) (:func:`plane_coordinates`: the orthogonal projection's coordinates in the
   basis of the slave's edges ``x₁ − x₀, x₂ − x₀``);
2. the projected master triangle is clipped against the reference triangle
   (:func:`clip`, Sutherland–Hodgman: both are convex, so their intersection is one
   convex polygon; a vertex within :data:`ON_LINE` of a clipping line is on it);
3. a polygon below ``sliver`` of the slave's reference area is dropped (an edge of the
   master along an edge of the slave leaves a degenerate polygon of round-off area);
4. each polygon is cut into triangles by a fan from its vertices' mean (inside: the
   polygon is convex), and each triangle carries a triangle Gauss rule of ``degree``
   (basix's: positive weights, interior points).

The points are in the slave's reference coordinates, their weights in its reference
area measure (a fully covered slave triangle's sum to ½, its reference area): the
surface weight of a point is its weight times ``|x_ξ × x_η|`` there
(:func:`~breakwater.contact.projection3d.surface`). Each polygon lies over one master
triangle, so the integrand of a flat patch is a polynomial on each (the master's shape
functions at the projection are polynomials in ξ, η there, of their own degree): the
products N_s N̄_m of a contact force's work are of degree 2 on 3-node faces, 4 on flat
6-node faces, and a rule of that degree integrates them exactly: the patch test. For
curved (6-node) faces the segments' edges are the projected chords of the master's, as
for Puso & Laursen's linear segments: a point near one may project onto the
neighbouring master face, so a pair should take each point's master face from its
closest-point projection (:func:`~breakwater.contact.projection3d.project`) and the face
here as the candidate. The arithmetic is real: the segmentation is held
fixed in a linearisation, as the 2-D cuts are (the integrand is continuous across a
segment's edge, so the derivatives of the edges' positions cancel).
"""

from __future__ import annotations

import basix
import numpy as np

from breakwater.contact.projection import FacetGrid

__all__ = ["ON_LINE", "SLIVER", "clip", "integration_points", "plane_coordinates", "rule",
           "segment_points"]

SLIVER = 1e-12
"""A polygon (or one of its triangles) smaller than this fraction of the slave's
reference area is dropped: round-off, ≈ 1e-16 of the area where edges coincide."""

ON_LINE = 1e-12
"""A vertex within this of a clipping line (in the reference coordinates) is on it: kept,
not crossed. Without it, round-off decides: a master corner on a slave edge (nested
meshes, a shared boundary) was kept or replaced by the crossings of its two edges, and a
master edge along a slave edge crossed it at a point anywhere along it: the polygon the
same to round-off, but its vertices, and so its fan (from their mean), not."""


# The reference triangle as half-planes a·(ξ, η) + b ≥ 0.
_HALF_PLANES = ((np.array([1.0, 0.0]), 0.0), (np.array([0.0, 1.0]), 0.0),
                (np.array([-1.0, -1.0]), 1.0))


def rule(degree: int) -> tuple[np.ndarray, np.ndarray]:
    """A Gauss rule on the reference triangle exact for polynomials of ``degree``.

    Returns:
        Points ``(q, 2)`` and weights ``(q,)`` summing to ½ (basix's default rule).
    """
    points, weights = basix.make_quadrature(basix.CellType.triangle, degree)
    return np.asarray(points, float), np.asarray(weights, float)


def plane_coordinates(corners: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Slave reference coordinates of points projected onto the slave's plane.

    The projection along the normal of the plane through the corners, written in the
    basis of the edges ``e₁ = x₁ − x₀, e₂ = x₂ − x₀``: the (ξ, η) minimising
    ``|x₀ + ξ e₁ + η e₂ − p|`` (Gram system, in closed form).

    Args:
        corners: The slave triangle's corners, ``(3, 3)``.
        points: Shape ``(k, 3)``.

    Returns:
        Shape ``(k, 2)``.
    """
    o = corners[0]
    e = np.stack([corners[1] - o, corners[2] - o])
    G = e @ e.T
    r = (points - o) @ e.T
    det = G[0, 0] * G[1, 1] - G[0, 1] * G[1, 0]
    return np.stack([G[1, 1] * r[:, 0] - G[0, 1] * r[:, 1],
                     G[0, 0] * r[:, 1] - G[1, 0] * r[:, 0]], axis=1) / det


def clip(polygon: np.ndarray) -> np.ndarray:
    """A polygon clipped to the reference triangle (Sutherland–Hodgman).

    Args:
        polygon: Its vertices in order (either orientation), ``(v, 2)``.

    Returns:
        The vertices of the part inside, ``(w, 2)`` (``w`` may be 0).
    """
    out = np.asarray(polygon, float)
    for a, b in _HALF_PLANES:
        if not len(out):
            break
        d = out @ a + b
        d[np.abs(d) <= ON_LINE] = 0.0  # on the line: kept, not crossed
        nxt = np.roll(np.arange(len(out)), -1)
        kept = []
        for i, j in enumerate(nxt):
            if d[i] >= 0:
                kept.append(out[i])
            if d[i] * d[j] < 0:  # the edge crosses the line: its crossing point
                kept.append(out[i] + d[i] / (d[i] - d[j]) * (out[j] - out[i]))
        out = np.array(kept).reshape(-1, 2)
    return out


def _area(polygon: np.ndarray) -> float:
    """The (unsigned) area of a polygon ``(v, 2)`` (shoelace)."""
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _normal(corners: np.ndarray) -> np.ndarray:
    """The (unnormalised) normal ``(x₁ − x₀) × (x₂ − x₀)`` of triangles ``(..., 3, 3)``."""
    return np.cross(corners[..., 1, :] - corners[..., 0, :],
                    corners[..., 2, :] - corners[..., 0, :])


def segment_points(slave: np.ndarray, masters: np.ndarray, degree: int = 2,
                   sliver: float = SLIVER, facing: bool = False
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The integration points of one slave triangle over candidate master triangles.

    Args:
        slave: The slave face's corners (its vertices), ``(3, 3)``.
        masters: The candidate master faces' corners, ``(k, 3, 3)``.
        degree: The Gauss rule's degree on each triangle of a polygon (:func:`rule`).
        sliver: Polygons (and their triangles) below this fraction of the slave's
            reference area are dropped.
        facing: Only master faces whose normal ``(x₁ − x₀) × (x₂ − x₀)`` opposes the
            slave's (negative dot product) count.

    Returns:
        Slave reference coordinates ``(q, 2)``, weights ``(q,)`` in the slave's
        reference area measure, and the index in ``masters`` of each point's face.
    """
    g, w = rule(degree)
    xi, weight, which = [], [], []
    masters = np.asarray(masters, float).reshape(-1, 3, 3)
    if facing:
        opposed = np.flatnonzero(_normal(masters) @ _normal(slave) < 0)
    else:
        opposed = np.arange(len(masters))
    limit = sliver * 0.5
    for k in opposed:
        polygon = clip(plane_coordinates(slave, masters[k]))
        if len(polygon) < 3 or _area(polygon) < limit:
            continue
        c = polygon.mean(axis=0)
        nxt = np.roll(polygon, -1, axis=0)
        for v0, v1 in zip(polygon, nxt, strict=True):
            e = np.stack([v0 - c, v1 - c])  # the triangle (c, v0, v1)
            area = 0.5 * abs(e[0, 0] * e[1, 1] - e[0, 1] * e[1, 0])
            if area < limit:
                continue
            xi.append(c + g @ e)
            weight.append(2 * area * w)
            which.append(np.full(len(w), k))
    if not xi:
        return np.zeros((0, 2)), np.zeros(0), np.zeros(0, np.int64)
    return np.concatenate(xi), np.concatenate(weight), np.concatenate(which)


def integration_points(slave: np.ndarray, master: np.ndarray, radius: float,
                       degree: int = 2, sliver: float = SLIVER, facing: bool = False
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The segment-to-segment integration points of a slave surface over a master.

    The candidates of a slave face are the master faces whose bounding boxes come
    within ``radius`` of its own (the master's :class:`FacetGrid` with the radius
    widened by the largest slave box's extent, queried at the slave faces' corners'
    mean, then the boxes' test).

    Args:
        slave: The slave faces' nodes, ``(S, nn, 3)`` (the corners first: 3 or 6 nodes).
        master: The master faces' nodes, ``(M, nn, 3)``.
        radius: The gap up to which faces are paired.
        degree: :func:`segment_points`.
        sliver: :func:`segment_points`.
        facing: :func:`segment_points`.

    Returns:
        Per point: its slave face, its slave reference coordinates ``(q, 2)``, its
        weight (slave reference area measure) and its master face.
    """
    empty = (np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros(0), np.zeros(0, np.int64))
    if not len(slave) or not len(master):
        return empty
    s = np.asarray(slave, float)[:, :3]
    m = np.asarray(master, float)
    lo_s, hi_s = s.min(axis=1), s.max(axis=1)
    lo_m, hi_m = m.min(axis=1), m.max(axis=1)
    extent = float(np.max(hi_s - lo_s))
    grid = FacetGrid(m, radius + extent)
    point, cand = grid.candidates(s.mean(axis=1))
    overlap = np.all((lo_s[point] <= hi_m[cand] + radius)
                     & (lo_m[cand] <= hi_s[point] + radius), axis=1)
    point, cand = point[overlap], cand[overlap]
    out: tuple[list[np.ndarray], ...] = ([], [], [], [])
    bounds = np.searchsorted(point, np.arange(len(s) + 1))  # point is sorted
    for f in range(len(s)):
        mine = cand[bounds[f]:bounds[f + 1]]
        if not len(mine):
            continue
        xi, weight, which = segment_points(s[f], m[mine, :3], degree, sliver, facing)
        for lst, a in zip(out, (np.full(len(weight), f), xi, weight, mine[which]),
                          strict=True):
            lst.append(a)
    if not out[0]:
        return empty
    return (np.concatenate(out[0]), np.concatenate(out[1]), np.concatenate(out[2]),
            np.concatenate(out[3]))
