"""A plane section through a 3D mesh's vertex fields, for the 2D figures of a 3D run.

The figures of a run (:mod:`breakwater.outputs.figures`) draw contours on a
triangulation of the x-y plane. In 3D they draw them on the section z = const of the
bodies. A tetrahedron is cut by the plane into one or two triangles whose vertices lie
on its edges, the P1 values interpolated linearly along them (exact). A hexahedron is
cut along its twelve edges, along which its Q1 values are linear (exact there): the
crossings, ordered around their centroid, make a polygon fanned around that centroid,
which takes the crossings' mean (a box's bilinear section exactly: its centre value).
Splitting the hexahedron into the six tetrahedra of a diagonal instead was not exact
for Q1 between vertex planes and not symmetric: on a block centred on its base
(mirror-symmetric), the section through the middle of a layer of cells had its
vertical stress 2.1 kPa (20 % of the largest) off the mirror image (measured).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from mpi4py import MPI

if TYPE_CHECKING:
    from breakwater.model.model import ContactModel

__all__ = ["mid_row", "section", "section_plane"]

# The six tetrahedra of a hexahedron around its diagonal 0-7 (dolfinx's tensor-product
# vertex order: vertex k at (k & 1, k >> 1 & 1, k >> 2 & 1)): a test's decomposition.
_HEX_TETS = np.array([[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7],
                      [0, 4, 5, 7], [0, 4, 6, 7]])
_EDGES = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
# The twelve edges of a hexahedron: the vertex pairs whose indices differ in one bit.
_HEX_EDGES = [(a, a | bit) for bit in (1, 2, 4) for a in range(8) if not a & bit]


def section(x: np.ndarray, cells: np.ndarray, values: dict[str, np.ndarray], z: float
            ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """The section z = ``z`` of tetrahedra (4 vertices) or hexahedra (8) with vertex values.

    Args:
        x: Vertex coordinates, ``(n, 3)``.
        cells: Vertex indices per cell, ``(m, 4)`` or ``(m, 8)``.
        values: Vertex values, each ``(n,)``.
        z: The plane's z.

    Returns:
        ``(xy, triangles, values)``: the section's points ``(p, 2)`` (x, y), its triangles
        ``(t, 3)`` (those of zero area left out) and the values at its points. A plane
        through vertices (to 1e-9 of the mesh's extent: gmsh's node rows differ by
        ulps between volumes) takes the cells on its lower side (z below), once.
    """
    tol = 1e-9 * float(np.ptp(x, axis=0).max()) if len(x) else 0.0
    x = x.copy()
    x[np.abs(x[:, 2] - z) <= tol, 2] = z
    if cells.shape[1] == 8:
        return _hexahedra(x, cells, values, z)
    tets = cells
    d = x[tets, 2] - z  # (t, 4) signed distances
    above = d >= 0
    count = above.sum(axis=1)
    cut = (count > 0) & (count < 4)
    tets, d, above = tets[cut], d[cut], above[cut]
    points: list[tuple[int, int, float]] = []  # each edge point: its edge's vertices, t
    triangles = []
    n = 0
    for tet, dist, up in zip(tets, d, above, strict=True):
        crossing = [(a, b) for a, b in _EDGES if up[a] != up[b]]
        w = [dist[a] / (dist[a] - dist[b]) for a, b in crossing]
        points.extend((tet[a], tet[b], t) for (a, b), t in zip(crossing, w, strict=True))
        if len(crossing) == 3:
            triangles.append([n, n + 1, n + 2])
        else:  # 4 points: a quadrilateral; its edges pair the crossings sharing a vertex
            # The crossings in order around the quadrilateral: (0-a, 0-b, ...) share vertex
            # 0 or not; order them so that consecutive ones share a vertex of the tet.
            e = crossing
            order = [0]
            rest = [1, 2, 3]
            while rest:
                last = e[order[-1]]
                nxt = next(k for k in rest if set(e[k]) & set(last))
                order.append(nxt)
                rest.remove(nxt)
            q = [n + k for k in order]
            triangles += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
        n += len(crossing)
    if not points:
        return np.zeros((0, 2)), np.zeros((0, 3), np.int64), {k: np.zeros(0) for k in values}
    a, b, t = (np.array(c) for c in zip(*points, strict=True))
    a, b = a.astype(np.int64), b.astype(np.int64)
    xy = (1 - t)[:, None] * x[a, :2] + t[:, None] * x[b, :2]
    out = {k: (1 - t) * v[a] + t * v[b] for k, v in values.items()}
    tri = np.array(triangles, dtype=np.int64)
    p = xy[tri]
    area = 0.5 * np.abs((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
                        - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
    scale = max(float(np.ptp(xy, axis=0).max()), 1e-300)
    return xy, tri[area > 1e-12 * scale**2], out


def _hexahedra(x: np.ndarray, cells: np.ndarray, values: dict[str, np.ndarray], z: float
               ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """:func:`section` of hexahedra: each cut along its edges (module docstring)."""
    d = x[cells, 2] - z
    above = d >= 0
    count = above.sum(axis=1)
    cut = (count > 0) & (count < 8)
    xy_parts: list[np.ndarray] = []
    value_parts: dict[str, list[np.ndarray]] = {k: [] for k in values}
    triangles = []
    n = 0
    for cell, dist, up in zip(cells[cut], d[cut], above[cut], strict=True):
        a = np.array([cell[i] for i, j in _HEX_EDGES if up[i] != up[j]])
        b = np.array([cell[j] for i, j in _HEX_EDGES if up[i] != up[j]])
        t = np.array([dist[i] / (dist[i] - dist[j]) for i, j in _HEX_EDGES if up[i] != up[j]])
        xy = (1 - t)[:, None] * x[a, :2] + t[:, None] * x[b, :2]
        c = xy.mean(axis=0)
        order = np.argsort(np.arctan2(xy[:, 1] - c[1], xy[:, 0] - c[0]), kind="stable")
        k = len(order)
        xy_parts += [xy[order], c[None, :]]
        for key, v in values.items():
            w = ((1 - t) * v[a] + t * v[b])[order]
            value_parts[key] += [w, np.array([w.mean()])]
        triangles += [[n + i, n + (i + 1) % k, n + k] for i in range(k)]
        n += k + 1
    if not triangles:
        return np.zeros((0, 2)), np.zeros((0, 3), np.int64), {k: np.zeros(0) for k in values}
    xy = np.vstack(xy_parts)
    tri = np.array(triangles, dtype=np.int64)
    p = xy[tri]
    area = 0.5 * np.abs((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
                        - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
    scale = max(float(np.ptp(xy, axis=0).max()), 1e-300)
    return xy, tri[area > 1e-12 * scale**2], {k: np.concatenate(v)
                                              for k, v in value_parts.items()}


def mid_row(x: np.ndarray) -> np.ndarray:
    """Mask of the 3D interface nodes on the row nearest the interface's mid z.

    The nodes whose z is that of the node nearest (z_min + z_max)/2, to 1e-9 of the
    interface's extent (a structured interface's node row; on an unstructured one the
    nodes at that exact z). 2D nodes: all of them.
    """
    if x.shape[1] < 3 or len(x) == 0:
        return np.ones(len(x), bool)
    z = x[:, 2]
    nearest = z[np.argmin(np.abs(z - 0.5 * (z.min() + z.max())))]
    return np.abs(z - nearest) <= 1e-9 * max(float(np.ptp(x, axis=0).max()), 1e-300)


def section_plane(model: ContactModel) -> float:
    """The z of a 3D model's figure section (collective).

    The row of the first contact pair's interface nodes nearest the interface's mid z
    (the row of the static pressure's figure, :func:`mid_row`), so that the section
    cuts the pair's two bodies where the pressure is drawn, wherever they lie across
    the model; without a pair, the model's mid-plane. (The model's mid-plane missed a
    block standing off the middle of its base: a run's figures then ended in a
    traceback.)
    """
    import dolfinx

    from breakwater.model.mesh import group_tag

    msh, comm = model.mesh, model.comm
    z = msh.geometry.x[:, 2]
    if model.pairs:
        tags = model.mesh_data.facet_tags
        assert tags is not None
        fdim = msh.topology.dim - 1
        facets = tags.find(group_tag(model.mesh_data, model.pairs[0].spec.interface, fdim))
        nodes = dolfinx.mesh.entities_to_geometry(msh, fdim, facets)
        z = z[np.unique(nodes.ravel())] if nodes.size else z[:0]
    lo = comm.allreduce(float(z.min()) if len(z) else np.inf, op=MPI.MIN)
    hi = comm.allreduce(float(z.max()) if len(z) else -np.inf, op=MPI.MAX)
    mid = 0.5 * (lo + hi)
    near = float(z[np.argmin(np.abs(z - mid))]) if len(z) else np.inf
    distance = comm.allreduce((abs(near - mid), near) if len(z) else (np.inf, np.inf),
                              op=MPI.MIN)
    return float(distance[1])
