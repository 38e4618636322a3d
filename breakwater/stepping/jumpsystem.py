"""The conforming pairs' Newton step on the jumps of the closed nodes (half the unknowns).

A conforming pair's forces depend on each node's jump alone, the difference of its two
sides' unknowns: ``∂f_c/∂y = Dᵀ Ŵ D``, where D maps the unknowns to the jumps (one row
per closed node and component, −1 on its slave unknown and +1 on its master one; a
Dirichlet side has none) and Ŵ is block diagonal, one gdim × gdim block per node
(:func:`~breakwater.contact.nodalkernels.nodal_tangents`, the blocks of
:func:`~breakwater.contact.nodalkernels.tangent_block`). Newton's step
``(1 + X_II Dᵀ Ŵ D) δ = G`` is then, with ĵ = D δ,

    (1 + C Ŵ) ĵ = D G,        C = D X_II Dᵀ,        δ = G − X_II Dᵀ (Ŵ ĵ),

the same step as the primal system on the closed nodes' unknowns
(:func:`~breakwater.stepping.interfacenewton.active_step`) in exact arithmetic, with a
dense solve of half its size: an eighth of its LU's work. C, the compliance of the
jumps, is formed when the closed nodes change (each entry the same ± sum of four
entries of X_II that the primal system's product forms); the system per iteration costs
|ĵ|² gdim. On ``goda3d`` at ``mesh.refinement = 2`` (3108 closed unknowns, 1554 jumps)
a Newton iteration took 0.045 s for the primal system's 0.211 s (its formation and LU;
record ``2026-11-28-jump-newton``).
"""

from __future__ import annotations

import numpy as np

from breakwater.common.jit import kernel
from breakwater.contact.nodalkernels import closed_nodes

__all__ = ["JumpSystem", "jump_compliance", "jump_rows", "jump_system"]


@kernel
def jump_rows(W, slave, master):  # type: ignore[no-untyped-def]
    """The jumps of the closed nodes: ``(Ŵ, s, m)`` (compiled).

    Args:
        W: The nodes' tangents, ``(nodes, gdim, gdim)`` (zero: an open node).
        slave: Each node's slave unknowns, ``(nodes, gdim)`` (−1: Dirichlet).
        master: Its master unknowns.

    Returns:
        Ŵ = −W of the closed nodes, ``(closed, gdim, gdim)``, and each jump's slave and
        master unknown, ``(closed · gdim,)`` each (node-major).
    """
    gdim = W.shape[1]
    closed = np.flatnonzero(closed_nodes(W))
    Wh = np.empty((len(closed), gdim, gdim))
    s = np.empty(len(closed) * gdim, np.int64)
    m = np.empty(len(closed) * gdim, np.int64)
    for k in range(len(closed)):
        r = closed[k]
        for i in range(gdim):
            s[k * gdim + i] = slave[r, i]
            m[k * gdim + i] = master[r, i]
            for j in range(gdim):
                Wh[k, i, j] = -W[r, i, j]
    return Wh, s, m


@kernel
def jump_compliance(X, s, m):  # type: ignore[no-untyped-def]
    """C = D X Dᵀ: ``C[p, q] = X[m_p, m_q] − X[m_p, s_q] − X[s_p, m_q] + X[s_p, s_q]``.

    The terms of a Dirichlet side (−1) are left out. X is read along its rows.

    Args:
        X: X_II, ``(n_I, n_I)``.
        s: The jumps' slave unknowns.
        m: Their master unknowns.
    """
    J = len(s)
    C = np.zeros((J, J))
    for p in range(J):
        for a, σa in ((s[p], -1.0), (m[p], 1.0)):
            if a < 0:
                continue
            row = X[a]
            for q in range(J):
                c = 0.0
                if s[q] >= 0:
                    c -= row[s[q]]
                if m[q] >= 0:
                    c += row[m[q]]
                C[p, q] += σa * c
    return C


@kernel
def jump_system(C, Wh):  # type: ignore[no-untyped-def]
    """``1 + C Ŵ`` with Ŵ block diagonal (``Wh``: its gdim × gdim blocks) (compiled)."""
    J = C.shape[0]
    gdim = Wh.shape[1]
    M = np.zeros((J, J))
    for p in range(J):
        for k in range(Wh.shape[0]):
            for j in range(gdim):
                acc = 0.0
                for i in range(gdim):
                    acc += C[p, k * gdim + i] * Wh[k, i, j]
                M[p, k * gdim + j] = acc
        M[p, p] += 1.0
    return M


@kernel
def _jump_forces(Wh, ĵ, s, m, n):  # type: ignore[no-untyped-def]
    """Dᵀ Ŵ ĵ on the n interface unknowns (B δ of the step)."""
    gdim = Wh.shape[1]
    out = np.zeros(n)
    for k in range(Wh.shape[0]):
        for i in range(gdim):
            f = 0.0
            for j in range(gdim):
                f += Wh[k, i, j] * ĵ[k * gdim + j]
            p = k * gdim + i
            if s[p] >= 0:
                out[s[p]] -= f
            if m[p] >= 0:
                out[m[p]] += f
    return out


class JumpSystem:
    """The step ``(1 + X_II Dᵀ Ŵ D) δ = G`` on the jumps (module doc), C kept.

    C is kept while X_II (by identity) and the closed nodes' unknowns stay: the
    iterations of a step, and the steps after it while no node opens or closes.
    """

    def __init__(self) -> None:
        self._kept: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None

    def compliance(self, X_II: np.ndarray, s: np.ndarray, m: np.ndarray) -> np.ndarray:
        """C for these jumps (kept)."""
        kept = self._kept
        if (kept is None or kept[0] is not X_II or not np.array_equal(kept[1], s)
                or not np.array_equal(kept[2], m)):
            self._kept = kept = (X_II, s, m, jump_compliance(X_II, s, m))
        return kept[3]

    def step(self, X_II: np.ndarray, G: np.ndarray, W: np.ndarray, slave: np.ndarray,
             master: np.ndarray) -> np.ndarray:
        """Newton's step δ.

        Args:
            X_II: The interface compliance.
            G: Newton's residual.
            W: The nodes' tangents (all pairs' nodes), ``(nodes, gdim, gdim)``.
            slave: Their slave unknowns (−1: Dirichlet), ``(nodes, gdim)``.
            master: Their master unknowns.

        Raises:
            np.linalg.LinAlgError: A singular system.
        """
        Wh, s, m = jump_rows(W, slave, master)
        if not len(s):
            return G.copy()
        DG = np.where(m >= 0, G[m], 0.0) - np.where(s >= 0, G[s], 0.0)
        ĵ = np.linalg.solve(jump_system(self.compliance(X_II, s, m), Wh), DG)
        return G - X_II @ _jump_forces(Wh, ĵ, s, m, len(G))
