"""The contact forces of a conforming pair on nodal arrays, for the fast step solver.

The interface forms integrate with Gauss–Lobatto quadrature of degree 3 on P2 facets
(:meth:`breakwater.model.model.ContactModel._build_pair`): in 2D its points are the facet's
three P2 nodes (the ends and the midpoint, Simpson's weights L/6, 4L/6, L/6), where
the basis functions are Kronecker deltas. The assembled contact residual is then a sum
over (facet, node) points of the law at the node with that facet's normal,

    f_s = −Σ w t(u_s − u_m, v_s − v_m, n_f),       f_m = +Σ w t(...),

and its derivative in Δa, through u₁ = ũ + ½β₂Δt² Δa and v₁ = ṽ + β₁Δt Δa, is made of
the law's nodal derivatives (:meth:`forms.ContactLaw.nodal`).
:class:`NodalContactForces` evaluates these with NumPy on the interface nodes (gathered
on every rank in a partition-independent order: no form assembly, at most one
reduction per call), the same numbers as the UFL assembly to round-off
(``tests/test_nodalcontact.py``). :func:`nodal_contact_applies` says when it is exact
(2D, affine geometry, P2 Lagrange bodies); elsewhere the fast solver assembles the UFL
forms (:class:`~breakwater.stepping.condensed.InterfaceAssembler`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

import basix
import dolfinx
import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater import forms  # type: ignore[attr-defined]
from breakwater.contact.conforming import InterfaceNodes
from breakwater.model.layout import MonolithicLayout
from breakwater.model.model import ContactModel

__all__ = ["NodalContactForces", "nodal_contact_applies", "quadrature_points"]


def nodal_contact_applies(model: ContactModel) -> bool:
    """Whether the nodal evaluation equals the forms' (2D, affine cells, P2 Lagrange)."""
    if model.gdim != 2 or model.mesh.topology.dim != 2:
        return False
    if model.mesh.geometry.cmaps[0].degree != 1:
        return False
    for b in model.bodies:
        e = b.V.ufl_element().basix_element
        if e.family != basix.ElementFamily.P or e.degree != 2 or e.discontinuous:
            return False
    return True


def quadrature_points(model: ContactModel, nodes: InterfaceNodes
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every quadrature point of a conforming pair: its node, weight and facet normal.

    In a partition-independent order (sorted by node, then by the facet's other
    node), the same on every rank.
    """
    msh, pair = model.mesh, nodes.pair
    tdim = msh.topology.dim
    points, weights = basix.make_quadrature(basix.CellType.interval, 3,
                                            rule=basix.QuadratureType.gll)
    c2f = msh.topology.connectivity(tdim, tdim - 1)
    facets = np.array([c2f.links(c)[lf] for c, lf in pair.facet_data[:, :2]],
                      dtype=np.int32)
    fx = dolfinx.mesh.entities_to_geometry(msh, tdim - 1, facets)
    cx = dolfinx.mesh.entities_to_geometry(msh, tdim, pair.facet_data[:, 0])
    X = msh.geometry.x[:, : nodes.gdim]
    scale = max(float(np.ptp(nodes.x, axis=0).max()), 1e-300)
    local = []
    for f, c in zip(fx, cx, strict=True):
        v = X[f[:2]]
        t = v[1] - v[0]
        length = float(np.linalg.norm(t))
        normal = np.array([t[1], -t[0]]) / length
        if np.dot(X[c].mean(axis=0) - v.mean(axis=0), normal) < 0:  # into the slave
            normal = -normal
        for xi, w in zip(points[:, 0], weights, strict=True):
            x = v[0] + xi * t
            d = np.linalg.norm(nodes.x - x, axis=1)
            k = int(np.argmin(d))
            if d[k] > 1e-9 * scale:
                raise ValueError(f"interface '{pair.spec.interface}': a quadrature point "
                                 "is not a node")
            local.append((k, w * length, *normal))
    table = np.array([row for part in model.comm.allgather(local) for row in part])
    table = table[np.lexsort((table[:, 3], table[:, 2], table[:, 0]))]
    return table[:, 0].astype(np.int64), table[:, 1], table[:, 2:]


class NodalContactForces:
    """f_c and ∂f_c/∂Δa of one conforming pair on the interface unknowns, from nodal arrays.

    The provider protocol of :class:`~breakwater.stepping.condensed.CondensedNewton`:
    :meth:`vector` and :meth:`matrix` at the current state Functions (u, v, a at t and
    the step's Δa), the same on every rank.

    Args:
        model: The contact model.
        nodes: The pair's node pairs.
        layout: Stacked-vector layout of the model.
        interface: Global stacked indices of the interface unknowns (sorted).
        state: ``(u, v, a, Δa)``, one Function per body each.
        dt: The step size constant.
        beta1: GN22 β₁.
        beta2: GN22 β₂.
        kinematics: The GN22 update ``(u, v, a, Δa, Δt, β₁, β₂) -> (u₁, v₁, a₁)`` on
            arrays (:func:`breakwater.stepping.gn22.gn22_kinematics`).
    """

    def __init__(self, model: ContactModel, nodes: InterfaceNodes, layout: MonolithicLayout,
                 interface: np.ndarray,
                 state: tuple[Sequence[fem.Function], Sequence[fem.Function],
                              Sequence[fem.Function], Sequence[fem.Function]],
                 dt: fem.Constant, beta1: float, beta2: float,
                 kinematics: Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray]]) -> None:
        self.comm = model.comm
        self.nodes = nodes
        self.pair = pair = nodes.pair
        self.u, self.v, self.a, self.da = state
        self.dt, self.beta1, self.beta2 = dt, beta1, beta2
        self.kinematics = kinematics
        self.n = n = len(interface)
        gdim = nodes.gdim
        node, weight, normal = quadrature_points(model, nodes)
        self._node = node
        self._weight = weight
        self._normal = normal
        # Interface position of each node's components on each side (−1: not an unknown).
        where = np.full((2, nodes.size, gdim), -1, np.int64)
        for k, (body, (blocks, pos)) in enumerate(((pair.slave, nodes._slave),
                                                   (pair.master, nodes._master))):
            bs = layout.bs[body]
            g = layout.global_index[body][(blocks[:, None] * bs + np.arange(gdim)).ravel()]
            at = np.minimum(np.searchsorted(interface, g), max(n - 1, 0))
            hit = interface[at] == g if n else np.zeros(len(g), bool)
            where[k, pos] = np.where(hit, at, -1).reshape(-1, gdim)
        self.comm.Allreduce(MPI.IN_PLACE, where, op=MPI.MAX)
        # Residual rows: slave rows get −w t, master rows +w t, at each point's node.
        rows = np.concatenate([where[0][node], where[1][node]]).reshape(-1)
        self._rows_keep = np.flatnonzero(rows >= 0)
        self._rows = rows[self._rows_keep]
        # Jacobian entries: blocks (s,s) −wD, (s,m) +wD, (m,s) +wD, (m,m) −wD.
        r_idx = [where[0][node], where[1][node]]  # (q, gdim) each
        flat, sign = [], []
        for a_side, b_side, sgn in ((0, 0, -1.0), (0, 1, 1.0), (1, 0, 1.0), (1, 1, -1.0)):
            ri = r_idx[a_side][:, :, None]
            ci = r_idx[b_side][:, None, :]
            valid = (ri >= 0) & (ci >= 0)
            flat.append(np.where(valid, ri * n + ci, -1))
            sign.append(sgn)
        flat_all = np.stack(flat)  # (4, q, gdim, gdim)
        self._sign = np.array(sign)[:, None, None, None]
        self._flat_keep = np.flatnonzero(flat_all.reshape(-1) >= 0)
        self._flat = flat_all.reshape(-1)[self._flat_keep]
        # For left_product: the points of each node (sorted by node: runs), each node's
        # columns on both sides (−1 → a zero column n of an extended X).
        self._runs = np.flatnonzero(np.r_[True, node[1:] != node[:-1]])
        self._run_nodes = node[self._runs]
        self._cols = [np.where(where[k][self._run_nodes] >= 0, where[k][self._run_nodes], n)
                      for k in (0, 1)]
        self._extended: tuple[np.ndarray, np.ndarray] | None = None
        # The owned entries of the pair's nodes in each side's local arrays, and their
        # places in the gathered nodal arrays (node-major, component-minor).
        comps = np.arange(gdim)
        self._take = []
        for (blocks, pos), body in ((nodes._slave, pair.slave), (nodes._master, pair.master)):
            bs = layout.bs[body]
            arrays = [f[body].x.array for f in (self.u, self.v, self.a, self.da)]
            self._take.append(((blocks[:, None] * bs + comps).ravel(),
                               (pos[:, None] * gdim + comps).ravel(), arrays))
        self._gathered = np.zeros((2, 2, nodes.size * gdim))
        # Point values from the gathered arrays: the node of each point, per component.
        self._at_points = (node[:, None] * gdim + comps).ravel()
        constants = [getattr(part, f.name) for part in (pair.law.normal, pair.law.friction)
                     for f in dataclasses.fields(part)]
        self._constants = [c for c in constants if isinstance(c, fem.Constant)]
        self._law_key: tuple[float, ...] | None = None
        self._law = pair.law.values()

    def _state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """u₁, v₁ of both sides at the quadrature points (one reduction under MPI)."""
        gdim = self.nodes.gdim
        out = self._gathered
        if self.comm.size > 1:
            out[:] = 0.0  # the other ranks' nodes: their values come in the sum
        dt = float(self.dt.value)
        for k, (local, place, arrays) in enumerate(self._take):
            u1, v1, _ = self.kinematics(*(x[local] for x in arrays), dt, self.beta1,
                                        self.beta2)
            out[0, k, place] = u1
            out[1, k, place] = v1
        if self.comm.size > 1:
            self.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        at = out[:, :, self._at_points].reshape(2, 2, -1, gdim)
        return at[0, 0], at[0, 1], at[1, 0], at[1, 1]

    def _values(self) -> forms.ContactLaw:
        """The pair's law with float parameters (their values now)."""
        key = tuple(float(c.value) for c in self._constants)
        if key != self._law_key:
            self._law, self._law_key = self.pair.law.values(), key
        return self._law

    def vector(self) -> np.ndarray:
        """f_c on the interface unknowns (the same on every rank)."""
        us, um, vs, vm = self._state()
        law = self._values()
        t = law.nodal(us, um, self._normal, vs, vm)
        wt = self._weight[:, None] * t
        values = np.concatenate([-wt, wt]).reshape(-1)[self._rows_keep]
        return np.bincount(self._rows, weights=values, minlength=self.n)

    def matrix(self) -> np.ndarray:
        """∂f_c/∂y on the interface unknowns, dense (the same on every rank)."""
        D = self._point_tangents()
        values = (self._sign * D[None]).reshape(-1)[self._flat_keep]
        out = np.bincount(self._flat, weights=values, minlength=self.n * self.n)
        return out.reshape(self.n, self.n)

    def _node_tangents(self) -> np.ndarray:
        """W_k = Σ w ∂t/∂y over the points of each node k, shape ``(nodes, gdim, gdim)``."""
        return np.add.reduceat(self._point_tangents(), self._runs, axis=0)

    def _point_tangents(self) -> np.ndarray:
        """The weighted tangent w ∂t/∂y at each point, shape ``(points, gdim, gdim)``.

        ∂y = ½β₂Δt² ∂u + β₁Δt ∂v: the step's unknown moves u and v together.
        """
        us, um, vs, vm = self._state()
        dt = float(self.dt.value)
        _, t_u, t_v = self._values().nodal(us, um, self._normal, vs, vm, derivatives=True)
        return self._weight[:, None, None] * (0.5 * self.beta2 * dt**2 * t_u
                                              + self.beta1 * dt * t_v)

    def left_product(self, X: np.ndarray) -> np.ndarray:
        """X @ :meth:`matrix` for a dense X of n_I columns, from the matrix's structure.

        The matrix couples only the two sides of one node: its slave columns of node k
        are −W_k and its master columns +W_k, times the rows ``s_k − m_k``, so
        ``(X ∂f_c)[:, s_k] = −R_k W_k`` and ``[:, m_k] = R_k W_k`` with
        ``R_k = X[:, s_k] − X[:, m_k]``: O(n_I²) work instead of the dense O(n_I³).
        """
        W = self._node_tangents()
        if self._extended is None or self._extended[0] is not X:
            Xe = np.zeros((X.shape[0], self.n + 1))
            Xe[:, : self.n] = X
            self._extended = (X, Xe)
        Xe = self._extended[1]
        R = Xe[:, self._cols[0]] - Xe[:, self._cols[1]]  # (rows, nodes, gdim)
        Y = np.einsum("aki,kij->akj", R, W)
        out = np.zeros((X.shape[0], self.n + 1))
        out[:, self._cols[0]] = -Y
        out[:, self._cols[1]] = Y  # the −1 columns land in the extra column n
        return out[:, : self.n]

