"""The compiled closest-point projection onto triangular faces (3-D, issue 25).

The arithmetic of :mod:`breakwater.contact.projection3d` in loops
(:mod:`breakwater.common.jit`), as :mod:`breakwater.contact.searchkernels` is that of
:mod:`breakwater.contact.projection` in 2-D: :func:`candidates` is
:meth:`~breakwater.contact.projection.FacetGrid.candidates` of a grid of the faces (the
same pairs in the same order), :func:`project` is
:func:`breakwater.contact.projection3d.project` (the box filter, the Newton from the flat
start with the same stopping test, the same acceptance and the nearest). Faces of 3 or 6
nodes. Not yet used by a pair; ``tests/test_searchkernels3d.py`` checks each against its
reference.
"""

from __future__ import annotations

import numpy as np

from breakwater.common.jit import kernel
from breakwater.contact.projection3d import STEP_TOL

__all__ = ["candidates", "closest_points", "face_at", "flat_start", "near", "project"]

# Newton keeps each coordinate of its iterate in [−1, 2] (projection3d._LO, _HI).
_LO, _HI = -1.0, 2.0


@kernel
def face_at(nodes, f, xi, eta):  # type: ignore[no-untyped-def]
    """x, x_ξ, x_η ``(3,)`` each and x_ξξ, x_ξη, x_ηη ``(3,)`` each of face f at (ξ, η)."""
    nn = nodes.shape[1]
    L = (1 - xi - eta, xi, eta)
    DL = ((-1.0, -1.0), (1.0, 0.0), (0.0, 1.0))
    x = np.zeros(3)
    dx = np.zeros((2, 3))
    d2x = np.zeros((3, 3))
    for k in range(3):
        if nn == 3:
            n, d0, d1 = L[k], DL[k][0], DL[k][1]
            s00, s01, s11 = 0.0, 0.0, 0.0
        else:
            n = L[k] * (2 * L[k] - 1)
            d0, d1 = (4 * L[k] - 1) * DL[k][0], (4 * L[k] - 1) * DL[k][1]
            s00, s01, s11 = (4 * DL[k][0] * DL[k][0], 4 * DL[k][0] * DL[k][1],
                             4 * DL[k][1] * DL[k][1])
        for d in range(3):
            x[d] += n * nodes[f, k, d]
            dx[0, d] += d0 * nodes[f, k, d]
            dx[1, d] += d1 * nodes[f, k, d]
            d2x[0, d] += s00 * nodes[f, k, d]
            d2x[1, d] += s01 * nodes[f, k, d]
            d2x[2, d] += s11 * nodes[f, k, d]
    if nn == 6:
        edges = ((1, 2), (0, 2), (0, 1))
        for k in range(3):
            a, b = edges[k]
            n = 4 * L[a] * L[b]
            d0 = 4 * (L[b] * DL[a][0] + L[a] * DL[b][0])
            d1 = 4 * (L[b] * DL[a][1] + L[a] * DL[b][1])
            s00 = 4 * (DL[a][0] * DL[b][0] + DL[a][0] * DL[b][0])
            s01 = 4 * (DL[a][0] * DL[b][1] + DL[a][1] * DL[b][0])
            s11 = 4 * (DL[a][1] * DL[b][1] + DL[a][1] * DL[b][1])
            for d in range(3):
                y = nodes[f, 3 + k, d]
                x[d] += n * y
                dx[0, d] += d0 * y
                dx[1, d] += d1 * y
                d2x[0, d] += s00 * y
                d2x[1, d] += s01 * y
                d2x[2, d] += s11 * y
    return x, dx, d2x


@kernel
def flat_start(points, point, nodes, cand):  # type: ignore[no-untyped-def]
    """Newton's start: each point's foot on the plane of its face's vertices, ``(m, 2)``."""
    xi = np.empty((len(point), 2))
    for j in range(len(point)):
        f, p = cand[j], point[j]
        g00, g01, g11, r0, r1 = 0.0, 0.0, 0.0, 0.0, 0.0
        for d in range(3):
            e0 = nodes[f, 1, d] - nodes[f, 0, d]
            e1 = nodes[f, 2, d] - nodes[f, 0, d]
            q = points[p, d] - nodes[f, 0, d]
            g00 += e0 * e0
            g01 += e0 * e1
            g11 += e1 * e1
            r0 += e0 * q
            r1 += e1 * q
        det = g00 * g11 - g01 * g01
        xi[j, 0] = (g11 * r0 - g01 * r1) / det
        xi[j, 1] = (g00 * r1 - g01 * r0) / det
    return xi


@kernel
def closest_points(points, point, nodes, cand, xi, iterations, tol):  # type: ignore[no-untyped-def]
    """:func:`~breakwater.contact.projection3d.closest_point` of the pairs (point[j], cand[j]).

    Newton from ``xi`` ``(m, 2)`` (changed in place); each pair stops after a real step
    below ``tol`` in both coordinates, or when its clip to [−1, 2] returns the iterate
    it started from.
    """
    m = len(point)
    going = np.ones(m, np.bool_)
    left = m
    for _ in range(iterations):
        if left == 0:
            break
        for j in range(m):
            if not going[j]:
                continue
            x, dx, d2x = face_at(nodes, cand[j], xi[j, 0], xi[j, 1])
            f0, f1, j00, j01, j11 = 0.0, 0.0, 0.0, 0.0, 0.0
            for d in range(3):
                r = x[d] - points[point[j], d]
                f0 += r * dx[0, d]
                f1 += r * dx[1, d]
                j00 += dx[0, d] * dx[0, d] + r * d2x[0, d]
                j01 += dx[0, d] * dx[1, d] + r * d2x[1, d]
                j11 += dx[1, d] * dx[1, d] + r * d2x[2, d]
            det = j00 * j11 - j01 * j01
            s0 = (j11 * f0 - j01 * f1) / det
            s1 = (j00 * f1 - j01 * f0) / det
            o0, o1 = xi[j, 0], xi[j, 1]
            n0, n1 = o0 - s0, o1 - s1
            if n0 < _LO or n0 > _HI:
                n0 = min(max(n0, _LO), _HI)
            if n1 < _LO or n1 > _HI:
                n1 = min(max(n1, _LO), _HI)
            xi[j, 0], xi[j, 1] = n0, n1
            if (abs(s0) < tol and abs(s1) < tol) or (n0 == o0 and n1 == o1):
                going[j] = False
                left -= 1


@kernel
def candidates(points, nodes, radius):  # type: ignore[no-untyped-def]
    """FacetGrid(nodes, radius).candidates(points): (point, face) pairs in its order."""
    F, nn, m = nodes.shape[0], nodes.shape[1], len(points)
    if F == 0 or m == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    lo = np.empty((F, 3))
    hi = np.empty((F, 3))
    for f in range(F):
        for d in range(3):
            a, b = nodes[f, 0, d], nodes[f, 0, d]
            for k in range(1, nn):
                a = min(a, nodes[f, k, d])
                b = max(b, nodes[f, k, d])
            lo[f, d], hi[f, d] = a - radius, b + radius
    origin = np.empty(3)
    cell = 0.0
    for d in range(3):
        origin[d] = lo[:, d].min()
        cell = max(cell, (hi[:, d] - lo[:, d]).max())
    ilo = np.empty((F, 3), np.int64)
    ihi = np.empty((F, 3), np.int64)
    for f in range(F):
        for d in range(3):
            ilo[f, d] = np.int64(np.floor((lo[f, d] - origin[d]) / cell))
            ihi[f, d] = np.int64(np.floor((hi[f, d] - origin[d]) / cell))
    s = np.empty(3, np.int64)
    for d in range(3):
        s[d] = ihi[:, d].max() + 1
    keys = np.empty(8 * F, np.int64)
    owners = np.empty(8 * F, np.int64)
    c = 0
    for a in range(2):
        for b in range(2):
            for e in range(2):
                for f in range(F):
                    i0, i1, i2 = ilo[f, 0] + a, ilo[f, 1] + b, ilo[f, 2] + e
                    if i0 <= ihi[f, 0] and i1 <= ihi[f, 1] and i2 <= ihi[f, 2]:
                        keys[c] = ((i0 + 1) * (s[1] + 2) + (i1 + 1)) * (s[2] + 2) + (i2 + 1)
                        owners[c] = f
                        c += 1
    keys, owners = keys[:c], owners[:c]
    order = np.argsort(keys * F + owners, kind="mergesort")
    keys, owners = keys[order], owners[order]
    first = np.zeros(m, np.int64)
    last = np.zeros(m, np.int64)
    count = 0
    for p in range(m):
        i0 = np.int64(np.floor((points[p, 0] - origin[0]) / cell))
        i1 = np.int64(np.floor((points[p, 1] - origin[1]) / cell))
        i2 = np.int64(np.floor((points[p, 2] - origin[2]) / cell))
        if 0 <= i0 < s[0] and 0 <= i1 < s[1] and 0 <= i2 < s[2]:
            key = ((i0 + 1) * (s[1] + 2) + (i1 + 1)) * (s[2] + 2) + (i2 + 1)
            first[p] = np.searchsorted(keys, key, side="left")
            last[p] = np.searchsorted(keys, key, side="right")
        count += last[p] - first[p]
    point = np.empty(count, np.int64)
    face = np.empty(count, np.int64)
    c = 0
    for p in range(m):
        for i in range(first[p], last[p]):
            point[c], face[c] = p, owners[i]
            c += 1
    return point, face


@kernel
def near(points, point, nodes, cand, radius, tol):  # type: ignore[no-untyped-def]
    """:func:`breakwater.contact.projection3d.near`: the pairs a projection can accept."""
    keep = np.zeros(len(point), np.bool_)
    nn = nodes.shape[1]
    edges = ((1, 2), (0, 2), (0, 1))
    for j in range(len(point)):
        f, p = cand[j], point[j]
        ok = True
        for d in range(3):
            lo, hi = nodes[f, 0, d], nodes[f, 0, d]
            for k in range(1, nn):
                lo, hi = min(lo, nodes[f, k, d]), max(hi, nodes[f, k, d])
            linear = abs(nodes[f, 1, d] - nodes[f, 0, d]) + abs(nodes[f, 2, d] - nodes[f, 0, d])
            c = 0.0
            if nn == 6:
                for k in range(3):
                    a, b = edges[k]
                    c += abs(nodes[f, 3 + k, d] - 0.5 * (nodes[f, a, d] + nodes[f, b, d]))
            margin = radius + c * (1 + 2 * tol) ** 2 + 2 * tol * linear
            if points[p, d] < lo - margin or points[p, d] > hi + margin:
                ok = False
        keep[j] = ok
    return point[keep], cand[keep]


@kernel
def project(points, nodes, radius, tol):  # type: ignore[no-untyped-def]
    """:func:`breakwater.contact.projection3d.project` (FacetGrid(nodes, radius), 10 steps).

    Returns:
        The face of each point (−1: no projection) and its (ξ, η), ``(m, 2)``.
    """
    m = len(points)
    face = np.full(m, -1, np.int64)
    out = np.zeros((m, 2))
    point, cand = candidates(points, nodes, radius)
    point, cand = near(points, point, nodes, cand, radius, tol)
    if len(point) == 0:
        return face, out
    xi = flat_start(points, point, nodes, cand)
    closest_points(points, point, nodes, cand, xi, 10, STEP_TOL)
    best = np.full(m, np.inf)
    for j in range(len(point)):
        p, f = point[j], cand[j]
        x, dx, _ = face_at(nodes, f, xi[j, 0], xi[j, 1])
        dist, f0, f1, scale = 0.0, 0.0, 0.0, 0.0
        for d in range(3):
            r = x[d] - points[p, d]
            dist += r * r
            f0 += r * dx[0, d]
            f1 += r * dx[1, d]
            scale += dx[0, d] * dx[0, d] + dx[1, d] * dx[1, d]
        stationary = abs(f0) <= 1e-10 * scale and abs(f1) <= 1e-10 * scale
        a, b = xi[j, 0], xi[j, 1]
        inside = a >= -tol and b >= -tol and a + b <= 1 + tol
        if inside and dist <= radius ** 2 and stationary:
            if dist < best[p] or (dist == best[p] and f < face[p]):  # ties: the lowest face
                best[p], face[p] = dist, f
                a, b = max(a, 0.0), max(b, 0.0)
                over = max(a + b - 1, 0.0)
                out[p, 0], out[p, 1] = a - 0.5 * over, b - 0.5 * over
    return face, out
