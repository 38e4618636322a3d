"""The conforming pair's contact law on nodal arrays, compiled: the fast step's inner loop.

The kernels of :class:`~breakwater.contact.nodal.NodalContactForces` and of the slip
guard on the interface unknowns (:mod:`breakwater.contact.slipguard`), written as loops
over the interface's quadrature points (its nodes: Gauss–Lobatto on P2 facets) and
compiled (:func:`breakwater.common.jit.kernel`). They evaluate the formulas of
:meth:`forms.ContactLaw.nodal` (penalty normal contact, eq. 12, and the regularised
Coulomb law, eq. 23, with their derivatives), of
:func:`~breakwater.contact.slipguard.guard_slip` and of the GN22 update
(:func:`breakwater.stepping.gn22.gn22_kinematics`, the paper's eqs. 24–26), in the same
order of floating-point operations, so that they give the NumPy references' numbers
(``tests/test_nodalcontact.py`` checks them against those and against the UFL forms).

Array conventions (one pair, its nodes in the order of
:class:`~breakwater.contact.conforming.InterfaceNodes`):

- ``pos[side, k, i]``: the interface unknown of component i of node k on the slave
  (side 0) or the master (side 1), −1 where it is not one (a fixed DOF);
- ``base[j, side, k, i]``: per step, j = 0..4: u₀, Δt v₀ + ½Δt² a₀, v₀, Δt a₀ and the
  staged Δa (used where ``pos`` is −1);
- quadrature points q: ``node[q]``, ``weight[q]`` and the facet's ``normal[q]``, sorted
  by node, the points of node ``run_nodes[r]`` from ``runs[r]`` to ``runs[r + 1]``.
"""

from __future__ import annotations

import math

import numpy as np

from breakwater.common.jit import kernel
from breakwater.contact.guardkernels import land

__all__ = ["closed_nodes", "guard_steps", "nodal_left_product", "nodal_residual", "nodal_state",
           "nodal_tangents", "normal_forces", "tangent_block", "tangent_left_product"]


@kernel
def nodal_state(y: np.ndarray, pos: np.ndarray, base: np.ndarray, cu: float, cv: float,
                U: np.ndarray, V: np.ndarray) -> None:
    """u₁ and v₁ at the nodes of both sides for the iterate y (the step's Δa_I).

    ``u₁ = u₀ + ((Δt v₀ + ½Δt² a₀) + ½β₂Δt² Δa)``, ``v₁ = v₀ + (Δt a₀ + β₁Δt Δa)``
    with ``cu = ½β₂Δt²``, ``cv = β₁Δt``; into ``U``, ``V`` of shape ``(2, nodes, gdim)``.
    """
    for side in range(pos.shape[0]):
        for k in range(pos.shape[1]):
            for i in range(pos.shape[2]):
                p = pos[side, k, i]
                d = y[p] if p >= 0 else base[4, side, k, i]
                U[side, k, i] = base[0, side, k, i] + (base[1, side, k, i] + cu * d)
                V[side, k, i] = base[2, side, k, i] + (base[3, side, k, i] + cv * d)


@kernel
def _traction(U: np.ndarray, V: np.ndarray, k: int, n: np.ndarray, ε_n: float, g0: float,
              μ: float, χ2: float, t: np.ndarray, φ: np.ndarray) -> tuple[float, float, float]:
    """t_s = p (n − μφ) at node k with the normal n; returns (p, s, the closed indicator)."""
    gdim = n.shape[0]
    g = 0.0
    vn = 0.0
    for i in range(gdim):
        g += (U[0, k, i] - U[1, k, i]) * n[i]
        vn += (V[0, k, i] - V[1, k, i]) * n[i]
    g += g0
    closed = 1.0 if g <= 0.0 else 0.0
    p = -ε_n * g if g <= 0.0 else 0.0
    ss = 0.0
    for i in range(gdim):
        φ[i] = (V[0, k, i] - V[1, k, i]) - vn * n[i]
        ss += φ[i] * φ[i]
    s = math.sqrt(ss + χ2)
    for i in range(gdim):
        φ[i] = φ[i] / s
        t[i] = p * (n[i] - μ * φ[i])
    return p, s, closed


@kernel
def nodal_residual(y: np.ndarray, pos: np.ndarray, base: np.ndarray, cu: float, cv: float,
                   node: np.ndarray, weight: np.ndarray, normal: np.ndarray, ε_n: float,
                   g0: float, μ: float, χ2: float, U: np.ndarray, V: np.ndarray,
                   fc: np.ndarray) -> None:
    """Add the pair's f_c(y) to ``fc``: −w t_s on the slave's unknowns, +w t_s on the master's.

    u₁, v₁ at the nodes first (:func:`nodal_state`, into U and V); summed as the NumPy
    reference sums (all slave entries point by point, then all master entries).
    """
    nodal_state(y, pos, base, cu, cv, U, V)
    gdim = normal.shape[1]
    nq = node.shape[0]
    wt = np.empty((nq, gdim))
    t = np.empty(gdim)
    φ = np.empty(gdim)
    for q in range(nq):
        _traction(U, V, node[q], normal[q], ε_n, g0, μ, χ2, t, φ)
        for i in range(gdim):
            wt[q, i] = weight[q] * t[i]
    for side in range(2):
        for q in range(nq):
            for i in range(gdim):
                p = pos[side, node[q], i]
                if p >= 0:
                    fc[p] += -wt[q, i] if side == 0 else wt[q, i]


@kernel
def nodal_left_product(y: np.ndarray, pos: np.ndarray, base: np.ndarray, cu: float,
                       cv: float, node: np.ndarray, weight: np.ndarray, normal: np.ndarray,
                       runs: np.ndarray, ε_n: float, g0: float, μ: float, χ2: float,
                       slave: np.ndarray, master: np.ndarray, X: np.ndarray, U: np.ndarray,
                       V: np.ndarray, W: np.ndarray, out: np.ndarray) -> None:
    """Add X ∂f_c/∂y at y to ``out``.

    :func:`nodal_state`, :func:`nodal_tangents`, then :func:`tangent_left_product`.
    """
    nodal_state(y, pos, base, cu, cv, U, V)
    nodal_tangents(U, V, node, weight, normal, runs, ε_n, g0, μ, χ2, cu, cv, W)
    tangent_left_product(X, W, slave, master, out)


@kernel
def nodal_tangents(U: np.ndarray, V: np.ndarray, node: np.ndarray, weight: np.ndarray,
                   normal: np.ndarray, runs: np.ndarray, ε_n: float, g0: float, μ: float,
                   χ2: float, cu: float, cv: float, W: np.ndarray) -> None:
    """W_r = Σ w (½β₂Δt² ∂t/∂u + β₁Δt ∂t/∂v) over the points of run r, ``(runs, gdim, gdim)``.

    ∂t/∂u = −ε_n c (n − μφ) ⊗ n and ∂t/∂v = −μ p (I − n⊗n − φ⊗φ)/s
    (:meth:`forms.ContactLaw.nodal`).
    """
    gdim = normal.shape[1]
    t = np.empty(gdim)
    φ = np.empty(gdim)
    D = np.empty((gdim, gdim))
    for r in range(runs.shape[0] - 1):
        for q in range(runs[r], runs[r + 1]):
            n = normal[q]
            p, s, closed = _traction(U, V, node[q], n, ε_n, g0, μ, χ2, t, φ)
            fu = -ε_n * closed
            fv = -μ * p / s
            for i in range(gdim):
                for j in range(gdim):
                    P = (1.0 if i == j else 0.0) - n[i] * n[j]
                    tu = fu * ((n[i] - μ * φ[i]) * n[j])
                    tv = fv * (P - φ[i] * φ[j])
                    D[i, j] = weight[q] * (cu * tu + cv * tv)
            for i in range(gdim):
                for j in range(gdim):
                    if q == runs[r]:
                        W[r, i, j] = D[i, j]
                    else:
                        W[r, i, j] += D[i, j]


@kernel
def tangent_left_product(X: np.ndarray, W: np.ndarray, slave: np.ndarray,
                         master: np.ndarray, out: np.ndarray) -> None:
    """Add X ∂f_c/∂y to ``out`` from the node tangents W.

    Node r's slave columns of ∂f_c/∂y are −W_r and its master columns +W_r times the
    rows ``s_r − m_r``, so ``(X ∂f_c)[:, s_r] = −R_r W_r``, ``[:, m_r] = R_r W_r`` with
    ``R_r = X[:, s_r] − X[:, m_r]`` (a column −1: zero). ``slave``, ``master``: the
    unknowns ``(runs, gdim)`` of each run's node.
    """
    rows = X.shape[0]
    gdim = W.shape[1]
    R = np.empty(gdim)
    for r in range(W.shape[0]):
        for a in range(rows):
            for i in range(gdim):
                cs, cm = slave[r, i], master[r, i]
                R[i] = (X[a, cs] if cs >= 0 else 0.0) - (X[a, cm] if cm >= 0 else 0.0)
            for j in range(gdim):
                Y = 0.0
                for i in range(gdim):
                    Y += R[i] * W[r, i, j]
                if slave[r, j] >= 0:
                    out[a, slave[r, j]] += -Y
                if master[r, j] >= 0:
                    out[a, master[r, j]] += Y


@kernel
def closed_nodes(W: np.ndarray) -> np.ndarray:
    """The nodes whose tangent W_r is not zero (closed; an open node's is)."""
    live = np.zeros(W.shape[0], np.bool_)
    for r in range(W.shape[0]):
        for i in range(W.shape[1]):
            for j in range(W.shape[2]):
                if W[r, i, j] != 0.0:
                    live[r] = True
    return live


@kernel
def tangent_block(W: np.ndarray, slave: np.ndarray, master: np.ndarray,
                  n: int) -> tuple[np.ndarray, np.ndarray]:
    """∂f_c/∂y from the node tangents W on the unknowns it couples: ``(act, A[act, act])``.

    The blocks of :func:`tangent_left_product` with X = I: node r's
    ``[s_r, s_r] = [m_r, m_r] = −W_r`` and ``[s_r, m_r] = [m_r, s_r] = +W_r``; a node
    whose W_r is zero (open) couples nothing. ``n``: the interface unknowns.
    """
    gdim = W.shape[1]
    where = np.full(n, -1, np.int64)
    live = closed_nodes(W)
    for r in range(W.shape[0]):
        if live[r]:
            for i in range(gdim):
                for c in (slave[r, i], master[r, i]):
                    if c >= 0:
                        where[c] = 0
    act = np.flatnonzero(where >= 0)
    for k in range(len(act)):
        where[act[k]] = k
    A = np.zeros((len(act), len(act)))
    for r in range(W.shape[0]):
        if not live[r]:
            continue
        for i in range(gdim):
            for j in range(gdim):
                w = W[r, i, j]
                for a, sa in ((slave[r, i], -1.0), (master[r, i], 1.0)):
                    if a < 0:
                        continue
                    for b, sb in ((slave[r, j], -1.0), (master[r, j], 1.0)):
                        if b >= 0:
                            A[where[a], where[b]] += -(sa * sb) * w
    return act, A


@kernel
def normal_forces(U: np.ndarray, node: np.ndarray, weight: np.ndarray, normal: np.ndarray,
                  ε_n: float, g0: float, lam: np.ndarray) -> None:
    """Each node's normal force λ = Σ w p over its points at the nodal state U, into ``lam``.

    p as :func:`_traction`'s (the penalty pressure where the gap is closed).
    """
    lam[:] = 0.0
    for q in range(node.shape[0]):
        k = node[q]
        g = g0
        for i in range(normal.shape[1]):
            g += (U[0, k, i] - U[1, k, i]) * normal[q, i]
        if g <= 0.0:
            lam[k] += weight[q] * (-ε_n * g)


@kernel
def guard_steps(x: np.ndarray, step: np.ndarray, v_pred: np.ndarray, dv_dx: float,
                pos: np.ndarray, normal: np.ndarray, tangents: np.ndarray,
                band: float, acts: np.ndarray) -> int:
    """The slip guard of one pair on the interface unknowns; returns the nodes corrected.

    Newton's next iterate is ``x − step``; the velocities of the iterate are
    ``v_pred + dv_dx x`` (zero at a node component that is not an unknown). Where the
    relative slip velocity would turn by more than 90° in the tangent plane (w₀·w₁ < 0)
    from outside the band ``|w₀| ≤ band``, its tangential velocity lands at zero; any
    other step lands on the law's curve where
    :func:`~breakwater.contact.guardkernels.land` applies. The slave's step becomes
    ``ys − (I − nn) ys + (I − nn) ym + (w₀ − w₁')/dv_dx`` (normal part kept), written in
    ``step`` (:func:`~breakwater.contact.slipguard.guard_slip`,
    :class:`~breakwater.contact.slipguard.SlipGuard`). Only at the nodes where it ``acts``
    (:func:`~breakwater.contact.coupling.guarded_nodes`).
    """
    nodes, gdim = normal.shape
    ntan = tangents.shape[1]
    vs = np.zeros((2, gdim))
    ys = np.zeros((2, gdim))
    w0 = np.empty(gdim)
    w1 = np.empty(gdim)
    w1n = np.empty(gdim)
    c0s = np.empty(ntan)
    c1 = np.empty(ntan)
    target = np.empty(ntan)
    corrected = 0
    for k in range(nodes):
        if not acts[k]:
            continue
        for side in range(2):
            for i in range(gdim):
                p = pos[side, k, i]
                vs[side, i] = v_pred[p] + dv_dx * x[p] if p >= 0 else 0.0
                ys[side, i] = step[p] if p >= 0 else 0.0
        n = normal[k]
        dw0 = 0.0
        dy = 0.0
        for i in range(gdim):
            dw0 += (vs[0, i] - vs[1, i]) * n[i]
            dy += (ys[0, i] - ys[1, i]) * n[i]
        for i in range(gdim):
            w0[i] = (vs[0, i] - vs[1, i]) - dw0 * n[i]
            w1[i] = w0[i] - dv_dx * ((ys[0, i] - ys[1, i]) - dy * n[i])
        dot = 0.0
        speed2 = 0.0
        for m in range(ntan):
            c0 = 0.0
            c = 0.0
            for i in range(gdim):
                c0 += tangents[k, m, i] * w0[i]
                c += tangents[k, m, i] * w1[i]
            c0s[m] = c0
            c1[m] = c
            dot += c0 * c
            speed2 += c0 * c0
        if dot < 0.0 and math.sqrt(speed2) > band:
            target[:] = 0.0  # a reversal: lands at zero
        elif not land(c0s, c1, band, target):
            continue  # Newton's step stands
        fix = False
        for i in range(gdim):
            cut = 0.0
            for m in range(ntan):
                cut += tangents[k, m, i] * (c1[m] - target[m])
            w1n[i] = w1[i] - cut
            fix = fix or (w1n[i] != w1[i])
        if not fix:
            continue
        corrected += 1
        ysn = 0.0
        ymn = 0.0
        for i in range(gdim):
            ysn += ys[0, i] * n[i]
            ymn += ys[1, i] * n[i]
        for i in range(gdim):
            p = pos[0, k, i]
            if p >= 0:
                step[p] = ((ys[0, i] - (ys[0, i] - ysn * n[i]))
                           + (ys[1, i] - ymn * n[i])) + (w0[i] - w1n[i]) / dv_dx
    return corrected
