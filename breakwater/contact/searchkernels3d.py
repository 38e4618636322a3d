"""The compiled 3-D search: projection onto triangular faces and segmentation (issue 25).

The arithmetic of :mod:`breakwater.contact.projection3d` in loops
(:mod:`breakwater.common.jit`), as :mod:`breakwater.contact.searchkernels` is that of
:mod:`breakwater.contact.projection` in 2-D: :func:`candidates` is
:meth:`~breakwater.contact.projection.FacetGrid.candidates` of a grid of the faces (the
same pairs in the same order), :func:`project` is
:func:`breakwater.contact.projection3d.project` (the box filter, the Newton from the flat
start with the same stopping test, the same acceptance and the nearest), and
:func:`segment_points` is :func:`breakwater.contact.clip3d.integration_points` (the same
points in the same order). Faces of 3 or 6 nodes, real arithmetic. Not yet used by a
pair; ``tests/test_projection3d.py`` and ``tests/test_clip3d.py`` check each against its
reference.
"""

from __future__ import annotations

import numpy as np

from breakwater.common.jit import kernel
from breakwater.contact.clip3d import ON_LINE
from breakwater.contact.projection3d import STEP_TOL

__all__ = ["candidates", "closest_points", "face_at", "flat_start", "near", "project",
           "segment_points"]

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
def _margin(nodes, f, d, radius, tol):  # type: ignore[no-untyped-def]
    """:func:`near`'s margin of face f's nodes' box along axis d: the radius and more.

    A quadratic face leaves its nodes' box by at most the sum over its edges of the
    midside node's offset from the chord (each edge's 4 L_a L_b ≤ 1); a projection
    accepted up to ``tol`` outside the triangle a little more.
    """
    linear = abs(nodes[f, 1, d] - nodes[f, 0, d]) + abs(nodes[f, 2, d] - nodes[f, 0, d])
    c = 0.0
    if nodes.shape[1] == 6:
        for a, b, k in ((1, 2, 3), (0, 2, 4), (0, 1, 5)):
            c += abs(nodes[f, k, d] - 0.5 * (nodes[f, a, d] + nodes[f, b, d]))
    return radius + c * (1 + 2 * tol) ** 2 + 2 * tol * linear  # (projection3d.near's sum)


@kernel
def near(points, point, nodes, cand, radius, tol):  # type: ignore[no-untyped-def]
    """:func:`breakwater.contact.projection3d.near`: the pairs a projection can accept."""
    keep = np.zeros(len(point), np.bool_)
    nn = nodes.shape[1]
    for j in range(len(point)):
        f, p = cand[j], point[j]
        ok = True
        for d in range(3):
            lo, hi = nodes[f, 0, d], nodes[f, 0, d]
            for k in range(1, nn):
                lo, hi = min(lo, nodes[f, k, d]), max(hi, nodes[f, k, d])
            margin = _margin(nodes, f, d, radius, tol)
            if points[p, d] < lo - margin or points[p, d] > hi + margin:
                ok = False
        keep[j] = ok
    return point[keep], cand[keep]


RADIUS_GROWTH = 4.0
"""The passes of :func:`project` widen their radius by this factor."""


@kernel
def _project_within(points, nodes, radius, reach, tol):  # type: ignore[no-untyped-def]
    """One pass of :func:`project`: the projections within ``radius``.

    The grid's candidates are those of ``reach`` (≥ radius: the faces' bulge beyond
    their nodes' box added), the box filter and the acceptance use ``radius``.
    """
    m = len(points)
    face = np.full(m, -1, np.int64)
    out = np.zeros((m, 2))
    point, cand = candidates(points, nodes, reach)
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


@kernel
def _scales(nodes, tol):  # type: ignore[no-untyped-def]
    """The shortest of the faces' longest corner edges, and the box filter's widening.

    The widening is :func:`near`'s margin beyond its radius (:func:`_margin`), the
    largest over faces and axes.
    """
    shortest, widen = np.inf, 0.0
    edges = ((1, 2), (0, 2), (0, 1))
    for f in range(nodes.shape[0]):
        longest = 0.0
        for k in range(3):
            a, b = edges[k]
            e = 0.0
            for d in range(3):
                e += (nodes[f, a, d] - nodes[f, b, d]) ** 2
            longest = max(longest, np.sqrt(e))
        shortest = min(shortest, longest)
        for d in range(3):
            widen = max(widen, _margin(nodes, f, d, 0.0, tol))
    return shortest, widen


@kernel
def project(points, nodes, radius, tol):  # type: ignore[no-untyped-def]
    """:func:`breakwater.contact.projection3d.project` (FacetGrid(nodes, radius), 10 steps).

    In passes of a growing radius r, each on the points without a projection yet:
    first the shortest face size, then :data:`RADIUS_GROWTH` times more, and last
    ``radius`` itself (the reference's pass). The result is the reference's: a point's
    nearest projection within r is its nearest within ``radius``, since every face the
    reference accepts within r is a candidate of the pass (the grid's boxes are widened
    by the box filter's own margin beyond r, :func:`_scales`), every face the pass
    accepts is one of the reference's candidates (r and that margin stay within
    ``radius``), and each (point, face) pair's Newton is the same in every pass.

    Where the faces are of one size this is the reference's one pass. On a graded
    surface (the Hertz sphere's block: faces 0.04–0.73 m, the radius the largest) the
    points near the master no longer run Newton on every face within the largest
    face's reach (1.1 million pairs for 7616 points: 2 s a search).

    Returns:
        The face of each point (−1: no projection) and its (ξ, η), ``(m, 2)``.
    """
    m = len(points)
    face = np.full(m, -1, np.int64)
    out = np.zeros((m, 2))
    if m == 0 or nodes.shape[0] == 0:
        return face, out
    shortest, widen = _scales(nodes, tol)
    r = shortest
    left = np.arange(m)
    while len(left):
        # The last pass also where a size is 0, NaN or inf (a collapsed face, a diverged
        # iterate): a growing radius would not reach ``radius`` (the loop never ended).
        last = not (0.0 < r and r + widen < radius < np.inf)
        if last:
            f, o = _project_within(points[left], nodes, radius, radius, tol)
        else:
            f, o = _project_within(points[left], nodes, r, r + widen, tol)
        for j in range(len(left)):
            if f[j] >= 0:
                face[left[j]] = f[j]
                out[left[j], 0], out[left[j], 1] = o[j, 0], o[j, 1]
        if last:
            break
        left = left[f < 0]
        r *= RADIUS_GROWTH
    return face, out


@kernel
def _clip(poly, n):  # type: ignore[no-untyped-def]
    """:func:`breakwater.contact.clip3d.clip` of ``poly[:n]`` (room for 9 vertices)."""
    planes = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (-1.0, -1.0, 1.0))
    out = np.empty((9, 2))
    d = np.empty(9)
    for a0, a1, b in planes:
        if n == 0:
            break
        for i in range(n):
            d[i] = (poly[i, 0] * a0 + poly[i, 1] * a1) + b
            if abs(d[i]) <= ON_LINE:  # on the line: kept, not crossed
                d[i] = 0.0
        c = 0
        for i in range(n):
            j = (i + 1) % n
            if d[i] >= 0:
                out[c, 0], out[c, 1] = poly[i, 0], poly[i, 1]
                c += 1
            if d[i] * d[j] < 0:
                t = d[i] / (d[i] - d[j])
                out[c, 0] = poly[i, 0] + t * (poly[j, 0] - poly[i, 0])
                out[c, 1] = poly[i, 1] + t * (poly[j, 1] - poly[i, 1])
                c += 1
        poly[:c] = out[:c]
        n = c
    return n


@kernel
def _cross(x, f):  # type: ignore[no-untyped-def]
    """(x₁ − x₀) × (x₂ − x₀) of face f of ``x`` ``(F, nn, 3)``."""
    a = x[f, 1] - x[f, 0]
    b = x[f, 2] - x[f, 0]
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


@kernel
def segment_points(slave, master, radius, g, w, sliver, facing):  # type: ignore[no-untyped-def]
    """:func:`breakwater.contact.clip3d.integration_points` with the rule ``(g, w)``.

    Returns:
        Per point (in the reference's order): its slave face, slave reference
        coordinates ``(q, 2)``, weight and master face.
    """
    S, M, nq = slave.shape[0], master.shape[0], len(w)
    if S == 0 or M == 0:
        return (np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros(0), np.zeros(0, np.int64))
    lo_s, hi_s = np.empty((S, 3)), np.empty((S, 3))
    centre = np.empty((S, 3))
    extent = 0.0
    for f in range(S):
        for d in range(3):
            a, b, c = slave[f, 0, d], slave[f, 1, d], slave[f, 2, d]
            lo_s[f, d], hi_s[f, d] = min(a, b, c), max(a, b, c)
            centre[f, d] = (a + b + c) / 3
            extent = max(extent, hi_s[f, d] - lo_s[f, d])
    lo_m, hi_m = np.empty((M, 3)), np.empty((M, 3))
    for f in range(M):
        for d in range(3):
            lo_m[f, d], hi_m[f, d] = master[f, 0, d], master[f, 0, d]
            for k in range(1, master.shape[1]):
                lo_m[f, d] = min(lo_m[f, d], master[f, k, d])
                hi_m[f, d] = max(hi_m[f, d], master[f, k, d])
    point, cand = candidates(centre, master, radius + extent)
    size = len(point) * 6 * nq
    face, m_face = np.empty(size, np.int64), np.empty(size, np.int64)
    xi, weight = np.empty((size, 2)), np.empty(size)
    limit = sliver * 0.5
    poly = np.empty((9, 2))
    q = 0
    for j in range(len(point)):
        s, m = point[j], cand[j]
        apart = False
        for d in range(3):
            if lo_s[s, d] > hi_m[m, d] + radius or lo_m[m, d] > hi_s[s, d] + radius:
                apart = True
        if apart:
            continue
        n_s = _cross(slave, s)
        if facing:
            n_m = _cross(master, m)
            if n_m[0] * n_s[0] + n_m[1] * n_s[1] + n_m[2] * n_s[2] >= 0:
                continue
        # plane_coordinates of the master's corners.
        g00, g01, g11 = 0.0, 0.0, 0.0
        for d in range(3):
            e0, e1 = slave[s, 1, d] - slave[s, 0, d], slave[s, 2, d] - slave[s, 0, d]
            g00, g01, g11 = g00 + e0 * e0, g01 + e0 * e1, g11 + e1 * e1
        det = g00 * g11 - g01 * g01
        for k in range(3):
            r0, r1 = 0.0, 0.0
            for d in range(3):
                e0, e1 = slave[s, 1, d] - slave[s, 0, d], slave[s, 2, d] - slave[s, 0, d]
                r0 += (master[m, k, d] - slave[s, 0, d]) * e0
                r1 += (master[m, k, d] - slave[s, 0, d]) * e1
            poly[k, 0] = (g11 * r0 - g01 * r1) / det
            poly[k, 1] = (g00 * r1 - g01 * r0) / det
        n = _clip(poly, 3)
        if n < 3:
            continue
        area, c0, c1 = 0.0, 0.0, 0.0
        for i in range(n):
            i1 = (i + 1) % n
            area += poly[i, 0] * poly[i1, 1] - poly[i, 1] * poly[i1, 0]
            c0, c1 = c0 + poly[i, 0], c1 + poly[i, 1]
        if 0.5 * abs(area) < limit:
            continue
        c0, c1 = c0 / n, c1 / n
        for i in range(n):
            i1 = (i + 1) % n
            a0, a1 = poly[i, 0] - c0, poly[i, 1] - c1
            b0, b1 = poly[i1, 0] - c0, poly[i1, 1] - c1
            tri = 0.5 * abs(a0 * b1 - a1 * b0)
            if tri < limit:
                continue
            for k in range(nq):
                face[q], m_face[q] = s, m
                xi[q, 0] = c0 + (g[k, 0] * a0 + g[k, 1] * b0)
                xi[q, 1] = c1 + (g[k, 0] * a1 + g[k, 1] * b1)
                weight[q] = 2 * tri * w[k]
                q += 1
    return face[:q], xi[:q], weight[:q], m_face[:q]
