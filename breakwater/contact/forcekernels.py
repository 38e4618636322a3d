"""The compiled forces of a general contact pair: f_c and its Jacobian.

The arithmetic of the NumPy references (:mod:`breakwater.contact.pointkernels`, the
friction of :class:`breakwater.contact.general.SurfaceForces`) in loops
(:mod:`breakwater.common.jit`): :func:`point` is the point kernel of
:func:`~breakwater.contact.pointkernels.normal_forces` (the projection's two Newton
steps, the master's normal, the penalty traction; real or complex), :func:`residual`
the normal part of ``vector()`` with the slave nodes' normal forces λ,
:func:`friction` its friction part, :func:`jacobian` the dense ∂f_c/∂Δa of
``matrix()`` (:func:`point_tangents`: the derivatives of :func:`point` that the
reference takes by complex steps, in forward mode, summed in the reference's order),
:func:`left_product` ``X @ J`` from J's structure (the pair's slip guard, its
pre-check, is :func:`breakwater.contact.guardkernels.slip_guard`). The interface arrays
carry a trailing entry (position −1: Dirichlet, 0). ``tests/test_contactkernels.py``
checks each against its reference.
"""

from __future__ import annotations

import numpy as np

from breakwater.common.jit import kernel
from breakwater.contact.searchkernels import curve_at

__all__ = ["add_friction", "friction", "friction_round_off", "jacobian", "law_line",
           "left_product", "local_nodes", "point", "point_tangents", "residual", "tangential_slip"]

H = 1e-20  # the complex step (pointkernels.H)


@kernel
def point(Ns, xi0, xs, xm, ref, small, eps, g0, w, forces, shares, nodal):  # type: ignore[no-untyped-def]
    """One contact point: its nodal forces and its shares of the slave nodes' forces.

    Args:
        Ns: The slave shape functions at the point ``(ns,)``.
        xi0: The projection's ξ̄ (Newton's start: two steps, as ``refine = 2``).
        xs: The slave facet's nodes ``(ns, 2)`` (real or complex).
        xm: The master facet's nodes ``(nm, 2)`` (oriented).
        ref: Its reference nodes: the normal's facet if ``small``.
        small: Small rotations (the reference normal).
        eps: ε_n.
        g0: The initial gap.
        w: The point's weight.
        forces: Out, ``(ns + nm, 2)``: ``−N_s t w`` then ``N̄ t w``.
        shares: Out, ``(ns,)``: ``p w N_s`` (as ``nodal_normal_forces`` if ``nodal``,
            else as ``normal_and_shares``).
        nodal: Which of the two roundings of the shares.

    Returns:
        g_n and ξ̄ (real parts decide nothing here but the active set).
    """
    ns, nm = len(Ns), xm.shape[0]
    x0 = 0.0 * xs[0, 0]
    x1 = 0.0 * xs[0, 0]
    for k in range(ns):
        x0 += Ns[k] * xs[k, 0]
        x1 += Ns[k] * xs[k, 1]
    nodes = xm.reshape((1, nm, 2))
    xi = xi0 + 0.0 * x0
    for _ in range(2):
        c0, c1, dx0, dx1, d2x0, d2x1 = curve_at(nodes, 0, xi)
        r0, r1 = c0 - x0, c1 - x1
        step = (r0 * dx0 + r1 * dx1) / ((dx0 * dx0 + dx1 * dx1) + (r0 * d2x0 + r1 * d2x1))
        xi = xi - step
        if abs(xi.real) > 2:
            xi = min(max(xi.real, -2.0), 2.0) + 0.0 * x0
    if small:
        _, _, t0, t1, _, _ = curve_at(ref.reshape((1, nm, 2)), 0, xi)
    else:
        _, _, t0, t1, _, _ = curve_at(nodes, 0, xi)
    s = np.sqrt(t0 * t0 + t1 * t1)
    t0, t1 = t0 / s, t1 / s
    n0, n1 = t1, -t0
    xb0, xb1, _, _, _, _ = curve_at(nodes, 0, xi)
    g = ((x0 - xb0) * n0 + (x1 - xb1) * n1) + g0
    p = eps * (-g if g.real <= 0.0 else 0.0 * g)
    tr0, tr1 = p * n0, p * n1
    tw0, tw1 = tr0 * w, tr1 * w
    for k in range(ns):
        forces[k, 0], forces[k, 1] = -Ns[k] * tw0, -Ns[k] * tw1
    if nm == 2:
        N = (0.5 * (1 - xi), 0.5 * (1 + xi), 0.0 * xi)
    else:
        N = (0.5 * xi * (xi - 1), 0.5 * xi * (xi + 1), 1 - xi * xi)
    for k in range(nm):
        forces[ns + k, 0], forces[ns + k, 1] = N[k] * tw0, N[k] * tw1
    if nodal:
        share = (tr0 * n0 + tr1 * n1) * w
    else:
        share = tw0 * n0 + tw1 * n1
    for k in range(ns):
        shares[k] = share * Ns[k]
    return g, xi


@kernel
def _shape3(xi, nn):  # type: ignore[no-untyped-def]
    """N, N', N'' at ξ (real), each padded to 3 entries."""
    if nn == 2:
        return (0.5 * (1 - xi), 0.5 * (1 + xi), 0.0), (-0.5, 0.5, 0.0), (0.0, 0.0, 0.0)
    return ((0.5 * xi * (xi - 1), 0.5 * xi * (xi + 1), 1 - xi * xi), (xi - 0.5, xi + 0.5, -2 * xi),
            (1.0, 1.0, -2.0))


@kernel
def point_tangents(Ns, xi0, xs, xm, ref, small, eps, g0, w, cu, J, Jl, work):  # type: ignore[no-untyped-def]
    """∂(forces, shares)/∂Δa of one point, all local DOFs at once (forward mode).

    The derivatives :func:`point`'s complex steps take (``i h cu`` per local DOF: the
    imaginary parts follow these product rules; the terms of order h² vanish), in
    one pass: each quantity carries its tangents along the ``2 (ns + nm)`` local DOFs
    (the slave's nodes, then the master's, x then y). The active set and the
    projection's clip are decided on the values, as there on the real parts.

    Args:
        Ns: The slave shape functions at the point.
        xi0: The projection's ξ̄ (Newton's start).
        xs: The slave facet's nodes (real).
        xm: The master facet's nodes (oriented).
        ref: Its reference nodes (the normal's facet if ``small``).
        small: Small rotations (the reference normal).
        eps: ε_n.
        g0: The initial gap.
        w: The point's weight.
        cu: ∂x/∂Δa.
        J: Out, ``(2 (ns + nm), 2 (ns + nm))``: ∂forces/∂Δa (forces flattened).
        Jl: Out, ``(ns, 2 (ns + nm))``: ∂shares/∂Δa (the ``normal_and_shares`` shares).
        work: Scratch, ``(3, 2 (ns + nm))``.

    Returns:
        Whether the point is closed (g_n ≤ 0; else J and Jl are zero).
    """
    ns, nm = len(Ns), xm.shape[0]
    L = 2 * (ns + nm)
    x0, x1 = 0.0, 0.0
    for k in range(ns):
        x0 += Ns[k] * xs[k, 0]
        x1 += Ns[k] * xs[k, 1]
    dx0, dx1, dxi = work[0], work[1], work[2]
    dx0[:] = 0.0
    dx1[:] = 0.0
    dxi[:] = 0.0
    for k in range(ns):
        dx0[2 * k] = Ns[k] * cu
        dx1[2 * k + 1] = Ns[k] * cu
    xi = xi0
    m0 = 2 * ns  # the master's first local DOF
    for _ in range(2):
        N, D, D2 = _shape3(xi, nm)
        c0 = c1 = t0 = t1 = s0 = s1 = 0.0
        for b in range(nm):
            c0 += N[b] * xm[b, 0]
            c1 += N[b] * xm[b, 1]
            t0 += D[b] * xm[b, 0]
            t1 += D[b] * xm[b, 1]
            s0 += D2[b] * xm[b, 0]
            s1 += D2[b] * xm[b, 1]
        r0, r1 = c0 - x0, c1 - x1
        f = r0 * t0 + r1 * t1
        den = (t0 * t0 + t1 * t1) + (r0 * s0 + r1 * s1)
        step = f / den
        new = xi - step
        clip = abs(new) > 2
        for j in range(L):
            # Tangents of c, x', x'' at ξ: through ξ, and the master's own nodes.
            dc0, dc1 = t0 * dxi[j], t1 * dxi[j]
            dt0, dt1 = s0 * dxi[j], s1 * dxi[j]
            ds0, ds1 = 0.0, 0.0
            if j >= m0:
                b, d = (j - m0) // 2, (j - m0) % 2
                if d == 0:
                    dc0 += N[b] * cu
                    dt0 += D[b] * cu
                    ds0 += D2[b] * cu
                else:
                    dc1 += N[b] * cu
                    dt1 += D[b] * cu
                    ds1 += D2[b] * cu
            dr0, dr1 = dc0 - dx0[j], dc1 - dx1[j]
            df = (dr0 * t0 + r0 * dt0) + (dr1 * t1 + r1 * dt1)
            dden = 2 * (t0 * dt0 + t1 * dt1) + (dr0 * s0 + r0 * ds0) + (dr1 * s1 + r1 * ds1)
            dxi[j] = 0.0 if clip else dxi[j] - (df * den - f * dden) / (den * den)
        xi = min(max(new, -2.0), 2.0) if clip else new
    N, D, D2 = _shape3(xi, nm)
    nodes = ref if small else xm
    t0 = t1 = c0 = c1 = a0 = a1 = b0 = b1 = 0.0
    for b in range(nm):
        t0 += D[b] * nodes[b, 0]
        t1 += D[b] * nodes[b, 1]
        a0 += D2[b] * nodes[b, 0]
        a1 += D2[b] * nodes[b, 1]
        c0 += N[b] * xm[b, 0]
        c1 += N[b] * xm[b, 1]
        b0 += D[b] * xm[b, 0]
        b1 += D[b] * xm[b, 1]
    s = np.sqrt(t0 * t0 + t1 * t1)
    u0, u1 = t0 / s, t1 / s
    n0, n1 = u1, -u0
    g = ((x0 - c0) * n0 + (x1 - c1) * n1) + g0
    closed = g <= 0.0
    p = eps * -g if closed else 0.0
    tw0, tw1 = p * n0 * w, p * n1 * w
    for j in range(L):
        dt0, dt1 = a0 * dxi[j], a1 * dxi[j]
        dc0, dc1 = b0 * dxi[j], b1 * dxi[j]
        if j >= m0:
            b, d = (j - m0) // 2, (j - m0) % 2
            if d == 0:
                dc0 += N[b] * cu
                if not small:
                    dt0 += D[b] * cu
            else:
                dc1 += N[b] * cu
                if not small:
                    dt1 += D[b] * cu
        ds = (t0 * dt0 + t1 * dt1) / s
        du0, du1 = (dt0 * s - t0 * ds) / (s * s), (dt1 * s - t1 * ds) / (s * s)
        dn0, dn1 = du1, -du0
        dg = ((dx0[j] - dc0) * n0 + (x0 - c0) * dn0) + ((dx1[j] - dc1) * n1 + (x1 - c1) * dn1)
        dp = -eps * dg if closed else 0.0
        dtw0, dtw1 = (dp * n0 + p * dn0) * w, (dp * n1 + p * dn1) * w
        for k in range(ns):
            J[2 * k, j], J[2 * k + 1, j] = -Ns[k] * dtw0, -Ns[k] * dtw1
        for b in range(nm):
            dN = D[b] * dxi[j]
            J[m0 + 2 * b, j] = dN * tw0 + N[b] * dtw0
            J[m0 + 2 * b + 1, j] = dN * tw1 + N[b] * dtw1
        dshare = (dtw0 * n0 + tw0 * dn0) + (dtw1 * n1 + tw1 * dn1)
        for k in range(ns):
            Jl[k, j] = dshare * Ns[k]
    return closed


@kernel
def local_nodes(X, pos, f, u, out):  # type: ignore[no-untyped-def]
    """Facet (3-D: face) f's current nodes ``X[f] + u[pos[f]]`` into ``out`` (−1: trailing)."""
    for a in range(X.shape[1]):
        for d in range(X.shape[2]):
            out[a, d] = X[f, a, d] + u[pos[f, a, d]]
    return out


@kernel
def residual(sX, mX, pos_s, pos_m, u1, f_s, f_m, Ns, xi, weight, small, eps, g0,
             node_of, n_nodes):  # type: ignore[no-untyped-def]
    """The normal part of f_c and the slave nodes' normal forces λ (``vector()``).

    Args:
        sX: The slave's facets (reference nodes).
        mX: The master's.
        pos_s: The slave's interface positions (−1: Dirichlet).
        pos_m: The master's.
        u1: Displacements at the interface unknowns (a trailing 0).
        f_s: The slave facet of each point with a projection.
        f_m: Its master facet.
        Ns: The slave shape functions at the points.
        xi: The search's ξ̄ of each point.
        weight: The points' weights.
        small: The reference normal (small rotations).
        eps: ε_n.
        g0: The initial gap.
        node_of: The slave node of each facet node.
        n_nodes: The number of slave nodes.

    Returns:
        f_c's normal part ``(n,)``, λ, the points' forces ``(K, ns + nm, 2)``, g_n and ξ̄.
    """
    K, ns, nm = len(f_s), sX.shape[1], mX.shape[1]
    n = len(u1) - 1
    forces = np.zeros((K, ns + nm, 2))
    shares = np.zeros((K, ns))
    gap = np.zeros(K)
    xi_bar = np.zeros(K)
    out = np.zeros(n + 1)
    lam = np.zeros(n_nodes)
    xs, xm = np.empty((ns, 2)), np.empty((nm, 2))
    for k in range(K):
        local_nodes(sX, pos_s, f_s[k], u1, xs)
        local_nodes(mX, pos_m, f_m[k], u1, xm)
        gap[k], xi_bar[k] = point(Ns[k], xi[k], xs, xm, mX[f_m[k]], small, eps, g0,
                                  weight[k], forces[k], shares[k], True)
        for a in range(ns + nm):
            for d in range(2):
                q = pos_s[f_s[k], a, d] if a < ns else pos_m[f_m[k], a - ns, d]
                if q >= 0:
                    out[q] += forces[k, a, d]
        for a in range(ns):
            lam[node_of[f_s[k], a]] += shares[k, a]
    return out[:n], lam, forces, gap, xi_bar


@kernel
def friction(lam, facet0, N0, t0, node_pos, pos_m, v1, mu, chi, lin):  # type: ignore[no-untyped-def]
    """The slave nodes' friction forces (``SurfaceForces._friction``).

    Per slave node k in contact (λ_k > 0, a start-of-step master point), the force
    ``−μ λ_k φ(v_T)`` with ``v_T = t₀ ⊗ t₀ (v_k − v̄_m(ξ̄₀))``; where ``lin`` holds a
    crawl point h (:mod:`breakwater.contact.guardkernels`; NaN: none), the law's tangent
    line at h t₀ instead.

    Returns:
        The nodes ``k``, ``v_T`` (h t₀ where a crawl point is: where the law's slope,
        :func:`jacobian`'s ∂φ, is taken), the force and the force per unit λ (``unit``).
    """
    m = 0
    for j in range(len(lam)):
        if facet0[j] >= 0 and lam[j] > 0:
            m += 1
    k = np.empty(m, np.int64)
    c = 0
    for j in range(len(lam)):
        if facet0[j] >= 0 and lam[j] > 0:
            k[c] = j
            c += 1
    v_T = np.empty((m, 2))
    force = np.empty((m, 2))
    unit = np.empty((m, 2))
    a, b, line = np.empty(1), np.empty(1), np.empty(1)
    for i in range(m):
        j = k[i]
        along = tangential_slip(v1, j, facet0[j], N0, t0, node_pos, pos_m)
        v_T[i, 0], v_T[i, 1] = t0[j, 0] * along, t0[j, 1] * along
        h = lin[j]
        if h == h:  # the law's tangent line at the slip h (Newton's linearisation point)
            a[0], b[0] = h, along
            law_line(a, b, chi, line)
            d0, d1 = t0[j, 0] * line[0], t0[j, 1] * line[0]
            v_T[i, 0], v_T[i, 1] = t0[j, 0] * h, t0[j, 1] * h
        else:
            s = np.sqrt((v_T[i, 0] * v_T[i, 0] + v_T[i, 1] * v_T[i, 1]) + chi ** 2)
            d0, d1 = v_T[i, 0] / s, v_T[i, 1] / s
        force[i, 0], force[i, 1] = (-mu * lam[j]) * d0, (-mu * lam[j]) * d1
        unit[i, 0], unit[i, 1] = (-mu * 1.0) * d0, (-mu * 1.0) * d1
    return k, v_T, force, unit


@kernel
def tangential_slip(v, j, f, N0, t0, node_pos, pos_m):  # type: ignore[no-untyped-def]
    """Slave node j's velocity relative to master facet f's point under it, along t₀.

    ``(v_j − Σ_b N̄₀_b v_b)·t₀`` at the interface vector ``v`` (a trailing 0), the
    slip velocity of :func:`friction`, of the slip guard
    (:func:`breakwater.contact.guardkernels.slip_guard`) and of the slip memory
    (:func:`breakwater.contact.newtonaids.slip_along`).
    """
    a0, a1 = 0.0, 0.0
    for b in range(N0.shape[1]):
        a0 += N0[j, b] * v[pos_m[f, b, 0]]
        a1 += N0[j, b] * v[pos_m[f, b, 1]]
    return (v[node_pos[j, 0]] - a0) * t0[j, 0] + (v[node_pos[j, 1]] - a1) * t0[j, 1]


@kernel
def law_line(c0, c1, chi, out):  # type: ignore[no-untyped-def]
    """The friction law's linear model at the slip c₀, at c₁, into ``out``; returns |f|².

    ``f = φ(c₀) + φ'(c₀)(c₁ − c₀)``, φ(c) = c / sqrt(|c|² + χ²) (tangent-basis components):
    the force a Newton step asks of the law, which the slip guard's landing inverts
    (:func:`breakwater.contact.guardkernels.land`) and a crawl point's iterate applies
    (:func:`friction`); the operations of :func:`breakwater.contact.slipguard.land`.
    """
    n = len(c0)
    s = 0.0
    for m in range(n):
        s += c0[m] * c0[m]
    r = np.sqrt(s + chi * chi)
    p = 0.0
    for m in range(n):
        p += (c0[m] / r) * (c1[m] - c0[m])
    f2 = 0.0
    for m in range(n):
        phi = c0[m] / r
        out[m] = phi + ((c1[m] - c0[m]) - phi * p) / r
        f2 += out[m] * out[m]
    return f2


@kernel
def friction_round_off(k, v_T, lam, facet0, N0, node_pos, pos_m, v, a, y, dt, dv, mu, chi,
                       eps):  # type: ignore[no-untyped-def]
    """:func:`breakwater.contact.newtonaids.resolution` from :func:`friction`'s k and v_T.

    Per node k: ``μ λ_k φ'(v_T) ε Σ|v|``, the velocities' magnitudes
    ``|v| + Δt |a| + β₁Δt |Δa|`` summed over the node's and its master facet's DOFs
    (weighted by |N̄₀|); their root sum of squares.

    Args:
        k: The nodes in contact (:func:`friction`).
        v_T: Their slip velocities.
        lam: The slave nodes' normal forces.
        facet0: Their start-of-step master facets.
        N0: The master shape functions there.
        node_pos: The slave nodes' interface positions.
        pos_m: The master facets'.
        v: v at the start of the step (a trailing 0).
        a: a there.
        y: Δa at the interface unknowns (no trailing 0).
        dt: Δt.
        dv: β₁Δt.
        mu: μ.
        chi: χ.
        eps: The unit round-off.
    """
    n = len(y)
    total = 0.0
    for i in range(len(k)):
        j = k[i]
        node = 0.0
        for d in range(node_pos.shape[1]):
            q = node_pos[j, d]
            node += abs(v[q]) + dt * abs(a[q]) + dv * abs(y[q] if 0 <= q < n else 0.0)
        for b in range(N0.shape[1]):
            for d in range(2):
                q = pos_m[facet0[j], b, d]
                node += abs(N0[j, b]) * (abs(v[q]) + dt * abs(a[q])
                                         + dv * abs(y[q] if 0 <= q < n else 0.0))
        speed2 = v_T[i, 0] * v_T[i, 0] + v_T[i, 1] * v_T[i, 1]
        slope = chi**2 / (speed2 + chi**2) ** 1.5
        r = mu * lam[j] * slope * eps * node
        total += r * r
    return np.sqrt(total)


@kernel
def add_friction(out, k, force, facet0, N0, node_pos, pos_m):  # type: ignore[no-untyped-def]
    """f_c += the friction forces: −force on the slave node, N̄₀ force on the master's."""
    n = len(out)
    slave = np.zeros(n + 1)
    master = np.zeros(n + 1)
    for i in range(len(k)):
        for d in range(2):
            q = node_pos[k[i], d]
            if q >= 0:
                slave[q] += -force[i, d]
    for i in range(len(k)):
        f = facet0[k[i]]
        for b in range(N0.shape[1]):
            for d in range(2):
                q = pos_m[f, b, d]
                if q >= 0:
                    master[q] += N0[k[i], b] * force[i, d]
    for q in range(n):
        out[q] = (out[q] + slave[q]) + master[q]


@kernel
def jacobian(sX, mX, pos_s, pos_m, u1, f_s, f_m, Ns, xi, weight, gap, small, eps, g0,
             node_of, n_nodes, cu, cv, use_friction, lam, k, v_T, unit, facet0, N0, t0,
             node_pos, mu, chi):  # type: ignore[no-untyped-def]
    """∂f_c/∂Δa (``matrix()``) on the interface unknowns it couples.

    The normal part and dλ/dΔa by :func:`point_tangents` (the reference's complex
    steps ``i h cu`` of each local DOF of a point, in forward mode), the friction part
    by the chain rule through λ_k and v_T (∂φ/∂v_T by complex steps), each entry summed
    in the order of the reference. ``gap``: the points' g_n of :func:`residual` at
    the same state; an open point (g_n > 0) has no tangents and couples nothing.

    Returns:
        The unknowns the matrix couples (sorted: the DOFs of the closed points, g_n ≤ 0,
        and of the friction's nodes) and the matrix on them, ``A[act, act]``
        (zero elsewhere).
    """
    K, ns, nm = len(f_s), sX.shape[1], mX.shape[1]
    n = len(u1) - 1
    local = (ns + nm) * 2
    # Each point's tangents; an open point's are zero and couple nothing.
    Jp = np.empty((K, local, local))
    Jl = np.empty((K, ns, local))
    closed = np.empty(K, np.bool_)
    xs, xm, work = np.empty((ns, 2)), np.empty((nm, 2)), np.empty((3, local))
    for p in range(K):
        closed[p] = gap[p] <= 0.0 and point_tangents(
            Ns[p], xi[p], local_nodes(sX, pos_s, f_s[p], u1, xs),
            local_nodes(mX, pos_m, f_m[p], u1, xm),
            mX[f_m[p]], small, eps, g0, weight[p], cu, Jp[p], Jl[p], work)
    rows = np.empty((K, local), np.int64)
    where = np.full(n + 1, -1, np.int64)
    for p in range(K):
        for a in range(ns + nm):
            for d in range(2):
                q = pos_s[f_s[p], a, d] if a < ns else pos_m[f_m[p], a - ns, d]
                rows[p, 2 * a + d] = q
                if q >= 0 and closed[p]:
                    where[q] = 0
    friction = use_friction and len(k) > 0
    m = len(k) if friction else 0
    R = nm + 1
    row_pos = np.empty((m, R, 2), np.int64)
    sign = np.empty((m, R))
    for i in range(m):
        row_pos[i, 0] = node_pos[k[i]]
        sign[i, 0] = -1.0
        for b in range(nm):
            row_pos[i, b + 1] = pos_m[facet0[k[i]], b]
            sign[i, b + 1] = N0[k[i], b]
        for r in range(R):
            for a in range(2):
                if row_pos[i, r, a] >= 0:
                    where[row_pos[i, r, a]] = 0
    act = np.flatnonzero(where[:n] >= 0)
    na = len(act)
    for i in range(na):
        where[act[i]] = i
    A = np.zeros((na, na))
    for p in range(K):
        if not closed[p]:
            continue
        for o in range(local):
            r = rows[p, o]
            if r < 0:
                continue
            for j in range(local):
                c = rows[p, j]
                if c >= 0:
                    A[where[r], where[c]] += Jp[p, o, j]
    if not friction:
        return act, A
    # The blocks in the reference's order: the normal part above, then per point.
    dlam = np.zeros((n_nodes, na))
    for p in range(K):
        if not closed[p]:
            continue
        for b in range(ns):
            for j in range(local):
                c = rows[p, j]
                if c >= 0:
                    dlam[node_of[f_s[p], b], where[c]] += Jl[p, b, j]
    B = np.zeros((m, 2, 2))
    for i in range(m):
        D = np.zeros((2, 2))
        for c in range(2):
            v0 = v_T[i, 0] + (1j * H if c == 0 else 0j)
            v1 = v_T[i, 1] + (1j * H if c == 1 else 0j)
            s = np.sqrt((v0 * v0 + v1 * v1) + chi ** 2)
            D[0, c] = ((-mu * lam[k[i]]) * (v0 / s)).imag / H
            D[1, c] = ((-mu * lam[k[i]]) * (v1 / s)).imag / H
        t = t0[k[i]]
        for a in range(2):
            for b in range(2):
                B[i, a, b] = cv * ((D[a, 0] * t[0] * t[b]) + (D[a, 1] * t[1] * t[b]))
    # Rows (and columns): the slave node, then the master nodes of its f₀. dλ_k is
    # nonzero in the columns of the points on the node's facets alone: those visited.
    cols = np.empty((m, na), np.int64)
    ncols = np.zeros(m, np.int64)
    for i in range(m):
        for c in range(na):
            if dlam[k[i], c] != 0.0:
                cols[i, ncols[i]] = c
                ncols[i] += 1
    for r in range(R):
        for i in range(m):
            for a in range(2):
                q = row_pos[i, r, a]
                if q >= 0:
                    for j in range(ncols[i]):
                        c = cols[i, j]
                        A[where[q], c] += sign[i, r] * (unit[i, a] * dlam[k[i], c])
    for r in range(R):
        for cc in range(R):
            for i in range(m):
                col_sign = 1.0 if cc == 0 else -N0[k[i], cc - 1]
                f = sign[i, r] * col_sign
                for a in range(2):
                    q = row_pos[i, r, a]
                    if q < 0:
                        continue
                    for b in range(2):
                        c = row_pos[i, cc, b]
                        if c >= 0:
                            A[where[q], where[c]] += f * B[i, a, b]
    return act, A


@kernel
def left_product(X, act, A):  # type: ignore[no-untyped-def]
    """``X @ M`` for the matrix M that is ``A`` on ``act × act`` and zero elsewhere.

    ``(rows(X), n)``; only A's nonzero rows are visited (single-threaded: no BLAS
    threads for these small products).
    """
    n, na = X.shape[1], len(act)
    out = np.zeros((X.shape[0], n))
    nonzero = np.zeros(na, np.bool_)
    for k in range(na):
        for j in range(na):
            if A[k, j] != 0.0:
                nonzero[k] = True
                break
    rows = np.flatnonzero(nonzero)
    row = np.zeros(na)
    for i in range(X.shape[0]):
        row[:] = 0.0
        for k in rows:
            a = X[i, act[k]]
            for j in range(na):
                row[j] += a * A[k, j]
        for j in range(na):
            out[i, act[j]] = row[j]
    return out
