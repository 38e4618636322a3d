"""The contact pressure at a 3-D general pair's slave nodes, from its integration points.

The pressure field of the outputs (ParaView, snapshots, figures, the static summary) is
the traction the pair applies, ``p = ε_n⟨−g_n⟩₊`` at its integration points, carried to
the slave nodes by a lumped projection on the slave face's linear basis (the vertex hats
L_v, which are positive, unlike a 6-node triangle's vertex functions, whose integrals
vanish: no dual basis of them exists, see :mod:`breakwater.contact.general3d`):

    p_v = ∫ p L_v dS / ∫ L_v dS     at the vertices,
    p_m = ½ (p_a + p_b)             at the mid-edge node of the edge ab,

so ``Σ_v p_v ∫ L_v dS = ∫ p dS`` (the pair's normal resultant) and ``p_v ≥ 0``, a
weighted mean of the applied pressure around the vertex (as the 2-D pair's dual
projection, :func:`breakwater.contact.slavepoints.snapshot`, with the linear basis in
place of the dual one; Wohlmuth 2000 for the dual basis, Popp et al. 2012 on why a
quadratic triangle has none with positive weights). A uniform pressure is reproduced
exactly; a smooth one to O(h²) inside the contact, and the contact's edge is smeared
over a face. The law at the nodes' own projections (``law_pressure``) misses nodes
that have no projection (on a symmetry plane at the master's boundary, or below a
concave kink of the master when the penalty lets them in) and, between them, follows
the gap's variation over the P2 faces (measured on Hertz's point contact, element size
a/2: nodes at 0 inside the contact disc, the others −30 … +24 % of p₀; this projection
−16 … −3 %).
"""

from __future__ import annotations

import numpy as np

from breakwater.contact.clip3d import rule
from breakwater.contact.projection3d import shape

__all__ = ["VertexPressure", "linear_basis"]

_EDGES = ((1, 2), (0, 2), (0, 1))
"""The vertices of the mid-edge nodes 3, 4, 5 of a 6-node triangle (basix's order)."""


def linear_basis(N: np.ndarray) -> np.ndarray:
    """The vertex hats ``L_v`` ``(K, 3)`` from a triangle's shape function values ``N``.

    For 6 nodes ``L_a = N_a + ½ Σ N_e`` over the two edges e at vertex a (the quadratic
    basis reproduces the linear functions), for 3 nodes ``N`` itself.
    """
    if N.shape[1] == 3:
        return N
    L = N[:, :3].copy()
    for e, (a, b) in enumerate(_EDGES):
        L[:, a] += 0.5 * N[:, 3 + e]
        L[:, b] += 0.5 * N[:, 3 + e]
    return L


class VertexPressure:
    """The lumped linear projection of a slave surface's pressure onto its nodes.

    Args:
        sX: The slave faces' reference nodes ``(S, nn, 3)`` (3 or 6 nodes).
        node_of: Each face node's index in the pair's node order ``(S, nn)``.
        nodes: The number of slave nodes.
        area_element: ``|X_ξ × X_η|`` of faces at points
            (:func:`breakwater.contact.surfacesearch3d.area_element`).
    """

    def __init__(self, sX: np.ndarray, node_of: np.ndarray, nodes: int,
                 area_element: object) -> None:
        self._node_of = np.asarray(node_of, dtype=np.int64)
        self._nodes = nodes
        # ∫ L_v dS by a degree-5 rule (exact for L_v on a flat face; the area element of
        # a curved P2 face is integrated to the rule's accuracy).
        g, gw = rule(5)
        S, nn = len(sX), sX.shape[1]
        self.weight = np.zeros(nodes)
        if S:
            faces = np.repeat(np.arange(S), len(gw))
            xi = np.tile(g, (S, 1))
            dA = np.tile(gw, S) * area_element(sX[faces], xi)  # type: ignore[operator]
            L = linear_basis(shape(xi, nn)[0])
            np.add.at(self.weight, self._node_of[faces, :3].ravel(),
                      (dA[:, None] * L).ravel())
        self.vertices = self.weight > 0
        # Each mid-edge node's two vertices (−1: a vertex).
        self._ends = np.full((nodes, 2), -1, np.int64)
        if nn == 6:
            for e, (a, b) in enumerate(_EDGES):
                self._ends[self._node_of[:, 3 + e]] = self._node_of[:, [a, b]]

    def __call__(self, slave_facet: np.ndarray, Ns: np.ndarray, weight: np.ndarray,
                 pressure: np.ndarray) -> np.ndarray:
        """The nodal pressures ``(nodes,)`` of the integration points' pressures.

        Args:
            slave_facet: Each point's slave face.
            Ns: The slave shape functions at the points ``(K, nn)``.
            weight: The points' weights (reference area).
            pressure: Their pressures (0 where open).
        """
        out = np.zeros(self._nodes)
        if len(slave_facet):
            L = linear_basis(Ns)
            np.add.at(out, self._node_of[slave_facet, :3].ravel(),
                      ((pressure * weight)[:, None] * L).ravel())
        v = self.vertices
        out[v] /= self.weight[v]
        mid = self._ends[:, 0] >= 0
        out[mid] = 0.5 * (out[self._ends[mid, 0]] + out[self._ends[mid, 1]])
        return out
