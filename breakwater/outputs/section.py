"""A plane section through a 3D mesh's vertex fields, for the 2D figures of a 3D run.

The figures of a run (:mod:`breakwater.outputs.figures`) draw contours on a
triangulation of the x-y plane. In 3D they draw them on the section z = const of the
bodies: each cell is split into tetrahedra (a hexahedron into the six of its main
diagonal), each tetrahedron cut by the plane into one or two triangles whose vertices
lie on its edges, with the P1 values interpolated linearly along them (exact for the
P1 fields the figures use).
"""

from __future__ import annotations

import numpy as np

__all__ = ["mid_row", "section"]

# The six tetrahedra of a hexahedron around its diagonal 0-7 (dolfinx's tensor-product
# vertex order: vertex k at (k & 1, k >> 1 & 1, k >> 2 & 1)).
_HEX_TETS = np.array([[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7],
                      [0, 4, 5, 7], [0, 4, 6, 7]])
_EDGES = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]


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
        through vertices takes the cells on its lower side (z below), once.
    """
    tets = cells[:, _HEX_TETS].reshape(-1, 4) if cells.shape[1] == 8 else cells
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
