"""The friction of a 3-D general contact pair at its slave nodes (issue 25).

Isotropic regularised Coulomb friction (the paper's law, as the 2-D pair's,
:mod:`breakwater.contact.forcekernels`): per slave node k in contact (its normal force
λ_k = ∫ p N_k > 0 and a master point at the start of the step) the force on the slave
node is ``F_k = −μ λ_k φ(c)``, with the slip velocity a tangent vector of two components

    c_α = T₀_α · (v_k − Σ_b N̄₀_b v_b),   α = 1, 2,

relative to the master material point under the node at the start of the step (its
closest point on the master surface then, face f₀ and shape values N̄₀), in the
orthonormal tangent basis T₀ of the master face there (``T₀₁ = x_ξ/|x_ξ|``,
``T₀₂ = n̄ × T₀₁``; the reference face's with small rotations), and
``φ(c) = Σ_α T₀_α c_α / sqrt(|c|² + χ²)``. The master's nodes of f₀ receive ``−N̄₀_b F_k``
(action and reaction; in the residual's sign, f_c, the slave row gets ``−F_k``).
Where the contact ends within a slave face, or a quadratic triangle's vertex function
makes λ_k < 0 (their integrals vanish: under a uniform pressure a 6-node face's vertex
forces are nil, under any other some are negative), the λ_k are scaled by
s = Σλ/Σ_carried λ so that sliding carries μ Σλ
(:func:`breakwater.contact.newtonaids.friction_normals`, as in 2-D); the Jacobian
differentiates s too (in 3-D s ≠ 1 nearly always: taken as a constant, as in 2-D, the
Newton converged linearly, by 1e-2 per iteration, on a block sliding on a slab).

The Jacobian is consistent: ``∂F_k/∂Δa = −μ φ ⊗ ∂λ̂_k/∂Δa − μ λ̂_k T₀ (∂φ/∂c) T₀ᵀ β₁Δt
(∂(v_k − v̄₀)/∂v)``, with ``∂φ_α/∂c_β = δ_αβ/r − c_α c_β/r³`` (r = sqrt(|c|² + χ²))
and ∂λ_k/∂Δa from the normal kernel's complex steps
(:func:`breakwater.contact.forcekernels3d.jacobian`'s ``dpw``).
:func:`breakwater.contact.pointkernels3d.friction_forces` is the NumPy reference;
``tests/test_pair3d_friction.py`` checks the kernels against it and the Jacobian against
complex steps and finite differences.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from breakwater.common.arrays import key_of, unchanged
from breakwater.common.jit import kernel
from breakwater.contact import newtonaids, searchkernels3d
from breakwater.contact.forcekernels import law_line
from breakwater.contact.guardkernels import (
    CRAWL,
    FREE,
    GROW,
    NONE,
    REGROW,
    REVERSED,
    crawl_point,
    land,
)
from breakwater.contact.projection import INSIDE
from breakwater.contact.projection3d import NODES, shape, surface, unit_normal

if TYPE_CHECKING:
    from breakwater.contact.surfacesearch3d import SurfaceSearch3D

__all__ = ["add_friction", "friction", "friction_jacobian", "frozen", "nearest_vertex", "power",
           "round_off", "slip_guard", "start_slip", "tangent_basis"]


def tangent_basis(nodes: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """The orthonormal tangent basis T₀ ``(K, 2, 3)`` of faces ``nodes`` at ``xi``."""
    _, dx, _ = surface(nodes, xi)
    t1 = dx[:, 0] / np.linalg.norm(dx[:, 0], axis=1)[:, None]
    t2 = np.cross(unit_normal(dx), t1)
    return np.ascontiguousarray(np.stack([t1, t2], axis=1))


def frozen(pair: SurfaceSearch3D, u0: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The slave nodes' master points at the state u0 (the start of the step; cached).

    A node with no projection (past the master surface's edge) takes the nearest master
    vertex within the search radius (:func:`nearest_vertex`), as the 2-D pair takes the
    nearest end: a slave face hanging over the master's edge presses with its nodes
    beyond it too (λ_k > 0), and their friction was missing (only the scale s of
    ``friction_normals`` restored μN, in sum).

    Returns:
        Per slave node: the master face f₀ (−1: no master vertex within the search
        radius either: no friction at the node), its shape values N̄₀ ``(nodes, nm)`` and
        the tangent basis T₀ ``(nodes, 2, 3)`` there.
    """
    kept = getattr(pair, "_frozen3d", None)
    if kept is not None and unchanged(kept[0], u0):
        return kept[1]  # type: ignore[no-any-return]
    mX, pm = pair._mX, pair._pm
    xm = mX + u0[pm]
    x = np.ascontiguousarray(pair.node_X + u0[pair.node_pos])
    facet, xi = searchkernels3d.project(x, np.ascontiguousarray(xm), pair.radius, INSIDE)
    beyond = np.flatnonzero(facet < 0)
    if len(beyond):
        facet[beyond], xi[beyond] = nearest_vertex(x[beyond], xm, pair.radius)
    nodes, nm = len(facet), mX.shape[1]
    N0, T0 = np.zeros((nodes, nm)), np.zeros((nodes, 2, 3))
    on = facet >= 0
    if on.any():
        N0[on] = shape(xi[on], nm)[0]
        T0[on] = tangent_basis((mX if pair.small_rotations else xm)[facet[on]], xi[on])
    out = (np.ascontiguousarray(facet, dtype=np.int64), N0, T0)
    pair._frozen3d = (key_of(u0), out)  # type: ignore[attr-defined]
    return out


def nearest_vertex(points: np.ndarray, xm: np.ndarray, radius: float
                   ) -> tuple[np.ndarray, np.ndarray]:
    """The nearest master vertex (a face corner) of each point within ``radius``.

    Among the faces the search's grid gives each point
    (:func:`~breakwater.contact.searchkernels3d.candidates`: every face whose box, grown
    by the radius, holds it, so every corner within the radius), as the 2-D pair's
    :func:`~breakwater.contact.searchkernels.nearest_end`.

    Args:
        points: The points ``(m, 3)``.
        xm: The master faces' nodes ``(M, nm, 3)`` (corners first).
        radius: The search radius.

    Returns:
        The face of each point's nearest corner (−1: none within the radius; ties: the
        lowest face, then corner) and the corner's reference coordinates (ξ, η) on it
        ``(m, 2)``.
    """
    facet = np.full(len(points), -1, np.int64)
    xi = np.zeros((len(points), 2))
    point, face = searchkernels3d.candidates(points, xm, radius)
    if not len(point):
        return facet, xi
    d2 = np.sum((xm[face, :3] - points[point, None, :]) ** 2, axis=2)
    corner = np.argmin(d2, axis=1)  # the first of equals: the lowest corner
    dist = d2[np.arange(len(face)), corner]
    order = np.lexsort((3 * face + corner, dist, point))  # per point the nearest first
    first = order[np.r_[True, point[order][1:] != point[order][:-1]]]
    first = first[dist[first] <= radius**2]
    facet[point[first]] = face[first]
    xi[point[first]] = NODES[3][corner[first]]
    return facet, xi


@kernel
def friction(lam, facet0, N0, T0, node_pos, pos_m, v1, mu, chi, lin):  # type: ignore[no-untyped-def]
    """The slave nodes' friction forces (the module doc).

    Where ``lin`` holds a crawl point h (tangent-basis components; NaN: none), the
    law's tangent line at h instead (as the 2-D pair's,
    :func:`breakwater.contact.forcekernels.friction`; :func:`slip_guard`).

    Args:
        lam: The slave nodes' normal forces (scaled: ``friction_normals``).
        facet0: Their start-of-step master faces (−1: none).
        N0: The master shape values there ``(nodes, nm)``.
        T0: The tangent bases there ``(nodes, 2, 3)``.
        node_pos: The slave nodes' interface positions ``(nodes, 3)`` (−1: Dirichlet).
        pos_m: The master faces' ``(M, nm, 3)``.
        v1: Velocities at the interface unknowns (a trailing 0).
        mu: μ.
        chi: χ.
        lin: The crawl points ``(nodes, 2)`` (NaN: the law at the slip itself).

    Returns:
        The nodes ``k`` (λ_k > 0 and a face), their slip components c ``(m, 2)`` (h
        where a crawl point is: where the law's slope is taken), the forces on them F
        ``(m, 3)`` and the forces per unit λ (``unit``, −μφ).
    """
    m = 0
    for j in range(len(lam)):
        if facet0[j] >= 0 and lam[j] > 0:
            m += 1
    k = np.empty(m, np.int64)
    i = 0
    for j in range(len(lam)):
        if facet0[j] >= 0 and lam[j] > 0:
            k[i] = j
            i += 1
    c = np.zeros((m, 2))
    force = np.empty((m, 3))
    unit = np.empty((m, 3))
    rel, h, line = np.empty(3), np.empty(2), np.empty(2)
    for i in range(m):
        j = k[i]
        f = facet0[j]
        for d in range(3):
            vm = 0.0
            for b in range(N0.shape[1]):
                vm += N0[j, b] * v1[pos_m[f, b, d]]
            rel[d] = v1[node_pos[j, d]] - vm
        for a in range(2):
            for d in range(3):
                c[i, a] += T0[j, a, d] * rel[d]
        if lin[j, 0] == lin[j, 0]:  # the law's tangent line at the crawl point h
            h[0], h[1] = lin[j, 0], lin[j, 1]
            law_line(h, c[i], chi, line)
            c[i, 0], c[i, 1] = h[0], h[1]
        else:
            s = np.sqrt((c[i, 0] * c[i, 0] + c[i, 1] * c[i, 1]) + chi * chi)
            line[0], line[1] = c[i, 0] / s, c[i, 1] / s
        for d in range(3):
            phi = T0[j, 0, d] * line[0] + T0[j, 1, d] * line[1]
            unit[i, d] = -mu * phi
            force[i, d] = -mu * lam[j] * phi
    return k, c, force, unit


@kernel
def add_friction(out, k, force, facet0, N0, node_pos, pos_m):  # type: ignore[no-untyped-def]
    """f_c += the friction: −F on the slave node, N̄₀ F on its master face's nodes."""
    n = len(out)
    for i in range(len(k)):
        j = k[i]
        for d in range(3):
            q = node_pos[j, d]
            if 0 <= q < n:
                out[q] -= force[i, d]
            for b in range(N0.shape[1]):
                q = pos_m[facet0[j], b, d]
                if 0 <= q < n:
                    out[q] += N0[j, b] * force[i, d]


@kernel
def _node_rows(j, facet0, N0, node_pos, pos_m, rows, sign):  # type: ignore[no-untyped-def]
    """Node j's friction DOFs into ``rows (1 + nm, 3)``: the slave node, then f₀'s nodes.

    ``sign``: ∂(slip)/∂v of each (1, −N̄₀_b); the residual's rows are ``−sign`` F.
    """
    for d in range(3):
        rows[0, d] = node_pos[j, d]
    sign[0] = 1.0
    for b in range(N0.shape[1]):
        for d in range(3):
            rows[1 + b, d] = pos_m[facet0[j], b, d]
        sign[1 + b] = -N0[j, b]


@kernel
def friction_jacobian(A, where, k, c, unit, lam, raw, scale, facet0, N0, T0, node_pos, pos_m,
                      mu, chi, cv, f_s, node_of, Ns, rows, dpw):  # type: ignore[no-untyped-def]
    """A += ∂(friction part of f_c)/∂Δa (in place; the module doc).

    Args:
        A: The Jacobian on the unknowns it couples (``where``: interface position → its
            row, every friction DOF included).
        where: Its map.
        k: :func:`friction`'s nodes.
        c: Their slip components.
        unit: −μφ.
        lam: The scaled normal forces λ̂ = s λ (:func:`~.newtonaids.friction_normals`).
        raw: The normal forces λ.
        scale: s (1: λ̂ is λ; else s = Σλ / Σ_carried λ, differentiated too: the
            carried nodes are those with λ > 0 and a master face).
        facet0: The start-of-step master faces.
        N0: Their shape values.
        T0: Their tangent bases.
        node_pos: The slave nodes' interface positions.
        pos_m: The master faces'.
        mu: μ.
        chi: χ.
        cv: ∂v/∂Δa (β₁Δt).
        f_s: Each point's slave face.
        node_of: The slave node of each slave face node.
        Ns: The points' slave shape values.
        rows: Each point's local DOFs' interface positions ``(K, 3 (ns + nm))``.
        dpw: ∂(p w)/∂Δa of each point along them (0: an open point).
    """
    m, nm = len(k), N0.shape[1]
    index = np.full(node_pos.shape[0], -1, np.int64)
    for i in range(m):
        index[k[i]] = i
    R = 1 + nm
    rr = np.empty((R, 3), np.int64)
    sign = np.empty(R)
    na = A.shape[0]
    # The scale's part: −sign_r unit λ_k ⊗ ∂s/∂Δa, ∂s = (∂Σλ − s ∂Σ_carried λ)/Σ_carried λ.
    if scale != 1.0 and m:
        total = 0.0
        for j in range(len(raw)):
            if raw[j] > 0 and facet0[j] >= 0:
                total += raw[j]
        ds = np.zeros(na)
        for p in range(len(f_s)):
            for jj in range(rows.shape[1]):
                col = rows[p, jj]
                if col < 0 or dpw[p, jj] == 0.0:
                    continue
                carried = 0.0
                for a in range(Ns.shape[1]):
                    j = node_of[f_s[p], a]
                    if raw[j] > 0 and facet0[j] >= 0:
                        carried += Ns[p, a]
                ds[where[col]] += (1.0 - scale * carried) * dpw[p, jj] / total
        for i in range(m):
            _node_rows(k[i], facet0, N0, node_pos, pos_m, rr, sign)
            for r in range(R):
                for d in range(3):
                    q = rr[r, d]
                    if q < 0:
                        continue
                    f = -sign[r] * unit[i, d] * raw[k[i]]
                    for col in range(na):
                        A[where[q], col] += f * ds[col]
    # The normal forces' part: −sign_r unit ⊗ s ∂λ_k/∂Δa.
    for p in range(len(f_s)):
        for a in range(Ns.shape[1]):
            i = index[node_of[f_s[p], a]]
            if i < 0:
                continue
            _node_rows(k[i], facet0, N0, node_pos, pos_m, rr, sign)
            for jj in range(rows.shape[1]):
                col = rows[p, jj]
                dl = scale * Ns[p, a] * dpw[p, jj]
                if col < 0 or dl == 0.0:
                    continue
                for r in range(R):
                    for d in range(3):
                        q = rr[r, d]
                        if q >= 0:
                            A[where[q], where[col]] += -sign[r] * unit[i, d] * dl
    # The slip's part: −sign_r sign_s B, B = −μλ T₀ ∂φ/∂c T₀ᵀ β₁Δt.
    B = np.empty((3, 3))
    D = np.empty((2, 2))
    for i in range(m):
        j = k[i]
        r2 = (c[i, 0] * c[i, 0] + c[i, 1] * c[i, 1]) + chi * chi
        s = np.sqrt(r2)
        for a in range(2):
            for b in range(2):
                D[a, b] = ((1.0 / s if a == b else 0.0) - c[i, a] * c[i, b] / (r2 * s))
        for d in range(3):
            for e in range(3):
                t = 0.0
                for a in range(2):
                    for b in range(2):
                        t += T0[j, a, d] * D[a, b] * T0[j, b, e]
                B[d, e] = -mu * lam[j] * t * cv
        _node_rows(j, facet0, N0, node_pos, pos_m, rr, sign)
        for r in range(R):
            for s_ in range(R):
                f = -sign[r] * sign[s_]
                for d in range(3):
                    q = rr[r, d]
                    if q < 0:
                        continue
                    for e in range(3):
                        col = rr[s_, e]
                        if col >= 0:
                            A[where[q], where[col]] += f * B[d, e]


def friction_dofs(k: np.ndarray, facet0: np.ndarray, node_pos: np.ndarray,
                  pos_m: np.ndarray) -> np.ndarray:
    """The interface positions the friction of nodes ``k`` couples (−1 left out)."""
    if not len(k):
        return np.zeros(0, np.int64)
    q = np.concatenate([node_pos[k].ravel(), pos_m[facet0[k]].ravel()])
    return np.ascontiguousarray(np.unique(q[q >= 0]), dtype=np.int64)


def power(lam: np.ndarray, k: np.ndarray, c: np.ndarray, mu: float, chi: float) -> float:
    """The friction's dissipated power ``Σ_k μ λ_k |c|²/sqrt(|c|² + χ²)``."""
    if not len(k):
        return 0.0
    c2 = np.sum(c * c, axis=1)
    return float(np.sum(mu * lam[k] * c2 / np.sqrt(c2 + chi * chi)))


def round_off(pair: Any, y: np.ndarray, lam: np.ndarray, k: np.ndarray, c: np.ndarray,
              frozen_: tuple[np.ndarray, np.ndarray, np.ndarray]) -> float:
    """The round-off of the friction part of f_c at the iterate y.

    As :func:`breakwater.contact.newtonaids.resolution` in 2-D: per node in contact
    ``μ λ_k |∂φ/∂c| ε Σ|v|`` (|∂φ/∂c| = 1/sqrt(|c|² + χ²), its largest eigenvalue), the
    velocities' magnitudes ``|v| + Δt |a| + β₁Δt |Δa|`` summed over the node's and its
    master face's DOFs (weighted by |N̄₀|); their root sum of squares.
    """
    if not len(k):
        return 0.0
    facet0, N0, _ = frozen_
    _, v, a, da = pair._start(y)
    dt = pair.step_dt()
    size = np.abs(v) + dt * np.abs(a) + pair.beta1 * dt * np.abs(da)
    size[-1] = 0.0
    node = size[pair._node_pos[k]].sum(axis=1) + np.einsum(
        "kb,kbd->k", np.abs(N0[k]), size[pair._pm[facet0[k]]])
    _, _, mu, chi = pair._law
    slope = 1.0 / np.sqrt(np.sum(c * c, axis=1) + chi * chi)
    r = mu * lam[k] * slope * float(np.finfo(float).eps) * node
    return float(np.sqrt(np.sum(r * r)))


def start_slip(pair: Any, frozen_: tuple[np.ndarray, np.ndarray, np.ndarray] | None
               ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`breakwater.contact.general.start_slip` of a 3-D pair.

    Per slave node in contact at the state, the slip velocity where the law gives the
    friction of the last step (projection ``frozen_``; None: the state's own), against
    it, in the tangent plane of the state's own projection, at most RELEASE χ; set as
    the velocities of the slave node's free components and, for its held ones (a node
    on a ``[fixed]`` face), of its master face's nodes
    (:func:`~breakwater.contact.newtonaids.slip_velocities_at`).

    Returns:
        The interface positions set and their velocities (flat).
    """
    from breakwater.contact.conforming import RELEASE

    none = np.zeros(0, np.int64), np.zeros(0)
    if not pair.spec.friction:
        return none
    u0, u1, v1 = pair._state()
    lam = pair._normal(u1)["lam"]
    _, _, mu, chi = pair._law
    now = frozen(pair, u0)
    lam_now, _ = newtonaids.friction_normals(lam, now[0])
    no = pair.crawl.none  # the law itself at every node
    k, c, _, _ = friction(lam_now, *now, pair._node_pos, pair._pm, v1, mu, chi, no)
    if not len(k):
        return none
    T = now[2][k]
    if frozen_ is None:
        speed = np.linalg.norm(c, axis=1)
        cap = RELEASE * chi
        c = c * (cap / np.maximum(speed, cap))[:, None]
        return newtonaids.slip_velocities_at(pair._node_pos, pair._pm, now[0], now[1], k,
                                             np.einsum("ka,kad->kd", c, T), pair.n)
    lam_f, _ = newtonaids.friction_normals(lam, frozen_[0])
    kf, _, F_k, _ = friction(lam_f, *frozen_, pair._node_pos, pair._pm, v1, mu, chi, no)
    force = np.zeros((len(lam), 3))
    force[kf] = F_k
    F = np.einsum("kad,kd->ka", T, force[k])  # in the state's tangent plane
    size = np.linalg.norm(F, axis=1)
    f = np.minimum(size / (mu * lam_now[k]), 1.0)
    speed = np.minimum(chi * f / np.sqrt(np.maximum(1.0 - f * f, 1e-300)), RELEASE * chi)
    against = -F / np.maximum(size, 1e-300)[:, None]
    return newtonaids.slip_velocities_at(pair._node_pos, pair._pm, now[0], now[1], k,
                                         np.einsum("ka,kad->kd", against * speed[:, None], T),
                                         pair.n)


@kernel
def slip_guard(step, v1, facet0, N0, T0, node_pos, pos_m, dv, chi, lin, lin_next,  # type: ignore[no-untyped-def]
               bounds, acts):
    """A 3-D pair's slip guard on Newton's step (``precheck``; in place).

    The 2-D pair's (:func:`breakwater.contact.guardkernels.slip_guard`, its arguments;
    t₀ is the tangent basis T₀ and the crawl points are tangent vectors ``(nodes, 2)``):
    per slave node with a start-of-step master point and free DOFs where it acts
    (``acts``), the slip vector of
    the iterate c₀ and of Newton's proposal c₁ (the iterate less the step); a step that
    reverses the slip (c₀·c₁ < 0) from outside the stick band (|c₀| > χ) lands at zero
    slip, any other whose linear model (at the node's crawl point where it has one)
    asks the law for a force within its curved zone lands where the law gives that
    force (:func:`~breakwater.contact.guardkernels.land`). The slave node's tangential
    step is set to give the landing slip (the slip is linear in Δa: exact); its normal
    step is kept. A slip crawling along the saturated law (a = the crawl point or c₀,
    a·c₁ > 0 and |c₁| > CRAWL |a|) is not moved: ``lin_next`` is where its law is
    linearised at the next iterate, along c₁ at the slip where the law gives the
    linear model's force, at most GROW (REGROW) |c₁|
    (:func:`~breakwater.contact.guardkernels.crawl_point`).

    Returns:
        The nodes whose step changed.
    """
    n = len(step)
    ext = np.zeros(n + 1)
    ext[:n] = step
    fixed = 0
    nm = N0.shape[1]
    c0, c1, target, a = np.empty(2), np.empty(2), np.empty(2), np.empty(2)
    vs, vm, ys, ym = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    for j in range(len(facet0)):
        lin_next[j, 0], lin_next[j, 1] = np.nan, np.nan
        f = facet0[j]
        if (f < 0 or node_pos[j, 0] < 0 or node_pos[j, 1] < 0 or node_pos[j, 2] < 0
                or not acts[j]):
            continue
        for d in range(3):
            vs[d], ys[d] = v1[node_pos[j, d]], ext[node_pos[j, d]]
            vm[d], ym[d] = 0.0, 0.0
            for b in range(nm):
                vm[d] += N0[j, b] * v1[pos_m[f, b, d]]
                ym[d] += N0[j, b] * ext[pos_m[f, b, d]]
        dot, size = 0.0, 0.0
        for q in range(2):
            c0[q], c1[q] = 0.0, 0.0
            for d in range(3):
                c0[q] += T0[j, q, d] * (vs[d] - vm[d])
                c1[q] += T0[j, q, d] * (ys[d] - ym[d])
            c1[q] = c0[q] - dv * c1[q]
            dot += c0[q] * c1[q]
            size += c0[q] * c0[q]
        if dot < 0 and size > chi * chi:
            target[0], target[1] = 0.0, 0.0
            bounds[j] = max(bounds[j], REVERSED)  # not a monotone crawl: a bounded one
        else:
            crawling = lin[j, 0] == lin[j, 0]
            for q in range(2):
                a[q] = lin[j, q] if crawling else c0[q]
            if land(a, c1, chi, target):
                if target[0] == c1[0] and target[1] == c1[1]:
                    continue
            else:
                along = a[0] * c1[0] + a[1] * c1[1]
                a2 = a[0] * a[0] + a[1] * a[1]
                c2 = c1[0] * c1[0] + c1[1] * c1[1]
                if along > 0 and c2 > CRAWL * CRAWL * a2 and bounds[j] != NONE:
                    speed = np.sqrt(c2)
                    far = crawl_point(np.sqrt(target[0] * target[0] + target[1] * target[1]),
                                      speed, chi, GROW if bounds[j] == FREE else REGROW)
                    for q in range(2):
                        lin_next[j, q] = far * c1[q] / speed
                continue
        # T₀·y_s = T₀·ȳ_m + (c₀ − target)/dv; the normal part of y_s kept.
        for q in range(2):
            along = (c0[q] - target[q]) / dv
            now = 0.0
            for d in range(3):
                along += T0[j, q, d] * ym[d]
                now += T0[j, q, d] * ys[d]
            for d in range(3):
                ys[d] += T0[j, q, d] * (along - now)
        for d in range(3):
            step[node_pos[j, d]] = ys[d]
        fixed += 1
    return fixed
