"""Where the slip guard acts: at the nodes whose own friction law sets their slip.

The slip guard (:mod:`breakwater.contact.guardkernels`) lands a node's slip on the law's
curve and linearises a crawling slip's law further along (its crawl points). Both assume
that the node's slip is set by its own friction force: that the law's stiffness at stick,
``μ λ β₁Δt / χ`` (the force per unit of Δa; λ the node's normal force), dwarfs the bulk's
there. The interface Newton's bulk stiffness on its unknowns is the condensed matrix S
(``F = S (y − z) + f_c``, :mod:`breakwater.stepping.interfacenewton`), and a slave node's is
``t·S·t`` on the node's block along its tangent(s) (:meth:`BulkStiffness.tangential`).

With the paper's χ = 1e-10 the law is stiffer than the bulk by many orders. With a
moderate χ it is not: a 3-D block pushed below μN with χ = 1e-3 (``tests/
test_pair3d_friction.py``'s creep) has ``μλβ₁Δt/χ`` at 0.01–0.1 of its nodes' ``S_tt``.
There the elastic block holds each node to its neighbours and Newton's own proposal is
already right, but the guard read a proposal of 1.5χ as a slip growing beyond the curved
zone, linearised the law at 111χ, landed the node at 64χ, and the iteration crept back
by ×0.58 an iteration: 15, 14, 14 Newton iterations a step against 6, 5, 6 without the
guard, the same state. The guard now acts only where the law is at least
:data:`COUPLING` times the bulk's stiffness (:func:`guarded_nodes`). Measured, Newton
iterations before → after: that creep 110 → 42 over 8 steps; at χ = 1e-4 14, 11, 12 → 14,
9, 9 (3 steps); at χ = 1e-10 18, 11, 11, unchanged. The default Goda case (conforming)
to 0.05 s with χ = 1e-3: 1646 → 1132, the same as without any guard; with the paper's
χ = 1e-10: 983, unchanged (without the guard that run failed after 177 steps).
``examples/goda_apart`` 3758 → 3756, ``examples/goda_nonmatching.toml`` 3937 → 3929;
every headline line of these runs the same. A threshold of 1 instead of 0.1 (a patch
measured before this module): creep 6, 5, 6 at χ = 1e-3 but the hand-meshed Goda case
4032 (max 204 in a step): slips crawled that the guard had held. Where S's block is
not known (a DOF that is not an unknown), the guard acts.

The reference path's SNES has no S: its guard acts at every node, as before.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from breakwater.common.jit import kernel

__all__ = ["COUPLING", "BulkStiffness", "guarded_nodes", "tangential_stiffness"]

#: The slip guard acts at a node whose law at stick is at least this stiff against the bulk.
COUPLING = 0.1


@dataclasses.dataclass(frozen=True)
class BulkStiffness:
    """The bulk's stiffness on the interface Newton's unknowns.

    Attributes:
        S: The condensed stiffness ``S = X_II⁻¹`` on the Newton's unknowns.
        index: The row of S of each interface unknown (−1: not among S's unknowns);
            None: the interface unknowns are S's own.
    """

    S: np.ndarray
    index: np.ndarray | None = None

    def tangential(self, pos: np.ndarray, tangents: np.ndarray) -> np.ndarray:
        """The bulk's stiffness along the tangents at nodes: ``t·S·t`` on each node's block.

        Args:
            pos: The nodes' interface positions ``(nodes, gdim)`` (−1: not an unknown).
            tangents: Their unit tangents ``(nodes, gdim)``, or tangent bases
                ``(nodes, 2, gdim)`` (then the mean over the two).

        Returns:
            Per node (NaN where a component is not among S's unknowns).
        """
        T = tangents[:, None, :] if tangents.ndim == 2 else tangents
        out = np.empty(len(pos))
        tangential_stiffness(self.S, _NO_INDEX if self.index is None else self.index,
                             pos, T, out)
        return out


_NO_INDEX = np.zeros(0, np.int64)


@kernel
def tangential_stiffness(S, index, pos, T, out):  # type: ignore[no-untyped-def]
    """:meth:`BulkStiffness.tangential`, compiled.

    In NumPy (fancy indexing and einsum) it took 50 µs a call, 2 % of the time loop of the
    Goda case at refinement 3.

    Args:
        S: The condensed stiffness.
        index: The row of S of each interface unknown (−1: none); empty: the unknown's own.
        pos: The nodes' interface positions ``(nodes, gdim)``.
        T: Their tangents ``(nodes, tangents, gdim)``.
        out: Out: per node, the mean over its tangents of ``t·S·t`` (NaN: a row unknown).
    """
    gdim = pos.shape[1]
    rows = np.empty(gdim, np.int64)
    for k in range(pos.shape[0]):
        known = True
        for i in range(gdim):
            p = pos[k, i]
            rows[i] = -1 if p < 0 else (index[p] if index.size else p)
            known = known and rows[i] >= 0
        if not known:
            out[k] = np.nan
            continue
        total = 0.0
        for a in range(T.shape[1]):
            for i in range(gdim):
                for j in range(gdim):
                    total += T[k, a, i] * S[rows[i], rows[j]] * T[k, a, j]
        out[k] = total / T.shape[1]


def guarded_nodes(lam: np.ndarray, stick: float, bulk: BulkStiffness | None,
                  pos: np.ndarray, tangents: np.ndarray) -> np.ndarray:
    """Where the slip guard acts (the module doc): the law at stick at least COUPLING S_tt.

    Args:
        lam: The nodes' normal forces λ.
        stick: The law's stick stiffness per unit normal force, ``μ β₁Δt / χ``.
        bulk: The bulk's stiffness; None: unknown (the guard acts at every node).
        pos: The nodes' interface positions.
        tangents: Their tangents (:meth:`BulkStiffness.tangential`).

    Returns:
        Per node, whether the guard acts (also where the bulk's stiffness is unknown).
    """
    acts = np.ones(len(lam), bool)
    if bulk is not None and len(lam):
        soft = stick * np.maximum(lam, 0.0) < COUPLING * bulk.tangential(pos, tangents)
        acts[soft] = False
    return acts
