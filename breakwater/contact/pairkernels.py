"""A conforming pair's per-step outputs from nodal arrays: compiled sums over its points.

The history's resultants of a conforming pair (contact length ``∫ [g_n ≤ 0] dS``, normal
resultant ``∫ ε_n ⟨−g_n⟩₊ dS``, tangential resultant ``∫ t_s·t dS``) and its ledger terms
(penalty energy, friction power, the interface share of the step's numerical
dissipation) are forms over the pair's measure, Gauss–Lobatto quadrature of degree 3 on
P2 facets (:meth:`breakwater.model.model.ContactModel._build_pair`), whose points are the
facets' nodes (:func:`breakwater.contact.nodal.quadrature_points`), where the basis
functions are Kronecker deltas. Each form is then a weighted sum over the (facet, node)
points of its integrand at the node's values with the facet's normal::

    ∫ f(u, v, n) dS = Σ_q w_q f(u(x_q), v(x_q), n_q).

:class:`NodalPairSums` gathers the nodal values once (one reduction, the same on every
rank) and evaluates the sums in compiled loops (:func:`breakwater.common.jit.kernel`), the
numbers of the assembled forms to round-off (``tests/test_pairkernels.py`` checks them
against the forms, which :class:`~breakwater.contact.pairstate.ConformingPair` keeps as
its reference and uses where the quadrature is not nodal: :func:`nodal_sums_apply`).
The integrands are those of :mod:`forms.contact` (the law), :mod:`forms.energy` and
:func:`forms.gn22_contact_dissipation`, written out in 2D.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater.common.jit import kernel
from breakwater.contact.conforming import InterfaceNodes
from breakwater.contact.nodal import nodal_contact_applies, quadrature_points
from breakwater.model.model import ContactModel

__all__ = ["NodalPairSums", "nodal_sums_apply"]


def nodal_sums_apply(model: ContactModel) -> bool:
    """Whether the nodal sums equal the forms (2D, affine cells, P2 Lagrange bodies).

    The kernels below are written out in 2D; a 3D pair keeps the assembled forms even
    where its contact forces are nodal (:func:`~breakwater.contact.nodal.nodal_contact_applies`).
    """
    return model.gdim == 2 and nodal_contact_applies(model)


@kernel
def resultant_sums(node: np.ndarray, weight: np.ndarray, normal: np.ndarray,
                   node_normal: np.ndarray, us: np.ndarray, um: np.ndarray, vs: np.ndarray,
                   vm: np.ndarray, eps: float, gap0: float, mu: float, chi: float
                   ) -> np.ndarray:
    """Contact length, normal and tangential resultants (2D; t = (n_y, −n_x)), penetration.

    Per point: g_n = (u_s − u_m)·n + g₀, p = ε_n ⟨−g_n⟩₊, v_T = (I − n⊗n)(v_s − v_m),
    t_s = p n − μ p v_T/sqrt(|v_T|² + χ²); sums of w [g_n ≤ 0], w p and w t_s·t. Then
    the largest ⟨−g_n⟩₊ at the nodes with their averaged normals ``node_normal``
    (:func:`breakwater.model.pairs.max_penetration` of
    :meth:`~breakwater.contact.conforming.InterfaceNodes.contact_state`'s gap).
    """
    out = np.zeros(4)
    for k in range(us.shape[0]):
        g = (us[k, 0] - um[k, 0]) * node_normal[k, 0] \
            + (us[k, 1] - um[k, 1]) * node_normal[k, 1] + gap0
        out[3] = max(out[3], -g)
    for q in range(node.shape[0]):
        k = node[q]
        n0, n1, w = normal[q, 0], normal[q, 1], weight[q]
        g = (us[k, 0] - um[k, 0]) * n0 + (us[k, 1] - um[k, 1]) * n1 + gap0
        if not g <= 0.0:
            continue  # open: no pressure, no traction
        p = eps * -g
        d0, d1 = vs[k, 0] - vm[k, 0], vs[k, 1] - vm[k, 1]
        dn = d0 * n0 + d1 * n1
        t0, t1 = d0 - dn * n0, d1 - dn * n1
        s = math.sqrt(t0 * t0 + t1 * t1 + chi * chi)
        f0 = p * n0 - mu * p * (t0 / s)
        f1 = p * n1 - mu * p * (t1 / s)
        out[0] += w
        out[1] += w * p
        out[2] += w * (f0 * n1 - f1 * n0)
    return out


@kernel
def energy_sums(node: np.ndarray, weight: np.ndarray, normal: np.ndarray,
                us: np.ndarray, um: np.ndarray, vs: np.ndarray, vm: np.ndarray,
                u0s: np.ndarray, u0m: np.ndarray, v0s: np.ndarray, v0m: np.ndarray,
                eps: float, gap0: float, mu: float, chi: float, dt: float,
                step: bool) -> np.ndarray:
    """Penalty energy, friction power and (``step``) the interface numerical dissipation.

    Per point, at (u, v) = (u₁, v₁): ½ p²/ε_n and μ p |v_T|²/sqrt(|v_T|² + χ²)
    (= −t_T·v_T); from (u₀, v₀) to (u₁, v₁) (:func:`forms.gn22_contact_dissipation`):
    −½(p₀ + p₁)(g₁ − g₀) − (½p₁²/ε_n − ½p₀²/ε_n) − ½ Σ_k t_Tk·(Δj − Δt v_Tk),
    Δj = (u₁ₛ − u₁ₘ) − (u₀ₛ − u₀ₘ), t_T = −μ p v_T/sqrt(|v_T|² + χ²).
    """
    out = np.zeros(3)
    for q in range(node.shape[0]):
        k = node[q]
        n0, n1, w = normal[q, 0], normal[q, 1], weight[q]
        j0, j1 = us[k, 0] - um[k, 0], us[k, 1] - um[k, 1]
        g1 = j0 * n0 + j1 * n1 + gap0
        p1 = eps * -g1 if g1 <= 0.0 else 0.0
        d0, d1 = vs[k, 0] - vm[k, 0], vs[k, 1] - vm[k, 1]
        dn = d0 * n0 + d1 * n1
        a0, a1 = d0 - dn * n0, d1 - dn * n1
        s1 = math.sqrt(a0 * a0 + a1 * a1 + chi * chi)
        e1 = 0.5 * p1 * p1 / eps
        out[0] += w * e1
        out[1] += w * (mu * p1 * ((a0 * a0 + a1 * a1) / s1))
        if not step:
            continue
        i0, i1 = u0s[k, 0] - u0m[k, 0], u0s[k, 1] - u0m[k, 1]
        g0 = i0 * n0 + i1 * n1 + gap0
        p0 = eps * -g0 if g0 <= 0.0 else 0.0
        c0, c1 = v0s[k, 0] - v0m[k, 0], v0s[k, 1] - v0m[k, 1]
        cn = c0 * n0 + c1 * n1
        b0, b1 = c0 - cn * n0, c1 - cn * n1
        s0 = math.sqrt(b0 * b0 + b1 * b1 + chi * chi)
        e0 = 0.5 * p0 * p0 / eps
        Δj0, Δj1 = j0 - i0, j1 - i1
        total = -0.5 * (p0 + p1) * (g1 - g0) - (e1 - e0)
        # t_T·(Δj − Δt v_T) at the start (p₀, v_T0) and at the end (p₁, v_T1).
        total += -0.5 * (-mu * p0 / s0) * (b0 * (Δj0 - dt * b0) + b1 * (Δj1 - dt * b1))
        total += -0.5 * (-mu * p1 / s1) * (a0 * (Δj0 - dt * a0) + a1 * (Δj1 - dt * a1))
        out[2] += w * total
    return out


class NodalPairSums:
    """A conforming pair's forms as sums over its quadrature points, from nodal arrays.

    Only where :func:`nodal_sums_apply` (2D, affine cells, P2 bodies): its points are the
    interface nodes.

    Args:
        model: The contact model.
        nodes: The pair's node pairs (its pair's law gives the parameters).
    """

    def __init__(self, model: ContactModel, nodes: InterfaceNodes) -> None:
        if not nodal_sums_apply(model):
            raise ValueError("the nodal sums need 2D affine cells and P2 bodies")
        self.nodes, self.comm, self.gdim = nodes, model.comm, nodes.gdim
        self.pair = pair = nodes.pair
        node, weight, normal = quadrature_points(model, nodes)
        self.node = np.ascontiguousarray(node, dtype=np.int64)
        self.weight = np.ascontiguousarray(weight, dtype=np.float64)
        self.normal = np.ascontiguousarray(normal, dtype=np.float64)
        self.node_normal = np.ascontiguousarray(nodes.normal, dtype=np.float64)
        # Each side's owned interface entries (component-wise) and their places in the
        # gathered (nodes, gdim) arrays.
        comps = np.arange(self.gdim)
        self._sides = [(body, (blocks[:, None] * self.gdim + comps).ravel(),
                        (pos[:, None] * self.gdim + comps).ravel())
                       for body, (blocks, pos) in ((pair.slave, nodes._slave),
                                                   (pair.master, nodes._master))]
        # The law's parameters: views of the Constants' values (read when used).
        law = pair.law
        self._parameters = [np.asarray(getattr(c, "value", c), dtype=np.float64)
                            for c in (law.normal.ε_n, law.normal.g0, law.friction.μ,
                                      law.friction.χ)]
        # Compiled (or loaded from numba's cache) now, not in the time loop.
        zero = np.zeros((2, 2, nodes.size, self.gdim))
        self.resultants(zero)
        self.energies(zero, zero, 1.0)

    def parameters(self) -> tuple[float, float, float, float]:
        """The law's ε_n, g₀, μ, χ now (floats; ``fem.Constant`` s' values)."""
        eps, g0, mu, chi = (float(c) for c in self._parameters)
        return eps, g0, mu, chi

    def gatherer(self, states: Sequence[Sequence[fem.Function]]) -> NodalGather:
        """A :class:`NodalGather` of the given states (each one Function per body)."""
        return NodalGather(self, states)

    def resultants(self, uv: np.ndarray) -> np.ndarray:
        """Contact length, normal and tangential resultants, largest nodal penetration.

        Args:
            uv: Gathered (u, v) (:class:`NodalGather`).
        """
        return resultant_sums(self.node, self.weight, self.normal, self.node_normal,
                              uv[0, 0], uv[0, 1], uv[1, 0], uv[1, 1], *self.parameters())

    def energies(self, uv: np.ndarray, uv0: np.ndarray | None, dt: float) -> np.ndarray:
        """Penalty energy, friction power, numerical dissipation (0 without ``uv0``).

        Args:
            uv: Gathered (u, v) at the end of the step.
            uv0: Gathered (u, v) at its start; None: the first record.
            dt: The step's Δt.
        """
        start = uv if uv0 is None else uv0
        return energy_sums(self.node, self.weight, self.normal, uv[0, 0], uv[0, 1],
                           uv[1, 0], uv[1, 1], start[0, 0], start[0, 1], start[1, 0],
                           start[1, 1], *self.parameters(), dt, uv0 is not None)


class NodalGather:
    """Nodal values of both sides of fixed states, on every rank (one reduction).

    Args:
        sums: The pair's sums (its nodes and sides).
        states: The states, each one Function per body; their arrays are read at
            each call (views kept: the Functions' storage does not move).
    """

    def __init__(self, sums: NodalPairSums, states: Sequence[Sequence[fem.Function]]) -> None:
        self.comm = sums.comm
        self.out = np.zeros((len(states), 2, sums.nodes.size, sums.gdim))
        flat = self.out.reshape(len(states), 2, -1)
        self._takes = [(flat[i, k], place, f[body].x.array, local)
                       for i, f in enumerate(states)
                       for k, (body, local, place) in enumerate(sums._sides)]

    def __call__(self) -> np.ndarray:
        """Shape ``(states, 2, nodes, gdim)``: per state the slave's and master's values."""
        if self.comm.size > 1:
            self.out[:] = 0.0  # the other ranks' nodes: their values come in the sum
        for out, place, array, local in self._takes:
            out[place] = array[local]
        if self.comm.size > 1:
            self.comm.Allreduce(MPI.IN_PLACE, self.out, op=MPI.SUM)
        return self.out
