"""The contact forces of a conforming pair on nodal arrays, for the fast step solver.

The interface forms integrate with Gauss–Lobatto quadrature of degree 3 on P2 facets
(:meth:`breakwater.model.model.ContactModel._build_pair`): in 2D its points are the facet's
three P2 nodes (the ends and the midpoint, Simpson's weights L/6, 4L/6, L/6), where
the basis functions are Kronecker deltas. The assembled contact residual is then a sum
over (facet, node) points of the law at the node with that facet's normal,

    f_s = −Σ w t(u_s − u_m, v_s − v_m, n_f),       f_m = +Σ w t(...),

and its derivative in Δa, through u₁ = ũ + ½β₂Δt² Δa and v₁ = ṽ + β₁Δt Δa, is made of
the law's nodal derivatives. :class:`NodalContactForces` evaluates these in compiled
kernels (:mod:`breakwater.contact.nodalkernels`) on the interface nodes, gathered on
every rank in a partition-independent order once per step (no form assembly, no
communication per Newton iteration): the same numbers as the UFL assembly to round-off
(``tests/test_nodalcontact.py``). :func:`nodal_contact_applies` says when it is exact
(P2 Lagrange bodies, flat affine interface facets: intervals in 2D, parallelograms of
hexahedra in 3D, where the points are the facet's nine nodes; the penalty and regularised
Coulomb laws the kernels encode); elsewhere the fast solver assembles the UFL forms
(:class:`~breakwater.stepping.condensed.InterfaceAssembler`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import basix
import dolfinx
import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater import forms  # type: ignore[attr-defined]
from breakwater.contact.conforming import InterfaceNodes
from breakwater.contact.coupling import BulkStiffness, guarded_nodes
from breakwater.contact.nodalkernels import (
    guard_steps,
    nodal_left_product,
    nodal_residual,
    nodal_state,
    nodal_tangents,
    normal_forces,
    tangent_block,
)
from breakwater.model.layout import MonolithicLayout
from breakwater.model.mesh import facet_type
from breakwater.model.model import ContactModel, PairData

__all__ = ["NodalContactForces", "nodal_contact_applies", "quadrature_points"]


def nodal_contact_applies(model: ContactModel) -> bool:
    """Whether the nodal evaluation equals the forms' (collective).

    P2 Lagrange bodies, every pair's law the one the kernels encode
    (:class:`forms.PenaltyContact`, :class:`forms.RegularisedCoulomb`), and flat
    interface facets on which the nodes are the Gauss–Lobatto points of an affine map:
    in 2D affine cells; in 3D hexahedra whose interface facets are parallelograms
    (their geometry nodes, if quadratic, at the affine positions: :func:`_affine_facets`).
    """
    tdim = model.mesh.topology.dim
    for p in model.pairs:
        if (type(p.law.normal) is not forms.PenaltyContact
                or type(p.law.friction) is not forms.RegularisedCoulomb):
            return False
    for b in model.bodies:
        e = b.V.ufl_element().basix_element
        if e.family != basix.ElementFamily.P or e.degree != 2 or e.discontinuous:
            return False
    if model.gdim != tdim:
        return False
    if tdim == 2:
        return model.mesh.geometry.cmaps[0].degree == 1
    if tdim != 3 or facet_type(model.mesh) != dolfinx.mesh.CellType.quadrilateral:
        return False
    flat = all(_affine_facets(model, p) for p in model.pairs)
    return bool(model.comm.allreduce(flat, op=MPI.LAND))


def _facets(model: ContactModel, pair: PairData) -> tuple[np.ndarray, np.ndarray]:
    """The geometry nodes of a pair's facets (this rank's) and of their slave cells."""
    msh = model.mesh
    tdim = msh.topology.dim
    c2f = msh.topology.connectivity(tdim, tdim - 1)
    facets = np.array([c2f.links(c)[lf] for c, lf in pair.facet_data[:, :2]],
                      dtype=np.int32)
    return (dolfinx.mesh.entities_to_geometry(msh, tdim - 1, facets),
            dolfinx.mesh.entities_to_geometry(msh, tdim, pair.facet_data[:, 0]))


def _reference_points(msh: dolfinx.mesh.Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Lobatto points of degree 3 on the reference facet ([0, 1] or [0, 1]²)."""
    cell = basix.CellType.interval if msh.topology.dim == 2 else basix.CellType.quadrilateral
    return basix.make_quadrature(cell, 3, rule=basix.QuadratureType.gll)


def _affine_map(v: np.ndarray, points: np.ndarray
                ) -> tuple[np.ndarray, float, np.ndarray]:
    """A facet's affine map from its corners ``v``: the points, its measure and normal.

    An interval x = v₀ + ξ (v₁ − v₀); a quadrilateral (dolfinx's order: v₃ opposite
    v₀) x = v₀ + ξ (v₁ − v₀) + η (v₂ − v₀). The normal is unoriented.
    """
    if len(v) == 2:
        t = v[1] - v[0]
        length = float(np.linalg.norm(t))
        return v[0] + points[:, :1] * t, length, np.array([t[1], -t[0]]) / length
    a, b = v[1] - v[0], v[2] - v[0]
    cross = np.cross(a, b)
    area = float(np.linalg.norm(cross))
    return v[0] + points[:, :1] * a + points[:, 1:2] * b, area, cross / area


def _affine_facets(model: ContactModel, pair: PairData) -> bool:
    """Whether this rank's facets of a 3D pair are parallelograms with affine nodes.

    Each facet's geometry nodes (if quadratic) must lie at the affine map's
    Gauss–Lobatto points: the nodes are then the quadrature points and the facet's
    Jacobian is constant.
    """
    points, _ = _reference_points(model.mesh)
    X = model.mesh.geometry.x
    fx, _ = _facets(model, pair)
    for f in fx:
        x = X[f]
        mapped, _, _ = _affine_map(x[:4], points)
        tol = 1e-9 * float(np.ptp(x, axis=0).max())
        if np.linalg.norm(x[3] - (x[1] + x[2] - x[0])) > tol:
            return False
        d = np.linalg.norm(x[:, None, :] - mapped[None, :, :], axis=2)
        if len(x) > 4 and not (d.min(axis=1).max() <= tol and d.min(axis=0).max() <= tol):
            return False
    return True


def quadrature_points(model: ContactModel, nodes: InterfaceNodes
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every quadrature point of a conforming pair: its node, weight and facet normal.

    The Gauss–Lobatto points of degree 3 of each facet (intervals in 2D,
    quadrilaterals in 3D) mapped affinely from its corners, each matched to its node.
    In a partition-independent order (sorted by node, then by weight and normal), the
    same on every rank.
    """
    msh, pair = model.mesh, nodes.pair
    points, weights = _reference_points(msh)
    corners = 2 if msh.topology.dim == 2 else 4
    fx, cx = _facets(model, pair)
    X = msh.geometry.x[:, : nodes.gdim]
    scale = max(float(np.ptp(nodes.x, axis=0).max()), 1e-300)
    local = []
    for f, c in zip(fx, cx, strict=True):
        v = X[f[:corners]]
        mapped, measure, normal = _affine_map(v, points)
        if np.dot(X[c].mean(axis=0) - v.mean(axis=0), normal) < 0:  # into the slave
            normal = -normal
        for x, w in zip(mapped, weights, strict=True):
            d = np.linalg.norm(nodes.x - x, axis=1)
            k = int(np.argmin(d))
            if d[k] > 1e-9 * scale:
                raise ValueError(f"interface '{pair.spec.interface}': a quadrature point "
                                 "is not a node")
            local.append((k, w * measure, *normal))
    table = np.array([row for part in model.comm.allgather(local) for row in part])
    table = table[np.lexsort(table[:, ::-1].T)]  # by node, weight, then the normal
    return table[:, 0].astype(np.int64), table[:, 1], table[:, 2:]


class NodalContactForces:
    """f_c and X ∂f_c/∂y of one conforming pair on the interface unknowns, compiled.

    A :class:`~breakwater.stepping.interface.ContactForces` provider of
    :class:`~breakwater.stepping.condensed.CondensedNewton`: :meth:`begin` gathers the
    pair's nodal state at the start of a step (u, v, a at t, the staged Δa; one
    reduction), then :meth:`add_vector` and :meth:`add_left_product` evaluate the law
    at an iterate y of the interface unknowns without touching the Functions and
    without communication (the same numbers on every rank), in the kernels of
    :mod:`breakwater.contact.nodalkernels`. :meth:`precheck` is the pair's slip guard on
    the interface unknowns.

    Args:
        model: The contact model.
        nodes: The pair's node pairs.
        layout: Stacked-vector layout of the model.
        interface: Global stacked indices of the interface unknowns (sorted).
        state: ``(u, v, a, Δa)``, one Function per body each.
        dt: The step size constant.
        beta1: GN22 β₁.
        beta2: GN22 β₂.
        guard: Whether :meth:`precheck` guards slip reversals (the stepper's
            ``flip_guard``).
    """

    primal = True  # the Newton solves for δ on the closed nodes (InterfaceNewton._step)

    def __init__(self, model: ContactModel, nodes: InterfaceNodes, layout: MonolithicLayout,
                 interface: np.ndarray,
                 state: tuple[Sequence[fem.Function], Sequence[fem.Function],
                              Sequence[fem.Function], Sequence[fem.Function]],
                 dt: fem.Constant, beta1: float, beta2: float, guard: bool = True) -> None:
        self.comm = model.comm
        self.guarded = guard
        self.nodes = nodes
        self.pair = pair = nodes.pair
        self.u, self.v, self.a, self.da = state
        self.dt, self.beta1, self.beta2 = dt, beta1, beta2
        self.n = n = len(interface)
        gdim = nodes.gdim
        self._node, self._weight, self._normal = quadrature_points(model, nodes)
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
        self._pos = where
        # The points of each node (sorted by node: runs) and the node's unknowns.
        node = self._node
        starts = np.flatnonzero(np.r_[True, node[1:] != node[:-1]])
        self._runs = np.append(starts, len(node)).astype(np.int64)
        self._run_slave = np.ascontiguousarray(where[0][node[starts]])
        self._run_master = np.ascontiguousarray(where[1][node[starts]])
        self._W = np.zeros((len(starts), gdim, gdim))
        # The owned entries of the pair's nodes in each side's local arrays, and their
        # places in the gathered nodal arrays (node-major, component-minor).
        comps = np.arange(gdim)
        self._take = []
        for (blocks, pos), body in ((nodes._slave, pair.slave), (nodes._master, pair.master)):
            bs = layout.bs[body]
            arrays = [f[body].x.array for f in (self.u, self.v, self.a, self.da)]
            self._take.append(((blocks[:, None] * bs + comps).ravel(),
                               (pos[:, None] * gdim + comps).ravel(), arrays))
        self._base = np.zeros((5, 2, nodes.size, gdim))
        self._U = np.zeros((2, nodes.size, gdim))
        self._V = np.zeros((2, nodes.size, gdim))
        self._coefficients = (0.0, 0.0)
        self._law = (0.0, 0.0, 0.0, 0.0)
        self._tangents = nodes.tangents.astype(float)

    def begin(self) -> None:
        """Gather the nodal state of the staged step (collective: one reduction).

        u₀, Δt v₀ + ½Δt² a₀, v₀, Δt a₀ and the staged Δa at the pair's nodes (the
        terms of :func:`breakwater.stepping.gn22.gn22_kinematics`), and the law's
        parameters and the step's coefficients ½β₂Δt², β₁Δt now.
        """
        dt = float(self.dt.value)
        base = self._base.reshape(5, 2, -1)
        if self.comm.size > 1:
            base[:] = 0.0  # the other ranks' nodes: their values come in the sum
        for side, (local, place, (u, v, a, da)) in enumerate(self._take):
            a_ = a[local]
            v_ = v[local]
            base[0, side, place] = u[local]
            base[1, side, place] = dt * v_ + 0.5 * dt**2 * a_
            base[2, side, place] = v_
            base[3, side, place] = dt * a_
            base[4, side, place] = da[local]
        if self.comm.size > 1:
            self.comm.Allreduce(MPI.IN_PLACE, base, op=MPI.SUM)
        self._coefficients = (0.5 * self.beta2 * dt**2, self.beta1 * dt)
        # The parameters' values now (not law.values(): a copy of the law, 20 µs a step).
        normal, friction = self.pair.law.normal, self.pair.law.friction
        value = forms.parameter_value
        self._law = (value(normal.ε_n), value(normal.g0), value(friction.μ),
                     value(friction.χ) ** 2)

    def end(self) -> None:
        """Nothing to release (the gathered state is overwritten by the next :meth:`begin`)."""

    def add_vector(self, y: np.ndarray, out: np.ndarray) -> None:
        """Add f_c(y) on the interface unknowns to ``out``."""
        nodal_residual(y, self._pos, self._base, *self._coefficients, self._node,
                       self._weight, self._normal, *self._law, self._U, self._V, out)

    def add_left_product(self, y: np.ndarray, X: np.ndarray, out: np.ndarray) -> bool:
        """Add X ∂f_c/∂y at y to ``out`` (X: n_I columns), from the node tangents.

        The matrix couples only the two sides of one node: O(rows · nodes) work
        (:func:`~breakwater.contact.nodalkernels.tangent_left_product`).
        """
        nodal_left_product(y, self._pos, self._base, *self._coefficients, self._node,
                           self._weight, self._normal, self._runs, *self._law,
                           self._run_slave, self._run_master, X, self._U, self._V, self._W,
                           out)
        return True

    def matrix(self, y: np.ndarray) -> np.ndarray:
        """∂f_c/∂y at y on the interface unknowns, dense (the product with I)."""
        out = np.zeros((self.n, self.n))
        self.add_left_product(y, np.eye(self.n), out)
        return out

    def resolution(self, y: np.ndarray) -> float:
        """0: no estimate (the conforming pairs' Newton meets its tolerance)."""
        return 0.0

    def active_jacobian(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """∂f_c/∂y at y as ``(act, A)``: the unknowns of the closed nodes and its block there.

        :func:`~breakwater.contact.nodalkernels.tangent_block` from the node tangents:
        the Newton then solves on the nodes in contact alone (a rocking caisson lifts a
        part of its base), instead of the whole ``1 + X ∂f_c/∂y``.
        """
        return tangent_block(self._node_tangents(y), self._run_slave, self._run_master, self.n)

    def _node_tangents(self, y: np.ndarray) -> np.ndarray:
        """The node tangents W at y (:func:`nodal_tangents`, into the kept array)."""
        nodal_state(y, self._pos, self._base, *self._coefficients, self._U, self._V)
        nodal_tangents(self._U, self._V, self._node, self._weight, self._normal, self._runs,
                       *self._law, *self._coefficients, self._W)
        return self._W

    def jump_jacobian(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """∂f_c/∂y at y as the node tangents: ``(W, slave, master)`` (a copy of W).

        ∂f_c/∂y = −Dᵀ W D with D the jumps of the nodes' unknowns
        (:mod:`breakwater.stepping.jumpsystem`; the blocks of :meth:`active_jacobian`).
        """
        return self._node_tangents(y).copy(), self._run_slave, self._run_master

    def precheck(self, x: np.ndarray, step: np.ndarray, v_pred: np.ndarray,
                 dv_dx: float, bulk: BulkStiffness | None = None) -> int:
        """The pair's slip guard on the interface unknowns; the nodes corrected.

        :func:`~breakwater.contact.nodalkernels.guard_steps` with the nodes' averaged
        normals and tangent bases and the law's stick band, as
        :class:`~breakwater.contact.slipguard.SlipGuard` does on body arrays (nothing
        without the guard), at the nodes whose law holds their slip against the bulk's
        stiffness ``bulk`` (:func:`~breakwater.contact.coupling.guarded_nodes`, the
        slave side's; None: every node).
        """
        if not self.guarded:
            return 0
        band = self.pair.law.friction.stick_band
        return int(guard_steps(x, step, v_pred, dv_dx, self._pos, self.nodes.normal,
                               self._tangents, forms.parameter_value(band),
                               self._guarded(x, bulk)))

    def _guarded(self, x: np.ndarray, bulk: BulkStiffness | None) -> np.ndarray:
        """The nodes where the guard acts at the iterate x (their normal forces there)."""
        ε_n, g0, μ, χ2 = self._law
        if bulk is None or not χ2 > 0.0:
            return np.ones(self.nodes.size, bool)
        nodal_state(x, self._pos, self._base, *self._coefficients, self._U, self._V)
        lam = np.empty(self.nodes.size)
        normal_forces(self._U, self._node, self._weight, self._normal, ε_n, g0, lam)
        return guarded_nodes(lam, μ * self._coefficients[1] / math.sqrt(χ2), bulk,
                             self._pos[0], self._tangents)

    def true_law(self, crawl: bool = True) -> bool:
        """Always the law itself (the guard moves slips alone): False."""
        return False

    def regularise(self, stretch: float) -> bool:
        """Its own χ always: False (the continuation is a general pair's rescue).

        A conforming pair's Newton, its nodes' slips each on one master node, converges
        with the slip guard alone (:mod:`breakwater.stepping.continuation`).
        """
        return False
