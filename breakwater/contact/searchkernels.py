"""The compiled search of a general contact pair: grid candidates, projections, cuts.

The same arithmetic as the NumPy references, in loops (:mod:`breakwater.common.jit`):
:func:`project` is :func:`breakwater.contact.projection.project` (the candidates of
:class:`~breakwater.contact.projection.FacetGrid`, in its order, the projection's Newton
run on all of them in lockstep with the same stopping test, the same filters and the
nearest), :func:`nearest_end` is :func:`~breakwater.contact.projection.nearest_end`,
:func:`segment_points` the ``segments`` integration of
:meth:`breakwater.contact.surfacesearch.SurfaceSearch._integration` and
:func:`frozen` its start-of-step projection of the slave nodes. 2-D, facets of 2 or 3
nodes. ``tests/test_contactkernels.py`` checks each against its reference.
"""

from __future__ import annotations

import numpy as np

from breakwater.common.jit import kernel
from breakwater.contact.projection import FACING, STEP_TOL
from breakwater.contact.reachkernels import beyond_reach, mark_near

__all__ = ["beyond_reach", "candidates", "closest_points", "current", "curve_at", "frozen",
           "iterate_state", "mark_near", "near", "nearest_end", "node_normals", "project", "search",
           "segment_points", "shape_values", "slave_normals", "slave_points", "used_candidates",
           "used_project",
           "used_segment_points"]


@kernel
def curve_at(nodes, f, xi):  # type: ignore[no-untyped-def]
    """x(ξ), x'(ξ), x''(ξ) of facet f of ``nodes`` ``(F, nn, 2)`` (real or complex)."""
    if nodes.shape[1] == 2:
        N0, N1 = 0.5 * (1 - xi), 0.5 * (1 + xi)
        x0 = N0 * nodes[f, 0, 0] + N1 * nodes[f, 1, 0]
        x1 = N0 * nodes[f, 0, 1] + N1 * nodes[f, 1, 1]
        dx0 = -0.5 * nodes[f, 0, 0] + 0.5 * nodes[f, 1, 0]
        dx1 = -0.5 * nodes[f, 0, 1] + 0.5 * nodes[f, 1, 1]
        zero = 0.0 * nodes[f, 0, 0]
        return x0, x1, dx0, dx1, zero, zero
    N0, N1, N2 = 0.5 * xi * (xi - 1), 0.5 * xi * (xi + 1), 1 - xi * xi
    D0, D1, D2 = xi - 0.5, xi + 0.5, -2 * xi
    x0 = N0 * nodes[f, 0, 0] + N1 * nodes[f, 1, 0] + N2 * nodes[f, 2, 0]
    x1 = N0 * nodes[f, 0, 1] + N1 * nodes[f, 1, 1] + N2 * nodes[f, 2, 1]
    dx0 = D0 * nodes[f, 0, 0] + D1 * nodes[f, 1, 0] + D2 * nodes[f, 2, 0]
    dx1 = D0 * nodes[f, 0, 1] + D1 * nodes[f, 1, 1] + D2 * nodes[f, 2, 1]
    d2x0 = 1.0 * nodes[f, 0, 0] + 1.0 * nodes[f, 1, 0] + -2.0 * nodes[f, 2, 0]
    d2x1 = 1.0 * nodes[f, 0, 1] + 1.0 * nodes[f, 1, 1] + -2.0 * nodes[f, 2, 1]
    return x0, x1, dx0, dx1, d2x0, d2x1


@kernel
def closest_points(points, point, nodes, cand, xi, iterations, tol):  # type: ignore[no-untyped-def]
    """:func:`~breakwater.contact.projection.closest_point` of the pairs (point[j], cand[j]).

    Newton from ``xi`` (changed in place); each pair stops after a real ``|Δξ|`` below
    ``tol`` (a NaN step does not stop it), or when its clip at ±2 returns the iterate it
    started from (a fixed point: every further iteration is the same).
    """
    m = len(point)
    if m == 0:
        return
    going = np.ones(m, np.bool_)
    left = m
    for _ in range(iterations):
        for j in range(m):
            if not going[j]:
                continue
            x0, x1, dx0, dx1, d2x0, d2x1 = curve_at(nodes, cand[j], xi[j])
            r0, r1 = x0 - points[point[j], 0], x1 - points[point[j], 1]
            f = r0 * dx0 + r1 * dx1
            df = (dx0 * dx0 + dx1 * dx1) + (r0 * d2x0 + r1 * d2x1)
            step = f / df
            old = xi[j]
            xi[j] = xi[j] - step
            real = xi[j].real
            if abs(real) > 2:
                xi[j] = min(max(real, -2.0), 2.0)
            if abs(step.real) < tol or xi[j] == old:
                going[j] = False
                left -= 1
        if left == 0:
            break


@kernel
def chord_start(points, point, nodes, cand):  # type: ignore[no-untyped-def]
    """Newton's start of :func:`closest_points`: the projection onto each facet's chord."""
    xi = np.empty(len(point))
    for j in range(len(point)):
        f, p = cand[j], point[j]
        c0, c1 = nodes[f, 1, 0] - nodes[f, 0, 0], nodes[f, 1, 1] - nodes[f, 0, 1]
        s = (points[p, 0] - nodes[f, 0, 0]) * c0 + (points[p, 1] - nodes[f, 0, 1]) * c1
        xi[j] = 2 * s / (c0 * c0 + c1 * c1) - 1
    return xi


@kernel
def candidates(points, nodes, radius):  # type: ignore[no-untyped-def]
    """:meth:`~breakwater.contact.projection.FacetGrid.candidates` of FacetGrid(nodes, radius).

    Returns:
        (point, facet) index pairs, in the reference's order.
    """
    return used_candidates(points, nodes, radius, np.ones(nodes.shape[0], np.bool_))


@kernel
def used_candidates(points, nodes, radius, use):  # type: ignore[no-untyped-def]
    """:func:`candidates` among the facets ``use`` marks (the grid of those alone)."""
    F, nn = nodes.shape[0], nodes.shape[1]
    m = len(points)
    if F == 0 or m == 0 or not use.any():
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    lo = np.empty((F, 2))
    hi = np.empty((F, 2))
    for f in range(F):
        for d in range(2):
            a, b = nodes[f, 0, d], nodes[f, 0, d]
            for k in range(1, nn):
                a = min(a, nodes[f, k, d])
                b = max(b, nodes[f, k, d])
            lo[f, d], hi[f, d] = a - radius, b + radius
    o0, o1, cell = np.inf, np.inf, 0.0
    for f in range(F):
        if use[f]:
            o0, o1 = min(o0, lo[f, 0]), min(o1, lo[f, 1])
            cell = max(cell, hi[f, 0] - lo[f, 0], hi[f, 1] - lo[f, 1])
    ilo = np.zeros((F, 2), np.int64)
    ihi = np.zeros((F, 2), np.int64)
    for f in range(F):
        if use[f]:
            ilo[f, 0] = np.int64(np.floor((lo[f, 0] - o0) / cell))
            ilo[f, 1] = np.int64(np.floor((lo[f, 1] - o1) / cell))
            ihi[f, 0] = np.int64(np.floor((hi[f, 0] - o0) / cell))
            ihi[f, 1] = np.int64(np.floor((hi[f, 1] - o1) / cell))
    s0, s1 = ihi[:, 0].max() + 1, ihi[:, 1].max() + 1
    # Each facet in the cells its box touches, sorted by (key, facet).
    keys = np.empty(4 * F, np.int64)
    owners = np.empty(4 * F, np.int64)
    c = 0
    for a in range(2):
        for b in range(2):
            for f in range(F):
                if not use[f]:
                    continue
                i0, i1 = ilo[f, 0] + a, ilo[f, 1] + b
                if i0 <= ihi[f, 0] and i1 <= ihi[f, 1]:
                    keys[c] = (i0 + 1) * (s1 + 2) + (i1 + 1)
                    owners[c] = f
                    c += 1
    keys, owners = keys[:c], owners[:c]
    order = np.argsort(keys * F + owners, kind="mergesort")
    keys, owners = keys[order], owners[order]
    count = 0
    first = np.empty(m, np.int64)
    last = np.empty(m, np.int64)
    for p in range(m):
        i0 = np.int64(np.floor((points[p, 0] - o0) / cell))
        i1 = np.int64(np.floor((points[p, 1] - o1) / cell))
        if 0 <= i0 < s0 and 0 <= i1 < s1:
            key = (i0 + 1) * (s1 + 2) + (i1 + 1)
            first[p] = np.searchsorted(keys, key, side="left")
            last[p] = np.searchsorted(keys, key, side="right")
        else:
            first[p], last[p] = 0, 0
        count += last[p] - first[p]
    point = np.empty(count, np.int64)
    facet = np.empty(count, np.int64)
    c = 0
    for p in range(m):
        for i in range(first[p], last[p]):
            point[c], facet[c] = p, owners[i]
            c += 1
    return point, facet


@kernel
def near(points, point, nodes, cand, radius, tol):  # type: ignore[no-untyped-def]
    """:func:`breakwater.contact.projection.near`: the pairs a projection can accept."""
    keep = np.zeros(len(point), np.bool_)
    nn = nodes.shape[1]
    for j in range(len(point)):
        f, p = cand[j], point[j]
        inside = True
        for d in range(2):
            x0, x1 = nodes[f, 0, d], nodes[f, 1, d]
            lo, hi = min(x0, x1), max(x0, x1)
            b, c = 0.5 * abs(x1 - x0), 0.0
            if nn == 3:
                x2 = nodes[f, 2, d]
                lo, hi = min(lo, x2), max(hi, x2)
                c = abs(0.5 * (x0 + x1) - x2)
            margin = radius + c + tol * (b + 3 * c)
            if points[p, d] < lo - margin or points[p, d] > hi + margin:
                inside = False
        keep[j] = inside
    return point[keep], cand[keep]


@kernel
def project(points, nodes, radius, tol):  # type: ignore[no-untyped-def]
    """:func:`breakwater.contact.projection.project` (FacetGrid(nodes, radius) candidates).

    Returns:
        The facet of each point (−1: no projection) and its local coordinate ξ.
    """
    return used_project(points, nodes, radius, tol, np.ones(nodes.shape[0], np.bool_),
                        np.zeros((0, 2)), np.zeros(0))


@kernel
def used_project(points, nodes, radius, tol, use, normals, deepest):  # type: ignore[no-untyped-def]
    """:func:`project` onto the facets ``use`` marks (:func:`used_candidates`).

    The same projections as :func:`project` where the others are beyond the radius of
    every point (:func:`beyond_reach`): each pair's Newton, the filters and the nearest
    (ties: the lowest facet) do not depend on the other candidates. With ``normals``
    (each point's outward unit normal, ``(m, 2)``; none: ``(0, 2)``), only projections
    whose master normal opposes it (:data:`~breakwater.contact.projection.FACING`) and
    where the point lies at most ``deepest[f]`` below facet f (what the pair sees,
    :func:`breakwater.contact.penetration.allowed_depth`).
    """
    m = len(points)
    facet = np.full(m, -1, np.int64)
    out = np.zeros(m)
    point, cand = used_candidates(points, nodes, radius, use)
    point, cand = near(points, point, nodes, cand, radius, tol)
    if len(point) == 0:
        return facet, out
    xi = chord_start(points, point, nodes, cand)
    closest_points(points, point, nodes, cand, xi, 8, STEP_TOL)
    best = np.full(m, np.inf)
    for j in range(len(point)):
        p, f = point[j], cand[j]
        x0, x1, dx0, dx1, _, _ = curve_at(nodes, f, xi[j])
        r0, r1 = x0 - points[p, 0], x1 - points[p, 1]
        dist = r0 * r0 + r1 * r1
        stationary = abs(r0 * dx0 + r1 * dx1) <= 1e-10 * (dx0 * dx0 + dx1 * dx1)
        facing = True
        if normals.shape[0]:  # the master's outward normal (dx1, −dx0)/|dx| opposes
            length = np.sqrt(dx0 * dx0 + dx1 * dx1)
            facing = normals[p, 0] * dx1 - normals[p, 1] * dx0 < FACING * length
            # and the point lies no deeper below the facet than the pair sees
            facing = facing and -(r1 * dx0 - r0 * dx1) <= deepest[f] * length
        if abs(xi[j]) <= 1 + tol and dist <= radius ** 2 and stationary and facing:
            # The nearest; ties: the lowest facet.
            if dist < best[p] or (dist == best[p] and f < facet[p]):
                best[p], facet[p] = dist, f
                out[p] = min(max(xi[j], -1.0), 1.0)
    return facet, out


@kernel
def nearest_end(points, nodes, radius):  # type: ignore[no-untyped-def]
    """:func:`breakwater.contact.projection.nearest_end`: the nearest facet end (ξ = ±1)."""
    m = len(points)
    facet = np.full(m, -1, np.int64)
    out = np.zeros(m)
    point, cand = candidates(points, nodes, radius)
    best = np.full(m, np.inf)
    for j in range(len(point)):
        p, f = point[j], cand[j]
        d = np.empty(2)
        for e in range(2):
            a, b = nodes[f, e, 0] - points[p, 0], nodes[f, e, 1] - points[p, 1]
            d[e] = a ** 2 + b ** 2
        end = 1 if d[1] < d[0] else 0
        dist = d[end]
        if dist <= radius ** 2 and (dist < best[p] or (dist == best[p] and f < facet[p])):
            best[p], facet[p] = dist, f
            out[p] = -1.0 if end == 0 else 1.0
    return facet, out


@kernel
def _jacobian_length(X, f, xi):  # type: ignore[no-untyped-def]
    """|dx/dξ| of facet f of the reference nodes X at ξ."""
    _, _, dx0, dx1, _, _ = curve_at(X, f, xi)
    return np.sqrt(dx0 * dx0 + dx1 * dx1)


@kernel
def segment_points(xs, xm, sX, radius, g, w):  # type: ignore[no-untyped-def]
    """The ``segments`` integration points: (slave facet, ξ, weight) of each.

    Each slave facet (current nodes ``xs``, reference ``sX``) is cut where the master
    facets' vertices (``xm``) project onto it; each segment carries the Gauss rule
    ``(g, w)``; the weight is the reference length.
    """
    return used_segment_points(xs, xm, sX, radius, g, w, np.ones(xm.shape[0], np.bool_))


@kernel
def used_segment_points(xs, xm, sX, radius, g, w, use):  # type: ignore[no-untyped-def]
    """:func:`segment_points` cut by the vertices of the master facets ``use`` marks.

    The same points where the others are beyond the radius of the slave facets
    (:func:`beyond_reach`): their vertices project nowhere.
    """
    n_f = xs.shape[0]
    F = 0
    for f in range(xm.shape[0]):
        if use[f]:
            F += 1
    vertices = np.empty((2 * F, 2))
    c = 0
    for f in range(xm.shape[0]):
        if use[f]:
            for v in range(2):
                vertices[2 * c + v, 0] = xm[f, v, 0]
                vertices[2 * c + v, 1] = xm[f, v, 1]
            c += 1
    if n_f and F:
        on, xi = project(vertices, xs, radius, 1e-9)
    else:
        on, xi = np.full(0, -1, np.int64), np.zeros(0)
    total = 2 * n_f
    for j in range(len(on)):
        if on[j] >= 0 and abs(xi[j]) < 1 - 1e-12:
            total += 1
    fa = np.empty(total, np.int64)
    ca = np.empty(total)
    for f in range(n_f):
        fa[f], ca[f] = f, -1.0
        fa[n_f + f], ca[n_f + f] = f, 1.0
    c = 2 * n_f
    for j in range(len(on)):
        if on[j] >= 0 and abs(xi[j]) < 1 - 1e-12:
            fa[c], ca[c] = on[j], xi[j]
            c += 1
    o1 = np.argsort(ca, kind="mergesort")
    o2 = np.argsort(fa[o1], kind="mergesort")
    order = o1[o2]
    fa, ca = fa[order], ca[order]
    nseg = 0
    for i in range(total - 1):
        if fa[i + 1] == fa[i] and ca[i + 1] - ca[i] > 1e-12:
            nseg += 1
    G = len(g)
    point_facet = np.empty(nseg * G, np.int64)
    xi_s = np.empty(nseg * G)
    weight = np.empty(nseg * G)
    c = 0
    for i in range(total - 1):
        if fa[i + 1] == fa[i] and ca[i + 1] - ca[i] > 1e-12:
            a, b = ca[i], ca[i + 1]
            for k in range(G):
                x = 0.5 * (a + b) + 0.5 * (b - a) * g[k]
                point_facet[c], xi_s[c] = fa[i], x
                weight[c] = 0.5 * (b - a) * w[k] * _jacobian_length(sX, fa[i], x)
                c += 1
    return point_facet, xi_s, weight


@kernel
def shape_values(xi, nn):  # type: ignore[no-untyped-def]
    """The shape functions N at each ξ, ``(m, nn)`` (``projection.shape``'s first)."""
    N = np.empty((len(xi), nn))
    for k in range(len(xi)):
        x = xi[k]
        if nn == 2:
            N[k, 0], N[k, 1] = 0.5 * (1 - x), 0.5 * (1 + x)
        else:
            N[k, 0], N[k, 1], N[k, 2] = 0.5 * x * (x - 1), 0.5 * x * (x + 1), 1 - x * x
    return N


@kernel
def slave_points(xs, point_facet, Ns):  # type: ignore[no-untyped-def]
    """The integration points' current positions ``Σ N_k x_k``, ``(P, 2)``."""
    P, ns = len(point_facet), Ns.shape[1]
    out = np.zeros((P, 2))
    for p in range(P):
        f = point_facet[p]
        for d in range(2):
            s = 0.0
            for k in range(ns):
                s += Ns[p, k] * xs[f, k, d]
            out[p, d] = s
    return out


@kernel
def slave_normals(xs, point_facet, xi_s, outward):  # type: ignore[no-untyped-def]
    """The slave surface's outward unit normal at each integration point, ``(P, 2)``.

    A point presses only on master facets in front of it: at a master surface's convex
    corner (a notch's edge, a step, the end of a ledge) a slave point pressed into both
    sides is nearer, by the penetration, to the side that does not face it, and the
    nearest projection alone alternated between the two from one Newton iterate to the
    next (an L-shaped wall's shear key in its notch: "no static equilibrium").
    """
    P = len(point_facet)
    out = np.empty((P, 2))
    for p in range(P):
        f = point_facet[p]
        _, _, a, b, _, _ = curve_at(xs, f, xi_s[p])
        s = outward[f] / np.sqrt(a * a + b * b)
        out[p, 0], out[p, 1] = b * s, -a * s
    return out


@kernel
def node_normals(xs, node_of, outward, n_nodes):  # type: ignore[no-untyped-def]
    """Each slave node's outward unit normal, the mean of its facets' there, ``(K, 2)``."""
    out = np.zeros((n_nodes, 2))
    for f in range(xs.shape[0]):
        for a in range(xs.shape[1]):
            xi = -1.0 if a == 0 else (1.0 if a == 1 else 0.0)
            _, _, dx0, dx1, _, _ = curve_at(xs, f, xi)
            s = outward[f] / np.sqrt(dx0 * dx0 + dx1 * dx1)
            out[node_of[f, a], 0] += dx1 * s
            out[node_of[f, a], 1] -= dx0 * s
    for k in range(n_nodes):
        length = np.sqrt(out[k, 0] ** 2 + out[k, 1] ** 2)
        if length > 0:
            out[k, 0], out[k, 1] = out[k, 0] / length, out[k, 1] / length
    return out


@kernel
def frozen(points, xm, surface, radius, normals, deepest):  # type: ignore[no-untyped-def]
    """The slave nodes' start-of-step projection (``SurfaceSearch._frozen``).

    Args:
        points: The slave nodes' positions.
        xm: The master facets' nodes (current).
        surface: Where the tangent is taken (the current or the reference nodes).
        radius: The search radius.
        normals: The nodes' outward normals (:func:`node_normals`; ``(0, 2)``: any
            facet) and
        deepest: the master facets' depths the pair sees, as in :func:`search`: a node
            past a master's corner took the facet round it (a block sliding over the
            end of a base whose end face was in the master surface: its friction
            along that face, the resultant 0.45 μN).

    Returns:
        The master facet (−1: none; a node with no projection takes the nearest end),
        the shape functions at ξ̄₀, the unit tangent there and whether it is a
        projection.
    """
    facet, xi = used_project(points, xm, radius, 1e-9, np.ones(xm.shape[0], np.bool_),
                             normals, deepest)
    projected = facet >= 0
    m = len(points)
    nb = m - projected.sum()
    if nb:
        beyond = np.flatnonzero(~projected)
        f2, x2 = nearest_end(points[beyond], xm, radius)
        for j in range(nb):
            facet[beyond[j]], xi[beyond[j]] = f2[j], x2[j]
    N0 = shape_values(xi, xm.shape[1])
    t0 = np.zeros((m, 2))
    for k in range(m):
        if len(surface):
            _, _, a, b, _, _ = curve_at(surface, max(facet[k], 0), xi[k])
            s = np.sqrt(a * a + b * b)
            t0[k, 0], t0[k, 1] = a / s, b / s
    return facet, N0, t0, projected


@kernel
def current(X, pos, u):  # type: ignore[no-untyped-def]
    """The facets' (3-D: faces') current nodes ``X + u[pos]`` (position −1: u's trailing entry)."""
    out = np.empty(X.shape)
    for f in range(X.shape[0]):
        for a in range(X.shape[1]):
            for d in range(X.shape[2]):
                out[f, a, d] = X[f, a, d] + u[pos[f, a, d]]
    return out


@kernel
def iterate_state(u, v, a, y, dt, c_a, c_u, c_v):  # type: ignore[no-untyped-def]
    """u₁ and v₁ of the Newton iterate Δa = y (compiled; a trailing 0 appended to y).

    GN22's update (:func:`breakwater.stepping.gn22.gn22_update`), its operations in its
    order, so bit for bit NumPy's ``u + (dt v + c_a a + c_u Δa)`` and
    ``v + (dt a + c_v Δa)``: one pass instead of a dozen array operations.
    """
    n = len(y)
    u1, v1 = np.empty(n + 1), np.empty(n + 1)
    for i in range(n + 1):
        da = y[i] if i < n else 0.0
        u1[i] = u[i] + ((dt * v[i] + c_a * a[i]) + c_u * da)
        v1[i] = v[i] + (dt * a[i] + c_v * da)
    return u1, v1


@kernel
def search(sX, mX, pos_s, pos_m, u1, segments, fixed_facet, fixed_xi, fixed_weight,
           fixed_N, radius, edge, g, w, use, outward, deepest):  # type: ignore[no-untyped-def]
    """A general pair's integration points and their projections at the state u1.

    Args:
        sX: The slave facets' reference nodes.
        mX: The master's (oriented).
        pos_s: The slave's interface positions (−1: Dirichlet).
        pos_m: The master's.
        u1: Displacements at the interface unknowns (a trailing 0).
        segments: Cut the slave facets (:func:`segment_points`); else the fixed points.
        fixed_facet: The fixed points' slave facets.
        fixed_xi: Their ξ.
        fixed_weight: Their weights.
        fixed_N: Their slave shape functions.
        radius: The search radius.
        edge: A projection at ``|ξ̄| ≤ 1 + edge`` is inside its facet.
        g: The Gauss points of a segment.
        w: Their weights.
        use: The master facets the search may be restricted to: it is, where every
            other is beyond the search radius of the slave surface (:func:`beyond_reach`;
            the same points and projections, without the others' grid and cuts).
        outward: Per slave facet, +1 where ``(t_y, −t_x)`` points out of its body, else
            −1: a point projects only onto master facets that face it
            (:func:`slave_normals`, :func:`used_project`).
        deepest: Per master facet, the deepest a point may lie below it and project
            onto it (:func:`breakwater.contact.penetration.allowed_depth`; a step that
            leaves a slave node deeper is cut back).

    Returns:
        Every point's slave facet, position and weight; of those with a projection:
        their index, slave facet, master facet, shape functions, ξ̄ and weight; and
        whether the search was restricted to ``use``.
    """
    xs = current(sX, pos_s, u1)
    xm = current(mX, pos_m, u1)
    restricted = beyond_reach(xs, xm, use, radius, edge)
    if not restricted:
        use = np.ones(xm.shape[0], np.bool_)
    if segments:
        point_facet, xi_s, weight = used_segment_points(xs, xm, sX, radius, g, w, use)
        Ns = shape_values(xi_s, sX.shape[1])
    else:
        point_facet, xi_s, weight, Ns = fixed_facet, fixed_xi, fixed_weight, fixed_N
    points = slave_points(xs, point_facet, Ns)
    normals = slave_normals(xs, point_facet, xi_s, outward)
    facet, xi = used_project(points, xm, radius, edge, use, normals, deepest)
    on = np.flatnonzero(facet >= 0)
    return (point_facet, points, weight, on, point_facet[on], facet[on],
            np.ascontiguousarray(Ns[on]), xi[on], weight[on], restricted)
