"""The compiled forces of a 3-D general contact pair: f_c's normal part and its Jacobian.

The 3-D counterpart of :mod:`breakwater.contact.forcekernels` (issue 25), with the
arithmetic of the NumPy reference :mod:`breakwater.contact.pointkernels3d` in loops
(:mod:`breakwater.common.jit`). The faces are Lagrange triangles of 3 or 6 nodes
(:mod:`breakwater.contact.projection3d`'s order). :func:`point` is the point kernel: the
slave point ``x = Σ N_s x_s``, two Newton steps of its closest-point projection onto the
master face from the search's (ξ̄, η̄), the master's unit outward normal
``n̄ = x_ξ × x_η / |x_ξ × x_η|`` there (the reference face's with small rotations), the
gap ``g_n = (x − x̄)·n̄ + g₀`` and the penalty traction ``t = ε_n ⟨−g_n⟩₊ n̄``: the slave
receives ``−N_s t w``, the master ``N̄ t w``. It runs in complex arithmetic: :func:`jacobian`
takes ∂f_c/∂Δa by a complex step ``i h c_u`` per local DOF of each closed point (3 per
node of the slave and the master face: 36 for two 6-node faces), the projection's Newton
differentiated with it (the implicit dependence of ξ̄ on the nodes included: exact).
The interface arrays carry a trailing entry (position −1: Dirichlet, 0).
``tests/test_pair3d.py`` checks them against the reference and finite differences.
"""

from __future__ import annotations

import numpy as np

from breakwater.common.jit import kernel
from breakwater.contact.forcekernels import local_nodes

__all__ = ["H", "jacobian", "point", "residual", "shape"]

H = 1e-20  # the complex step (pointkernels.H)
_LO, _HI = -1.0, 2.0  # Newton's iterate kept in [−1, 2] per coordinate (projection3d)


@kernel
def shape(xi, eta, nn, N, dN, d2N):  # type: ignore[no-untyped-def]
    """Triangle shape functions at (ξ, η) into N ``(nn,)``, dN ``(nn, 2)``, d2N ``(nn, 3)``.

    :func:`breakwater.contact.projection3d.shape` (ξξ, ξη, ηη), real or complex.
    """
    L0, L1, L2 = 1 - xi - eta, xi, eta
    if nn == 3:
        N[0], N[1], N[2] = L0, L1, L2
        dN[0, 0], dN[0, 1] = -1.0, -1.0
        dN[1, 0], dN[1, 1] = 1.0, 0.0
        dN[2, 0], dN[2, 1] = 0.0, 1.0
        d2N[:, :] = 0.0
        return
    # The gradients of L₀, L₁, L₂ (∂/∂ξ, ∂/∂η).
    g = ((-1.0, -1.0), (1.0, 0.0), (0.0, 1.0))
    L = (L0, L1, L2)
    for k in range(3):
        N[k] = L[k] * (2 * L[k] - 1)
        for a in range(2):
            dN[k, a] = (4 * L[k] - 1) * g[k][a]
        d2N[k, 0] = 4 * g[k][0] * g[k][0]
        d2N[k, 1] = 4 * g[k][0] * g[k][1]
        d2N[k, 2] = 4 * g[k][1] * g[k][1]
    edges = ((1, 2), (0, 2), (0, 1))
    for k in range(3):
        a, b = edges[k]
        N[3 + k] = 4 * L[a] * L[b]
        for c in range(2):
            dN[3 + k, c] = 4 * (L[b] * g[a][c] + L[a] * g[b][c])
        d2N[3 + k, 0] = 4 * (g[a][0] * g[b][0] + g[a][0] * g[b][0])
        d2N[3 + k, 1] = 4 * (g[a][0] * g[b][1] + g[a][1] * g[b][0])
        d2N[3 + k, 2] = 4 * (g[a][1] * g[b][1] + g[a][1] * g[b][1])


@kernel
def _face(nodes, N, dN, d2N, x, dx, d2x):  # type: ignore[no-untyped-def]
    """X ``(3,)``, x_ξ, x_η ``(2, 3)``, x_ξξ, x_ξη, x_ηη ``(3, 3)`` from the shape functions."""
    x[:] = 0.0
    dx[:, :] = 0.0
    d2x[:, :] = 0.0
    for k in range(nodes.shape[0]):
        for d in range(3):
            x[d] += N[k] * nodes[k, d]
            dx[0, d] += dN[k, 0] * nodes[k, d]
            dx[1, d] += dN[k, 1] * nodes[k, d]
            for c in range(3):
                d2x[c, d] += d2N[k, c] * nodes[k, d]


@kernel
def point(Ns, xi0, xs, xm, ref, small, eps, g0, w, forces, work):  # type: ignore[no-untyped-def]
    """One contact point: its nodal forces (complex arithmetic; see the module doc).

    Args:
        Ns: The slave shape functions at the point ``(ns,)`` (real).
        xi0: The projection's (ξ̄, η̄) from the search ``(2,)`` (Newton's start).
        xs: The slave face's current nodes ``(ns, 3)`` (complex).
        xm: The master face's current nodes ``(nm, 3)`` (oriented, complex).
        ref: Its reference nodes (the normal's face if ``small``), complex.
        small: Small rotations (the reference normal).
        eps: ε_n.
        g0: The initial gap.
        w: The point's weight.
        forces: Out ``(ns + nm, 3)`` complex: ``−N_s t w`` then ``N̄ t w``.
        work: Scratch, complex ``(nm, 6)``.

    Returns:
        g_n, ξ̄, η̄ (complex) and p w (the point's share of the normal force).
    """
    ns, nm = len(Ns), xm.shape[0]
    zero = 0.0 * xs[0, 0]
    x = np.zeros(3, xs.dtype)
    for k in range(ns):
        for d in range(3):
            x[d] += Ns[k] * xs[k, d]
    N, dN, d2N = work[:, 0], work[:, 1:3], work[:, 3:6]
    c, dx, d2x = np.zeros(3, xs.dtype), np.zeros((2, 3), xs.dtype), np.zeros((3, 3), xs.dtype)
    xi, eta = xi0[0] + zero, xi0[1] + zero
    for _ in range(2):
        shape(xi, eta, nm, N, dN, d2N)
        _face(xm, N, dN, d2N, c, dx, d2x)
        f0, f1 = zero, zero
        J00, J01, J11 = zero, zero, zero
        for d in range(3):
            r = c[d] - x[d]
            f0 += r * dx[0, d]
            f1 += r * dx[1, d]
            J00 += dx[0, d] * dx[0, d] + r * d2x[0, d]
            J01 += dx[0, d] * dx[1, d] + r * d2x[1, d]
            J11 += dx[1, d] * dx[1, d] + r * d2x[2, d]
        det = J00 * J11 - J01 * J01
        xi = xi - (J11 * f0 - J01 * f1) / det
        eta = eta - (J00 * f1 - J01 * f0) / det
        if xi.real < _LO or xi.real > _HI:
            xi = min(max(xi.real, _LO), _HI) + zero
        if eta.real < _LO or eta.real > _HI:
            eta = min(max(eta.real, _LO), _HI) + zero
    shape(xi, eta, nm, N, dN, d2N)
    _face(ref if small else xm, N, dN, d2N, c, dx, d2x)
    a, b = dx[0], dx[1]
    n0 = a[1] * b[2] - a[2] * b[1]
    n1 = a[2] * b[0] - a[0] * b[2]
    n2 = a[0] * b[1] - a[1] * b[0]
    s = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    n = (n0 / s, n1 / s, n2 / s)
    _face(xm, N, dN, d2N, c, dx, d2x)
    g = g0 + zero
    for d in range(3):
        g += (x[d] - c[d]) * n[d]
    p = eps * -g if g.real <= 0.0 else zero
    pw = p * w
    for d in range(3):
        t = pw * n[d]
        for k in range(ns):
            forces[k, d] = -Ns[k] * t
        for k in range(nm):
            forces[ns + k, d] = N[k] * t
    return g, xi, eta, pw


@kernel
def residual(sX, mX, pos_s, pos_m, u1, f_s, f_m, Ns, xi, weight, small, eps, g0,
             node_of, n_nodes):  # type: ignore[no-untyped-def]
    """The normal part of f_c and the slave nodes' normal forces λ (``vector()``).

    Args:
        sX: The slave's faces (reference nodes) ``(S, ns, 3)``.
        mX: The master's ``(M, nm, 3)``.
        pos_s: The slave's interface positions (−1: Dirichlet).
        pos_m: The master's.
        u1: Displacements at the interface unknowns (a trailing 0).
        f_s: The slave face of each point with a projection.
        f_m: Its master face.
        Ns: The slave shape functions at the points ``(K, ns)``.
        xi: The search's (ξ̄, η̄) of each point ``(K, 2)``.
        weight: The points' weights (reference area).
        small: The reference normal (small rotations).
        eps: ε_n.
        g0: The initial gap.
        node_of: The slave node of each face node.
        n_nodes: The number of slave nodes.

    Returns:
        f_c's normal part ``(n,)``, λ, the points' forces ``(K, ns + nm, 3)``, g_n and
        the refined (ξ̄, η̄) ``(K, 2)``.
    """
    K, ns, nm = len(f_s), sX.shape[1], mX.shape[1]
    n = len(u1) - 1
    forces = np.zeros((K, ns + nm, 3))
    gap = np.zeros(K)
    xi_bar = np.zeros((K, 2))
    out = np.zeros(n + 1)
    lam = np.zeros(n_nodes)
    xs, xm = np.empty((ns, 3), np.complex128), np.empty((nm, 3), np.complex128)
    ref = np.empty((nm, 3), np.complex128)
    fk = np.empty((ns + nm, 3), np.complex128)
    work = np.empty((nm, 6), np.complex128)
    for k in range(K):
        local_nodes(sX, pos_s, f_s[k], u1, xs)
        local_nodes(mX, pos_m, f_m[k], u1, xm)
        ref[:, :] = mX[f_m[k]]
        g, x0, x1, pw = point(Ns[k], xi[k], xs, xm, ref, small, eps, g0, weight[k], fk, work)
        gap[k], xi_bar[k, 0], xi_bar[k, 1] = g.real, x0.real, x1.real
        for a in range(ns + nm):
            for d in range(3):
                forces[k, a, d] = fk[a, d].real
                q = pos_s[f_s[k], a, d] if a < ns else pos_m[f_m[k], a - ns, d]
                if q >= 0:
                    out[q] += forces[k, a, d]
        for a in range(ns):
            lam[node_of[f_s[k], a]] += pw.real * Ns[k, a]
    return out[:n], lam, forces, gap, xi_bar


@kernel
def jacobian(sX, mX, pos_s, pos_m, u1, f_s, f_m, Ns, xi, weight, gap, small, eps, g0,
             cu, extra):  # type: ignore[no-untyped-def]
    """∂f_c/∂Δa (``matrix()``) on the interface unknowns it couples.

    Per closed point (g_n ≤ 0 at the same state, :func:`residual`'s ``gap``), a
    complex step ``i h c_u`` of each of its local DOFs (the slave face's nodes, then
    the master's, x y z each) through :func:`point`. ``extra``: further interface
    positions the matrix couples (the friction's, :mod:`breakwater.contact.friction3d`).

    Returns:
        The unknowns the matrix couples (sorted: the DOFs of the closed points and
        ``extra``), the matrix on them, ``A[act, act]``, each point's local DOFs'
        positions ``rows (K, 3 (ns + nm))`` and ∂(p w)/∂Δa along them ``dpw`` (0: an
        open point; the normal forces' derivatives, λ_k = Σ N_s,k p w).
    """
    K, ns, nm = len(f_s), sX.shape[1], mX.shape[1]
    n = len(u1) - 1
    local = (ns + nm) * 3
    rows = np.empty((K, local), np.int64)
    where = np.full(n + 1, -1, np.int64)
    for p in range(K):
        for a in range(ns + nm):
            for d in range(3):
                q = pos_s[f_s[p], a, d] if a < ns else pos_m[f_m[p], a - ns, d]
                rows[p, 3 * a + d] = q
                if q >= 0 and gap[p] <= 0.0:
                    where[q] = 0
    for q in extra:
        where[q] = 0
    act = np.flatnonzero(where[:n] >= 0)
    na = len(act)
    for i in range(na):
        where[act[i]] = i
    A = np.zeros((na, na))
    dpw = np.zeros((K, local))
    xs, xm = np.empty((ns, 3), np.complex128), np.empty((nm, 3), np.complex128)
    ref = np.empty((nm, 3), np.complex128)
    fk = np.empty((ns + nm, 3), np.complex128)
    work = np.empty((nm, 6), np.complex128)
    step = 1j * H * cu
    for p in range(K):
        if not gap[p] <= 0.0:
            continue
        ref[:, :] = mX[f_m[p]]
        for j in range(local):
            c = rows[p, j]
            if c < 0:
                continue
            local_nodes(sX, pos_s, f_s[p], u1, xs)
            local_nodes(mX, pos_m, f_m[p], u1, xm)
            a, d = j // 3, j % 3
            if a < ns:
                xs[a, d] += step
            else:
                xm[a - ns, d] += step
            pw = point(Ns[p], xi[p], xs, xm, ref, small, eps, g0, weight[p], fk, work)[3]
            dpw[p, j] = pw.imag / H
            for o in range(local):
                r = rows[p, o]
                if r >= 0:
                    A[where[r], where[c]] += fk[o // 3, o % 3].imag / H
    return act, A, rows, dpw
