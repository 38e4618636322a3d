"""General contact pairs: two surfaces that need not match, with finite sliding (2-D).

the paper's §2, eqs. 5-9 and 12-15: each slave integration point is projected onto the master
surface in the current configuration (closest point, :mod:`breakwater.contact.projection`);
the normal gap is ``g_n = (x_s − x̄_m)·n̄`` with n̄ the master's outward normal at the
projection (eq. 7), the slip velocity is the slave's velocity relative to the master
material point under the projection, ``v_s − v̄_m``, and the laws are those of
:mod:`forms.contact` (their NumPy path), written once for both kinds of pair.

Scheme (segment-to-segment, single pass): each slave facet is cut into segments at the
points where the master facets' vertices project onto it (current configuration), and
each segment carries ``points`` Gauss points (weight: the reference length), so that
every point's projection stays within one master facet over a segment and the
integrand is smooth there; on a flat patch the integration is exact (the patch test).
The cuts move with the bodies but are held fixed in the linearisation, which stays
exact: the integrand is continuous across a cut, so the derivatives of the cut
positions cancel between the two segments. ``integration = "gauss"`` gives plain
Gauss-point-to-segment integration (Gauss points per slave facet), ``"nodes"`` the
node-to-segment scheme (the slave nodes with Gauss–Lobatto weights, the conforming
pair's quadrature: on a conforming interface it is that pair with closest-point
kinematics). The master surface may join several facet groups (a crest that
continues beyond the slave, so that a slave corner sliding past the end of a shared
group still finds it). The master surface
is the exact current image of the master facets (the P2 displacement makes each facet a
quadratic curve, its three nodes the closure DOFs). The slave receives ``−∫ t_s N_s``
and the master ``+∫ t_s N̄_m`` at the projection (action and reaction).

The pair is a provider of the fast solver (:mod:`breakwater.stepping.condensed`): ``vector()``
and ``matrix()`` give the contact residual and its Jacobian with respect to the step's
unknown Δa on the interface unknowns. The surfaces' data (reference node coordinates,
interface positions of their DOFs, sorted by coordinates) are gathered once on every
rank; at each call the current u, v at the interface are reduced onto every rank (one
``Allreduce``) and every rank evaluates the same points in the same order, so the
result does not depend on the partition. The Jacobian is exact: a complex step per
local DOF of a (slave facet, master facet) point, with the projection's Newton run in
complex arithmetic, so the implicit dependence of ξ̄ on the nodes is included.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from functools import partial
from typing import TYPE_CHECKING, Any

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.contact.penetration import StepCheck, allowed_depth, search_radius
from breakwater.contact.pointkernels import (
    DenseEntries,
    H,
    contact_geometry,
    jacobian,
    nodal_normal_forces,
    normal_and_shares,
    normal_forces,
    unit_tangent,
)
from breakwater.contact.projection import FacetGrid, nearest_end, project, shape
from breakwater.contact.surfaces import SurfacePair, gather_surface

if TYPE_CHECKING:
    from breakwater.model.model import ContactModel
    from breakwater.stepping.bulk import MonolithicLayout, Timings

__all__ = ["SurfaceContact"]

# A slave facet's nodes in closure order (the vertices, then the mid-edge node) on
# [−1, 1] and their Gauss–Lobatto weights: the trapezoidal rule (P1), Simpson's (P2).
_NODES = {2: np.array([-1.0, 1.0]), 3: np.array([-1.0, 1.0, 0.0])}
_LOBATTO = {2: np.array([1.0, 1.0]), 3: np.array([1.0, 1.0, 4.0]) / 3}
# A slave node a little past the end of the master surface (|ξ̄| ≤ 1 + _EDGE) still
# presses on its end: where the two surfaces end together (a patch, a block on a block
# as wide), the penalty's compliance puts the end node 1e-5 of a facet past the end
# and back between Newton iterates, and a node carrying its lumped force in and out of
# contact 2-cycles Newton. Gauss points lie inside the slave facets: 1e-9 (round-off).
_EDGE = 1e-3


class SurfaceContact:
    """One general pair as a provider of the fast solver's interface (see the module doc).

    Args:
        model: The contact model.
        spec: The pair.
        layout: The stacked-vector layout.
        interface: Global stacked indices of the interface unknowns (sorted).
        state: ``(u, v, a, Δa)``, one Function per body each.
        dt: The step size constant.
        beta1: GN22 β₁.
        beta2: GN22 β₂.
    """

    def __init__(self, model: ContactModel, spec: SurfacePair, layout: MonolithicLayout,
                 interface: np.ndarray,
                 state: tuple[Sequence[fem.Function], Sequence[fem.Function],
                              Sequence[fem.Function], Sequence[fem.Function]],
                 dt: fem.Constant, beta1: float, beta2: float) -> None:
        self.spec, self.comm = spec, model.comm
        self.small_rotations = spec.rotations == "small"
        self._edge = _EDGE if spec.integration == "nodes" else 1e-9
        self.law = forms.ContactLaw.of(spec)
        self.n = n = len(interface)
        self.u, self.v, self.a, self.da = state
        self.dt, self.beta1, self.beta2 = dt, beta1, beta2
        slave = gather_surface(model, layout, spec.slave, (spec.slave_surface,))
        master = gather_surface(model, layout, spec.master, spec.master_groups)
        # Orient each master facet so that (t_y, −t_x) points out of its cell.
        mid = master.X.mean(axis=1)
        chord = master.X[:, 1] - master.X[:, 0]
        flip = np.sum((master.interior - mid) * np.stack([chord[:, 1], -chord[:, 0]], 1),
                      axis=1) > 0
        swap = np.arange(master.X.shape[1])
        swap[:2] = [1, 0]
        master.X[flip] = master.X[flip][:, swap]
        master.dofs[flip] = master.dofs[flip][:, swap]
        self.slave, self.master = slave, master
        self.pos_s, self.pos_m = (self._positions(interface, x.dofs) for x in (slave, master))
        # The Gauss rule of each integration segment on [−1, 1].
        self._gauss = np.polynomial.legendre.leggauss(spec.points)
        self.radius = search_radius(spec, master)
        # Owned entries of each body at the interface unknowns (for the reduction).
        self._owned = []
        for i, gi in enumerate(layout.global_index):
            local = np.arange(layout.sizes[i])
            pos = np.searchsorted(interface, gi[local])
            pos = np.minimum(pos, max(n - 1, 0))
            hit = interface[pos] == gi[local] if n else np.zeros(len(local), bool)
            self._owned.append((local[hit], pos[hit]))
        self.searches = 0
        self.search_seconds = 0.0
        self.timings: Timings | None = None  # the solver's: search time also added there
        # The slave nodes (friction acts on them): one id per node, by global DOF.
        _, first, self.node_of = np.unique(slave.dofs[..., 0], return_index=True,
                                             return_inverse=True)
        self.node_of = self.node_of.reshape(slave.dofs.shape[:2])
        self.node_pos = self.pos_s.reshape(-1, model.gdim)[first]
        self.node_X = slave.X.reshape(-1, model.gdim)[first]
        self._frozen_key: np.ndarray | None = None
        self._normal_key: np.ndarray | None = None
        self._normal_data: tuple[Any, list, np.ndarray, Any, np.ndarray]
        self._normal_points: dict[str, Any]  # the _points of _normal_key
        self._frozen_data: tuple[np.ndarray, np.ndarray, np.ndarray]
        self._frozen_projected = np.zeros(0, bool)  # of _frozen_data: not a nearest end
        # The start-of-step projection of the last step solved (see _friction).
        self._step_frozen: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self.step_check = StepCheck(spec, self.radius, allowed_depth(master, self.radius),
                                    self.node_X, self.node_pos, master.X, self.pos_m)

    @staticmethod
    def _positions(interface: np.ndarray, dofs: np.ndarray) -> np.ndarray:
        """Interface position of each DOF, −1 where it is not an unknown (Dirichlet)."""
        if not len(interface):
            return np.full(dofs.shape, -1, np.int64)
        at = np.minimum(np.searchsorted(interface, dofs), len(interface) - 1)
        return np.where(interface[at] == dofs, at, -1)

    # --- the current state ----------------------------------------------------------

    def _state(self, y: np.ndarray | None = None, accepted: bool = False
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """u₀, u₁ and v₁ of the step at the interface unknowns (every rank; a trailing 0).

        Args:
            y: Δa at the interface unknowns; None: read from the Δa Functions.
            accepted: The accepted state instead: u₀ = u₁ = u, v₁ = v.
        """
        u, v, a, da = self._values(self.u, self.v, self.a, self.da)
        if accepted:
            return u, u, v
        if y is not None:
            da[:-1] = y
        dt = float(self.dt.value)
        return (u, u + dt * v + 0.5 * dt**2 * a + 0.5 * self.beta2 * dt**2 * da,
                v + dt * a + self.beta1 * dt * da)

    def interface_values(self, functions: Sequence[fem.Function]) -> np.ndarray:
        """Values of one Function per body at the pair's interface unknowns (collective).

        Returns:
            Shape ``(n + 1,)``, the same on every rank, with a trailing 0 (the value at
            the Dirichlet entries, position −1).
        """
        return self._values(functions)[0]

    def _values(self, *fields: Sequence[fem.Function]) -> np.ndarray:
        """:meth:`interface_values` of several fields, ``(len(fields), n + 1)``.

        One reduction for all the fields.
        """
        out = np.zeros((len(fields), self.n + 1))
        for k, functions in enumerate(fields):
            for f, (local, pos) in zip(functions, self._owned, strict=True):
                out[k, pos] = f.x.array[local]
        self.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        return out

    def _integration(self, xs: np.ndarray, xm: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The slave integration points: (slave facet, ξ, weight) of each.

        Each slave facet is cut where the master facets' vertices project onto it
        (current configuration, ``segments``), or not at all (``gauss``); each segment
        carries the Gauss rule. With ``nodes``: the facet's nodes, Gauss–Lobatto
        weights. The weight is the reference length.
        """
        s = self.slave
        n_f, nn = s.X.shape[:2]
        if self.spec.integration == "nodes":
            point_facet = np.repeat(np.arange(n_f), nn)
            xi = np.tile(_NODES[nn], n_f)
            _, dN, _ = shape(xi, nn)
            jac = np.linalg.norm(np.einsum("kn,knd->kd", dN, s.X[point_facet]), axis=1)
            return point_facet, xi, np.tile(_LOBATTO[nn], n_f) * jac
        facet = [np.arange(n_f), np.arange(n_f)]
        cut = [-np.ones(n_f), np.ones(n_f)]
        if self.spec.integration == "segments" and len(xm) and n_f:
            vertices = xm[:, :2].reshape(-1, xm.shape[2])
            on, xi = project(vertices, xs, FacetGrid(xs, self.radius))
            inside = (on >= 0) & (np.abs(xi) < 1 - 1e-12)
            facet.append(on[inside])
            cut.append(xi[inside])
        f, c = np.concatenate(facet), np.concatenate(cut)
        order = np.lexsort((c, f))
        f, c = f[order], c[order]
        seg = np.flatnonzero((f[1:] == f[:-1]) & (c[1:] - c[:-1] > 1e-12))
        f_seg, a, b = f[seg], c[seg], c[seg + 1]
        g, w = self._gauss
        xi = (0.5 * (a + b)[:, None] + 0.5 * (b - a)[:, None] * g).ravel()
        point_facet = np.repeat(f_seg, len(g))
        _, dN, _ = shape(xi, nn)
        jac = np.linalg.norm(np.einsum("kn,knd->kd", dN, s.X[point_facet]), axis=1)
        weight = (0.5 * (b - a)[:, None] * w).ravel() * jac
        return point_facet, xi, weight

    def _points(self, u1: np.ndarray, v1: np.ndarray) -> dict[str, Any]:
        """The integration points and the local data of those with a projection (real).

        Args:
            u1: Displacements at the interface unknowns (a trailing 0).
            v1: Velocities at the interface unknowns (a trailing 0).
        """
        s, m = self.slave, self.master
        xs_all = s.X + u1[self.pos_s]
        xm_all = m.X + u1[self.pos_m]
        t0 = time.perf_counter()
        point_facet, xi_s, weight = self._integration(xs_all, xm_all)
        Ns, _, _ = shape(xi_s, s.X.shape[1])
        points = np.einsum("kn,knd->kd", Ns, xs_all[point_facet])
        facet, xi = project(points, xm_all, FacetGrid(xm_all, self.radius),
                            tol=self._edge)
        self.searches += 1
        elapsed = time.perf_counter() - t0
        self.search_seconds += elapsed
        if self.timings is not None:
            self.timings.seconds["contact_search"] += elapsed
        on = np.flatnonzero(facet >= 0)
        f_s, f_m = point_facet[on], facet[on]
        return {"index": on, "facet": f_m, "slave_facet": f_s, "Ns": Ns[on],
                "xs": xs_all[f_s], "vs": v1[self.pos_s][f_s], "xm": xm_all[f_m],
                "vm": v1[self.pos_m][f_m], "xi": xi[on], "weight": weight[on],
                "pos": np.concatenate([self.pos_s[f_s], self.pos_m[f_m]], axis=1),
                "all_x": points, "all_weight": weight}

    def _frozen(self, u0: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The projection of each slave node at the start of the step (cached).

        A node with no projection (beyond the master's end) takes the nearest master
        vertex within the search radius (ξ̄₀ = ±1).

        Returns:
            Per slave node: the master facet f₀ (−1: none), its shape functions at ξ̄₀
            and the unit tangent there, in the configuration at the start of the step.
        """
        if self._frozen_key is not None and np.array_equal(self._frozen_key, u0):
            return self._frozen_data
        m = self.master
        xm = m.X + u0[self.pos_m]
        points = self.node_X + u0[self.node_pos]
        grid = FacetGrid(xm, self.radius)
        facet, xi = project(points, xm, grid)
        # A node beyond the master's end (it slid past it) keeps its friction where its
        # facets' points still press: its master point is the surface's end vertex.
        beyond = np.flatnonzero(facet < 0)
        self._frozen_projected = facet >= 0
        if len(beyond):
            facet[beyond], xi[beyond] = nearest_end(points[beyond], xm, grid)
        N0, dN0, _ = shape(xi, m.X.shape[1])
        surface = m.X if self.small_rotations else xm
        t0 = unit_tangent(dN0, surface[np.maximum(facet, 0)]) if len(m.X) else \
            np.zeros_like(points)
        self._frozen_key = u0.copy()
        self._frozen_data = (facet, N0, t0)
        return self._frozen_data

    def _normal(self, u1: np.ndarray, v1: np.ndarray
                ) -> tuple[Any, list, np.ndarray, Any, np.ndarray]:
        """The normal part of the current iterate.

        Returns:
            The point kernel, its groups (local arguments), the interface positions of
            its outputs, the kernel of the points' shares of the nodal normal forces
            and the slave node of each share.
        """
        key = np.concatenate([u1, v1])
        if self._normal_key is not None and np.array_equal(self._normal_key, key):
            return self._normal_data
        p = self._points(u1, v1)
        self._normal_key, self._normal_points = key, p
        args = (self.law, p["Ns"], p["xi"], p["weight"])
        reference = self._reference(p)
        self._normal_data = (partial(normal_forces, *args, reference=reference),
                             [(p["xs"], p["vs"]), (p["xm"], p["vm"])], p["pos"],
                             partial(nodal_normal_forces, *args, reference=reference),
                             self.node_of[p["slave_facet"]])
        return self._normal_data

    def _reference(self, points: dict[str, Any]) -> np.ndarray | None:
        """The kernels' ``reference`` for the points of :meth:`_points`.

        Their master facets in the reference configuration (``rotations = "small"``),
        or None: the current ones.
        """
        return self.master.X[points["facet"]] if self.small_rotations else None

    def _friction(self, u0: np.ndarray, v1: np.ndarray, λ: np.ndarray,
                  accepted: bool = False) -> dict[str, np.ndarray] | None:
        """The nodal friction forces (None: no slave node in contact).

        Per slave node k in contact (λ_k > 0, a projection at the start of the step),
        the force ``−μ λ_k φ(v_T)`` (:class:`forms.ContactLaw`'s friction with the
        nodal normal force λ_k in place of the pressure), with
        ``v_T = t₀ ⊗ t₀ (v_k − v̄_m(ξ̄₀))``.

        Args:
            u0: Displacements at the start of the step (the projection ξ̄₀).
            v1: Velocities of the iterate.
            λ: The slave nodes' normal forces.
            accepted: At the accepted state: the projection of the step that was
                accepted (the force the step applied: where the interface sticks,
                φ(v_T) turns a change of t₀ of 1e-10 into an O(1) change of the
                force), or, before any step, that of the state itself.
        """
        if accepted and self._step_frozen is not None:
            facet, N0, t0 = self._step_frozen
        else:
            facet, N0, t0 = self._frozen(u0)
        k = np.flatnonzero((facet >= 0) & (λ > 0))
        if not len(k):
            return None
        pos_m = self.pos_m[facet[k]]
        slip = v1[self.node_pos[k]] - np.einsum("kn,knd->kd", N0[k], v1[pos_m])
        t = t0[k]
        v_T = t * np.sum(slip * t, axis=1)[:, None]
        friction = self.law.friction
        force = friction.traction(λ[k], v_T)
        return {"k": k, "pos_s": self.node_pos[k], "pos_m": pos_m, "N0": N0[k], "t": t,
                "v_T": v_T, "force": force, "unit": friction.traction(np.ones(len(k)), v_T)}

    def _nodal_forces(self, kernel: Any, groups: list, node: np.ndarray) -> np.ndarray:
        """λ: the slave nodes' normal forces ∫ p N_k."""
        share = kernel(groups)
        return np.bincount(node.ravel(), weights=share.ravel(),
                           minlength=len(self.node_pos))

    # --- the provider ---------------------------------------------------------------

    def vector(self, accepted: bool = False) -> np.ndarray:
        """The contact residual at the interface unknowns (the same on every rank).

        Args:
            accepted: At the stepper's accepted state (u, v) instead of the iterate.
        """
        u0, u1, v1 = self._state(accepted=accepted)
        kernel, groups, pos, lam_kernel, node = self._normal(u1, v1)
        out = self._add(np.zeros(self.n), pos, kernel(groups))
        if self.spec.friction:
            self._step_frozen = self._frozen(u0)
            fr = self._friction(u0, v1, self._nodal_forces(lam_kernel, groups, node))
            if fr is not None:
                self._add(out, fr["pos_s"], -fr["force"])
                self._add(out, fr["pos_m"], fr["N0"][:, :, None] * fr["force"][:, None, :])
        return out

    def _add(self, out: np.ndarray, pos: np.ndarray, values: np.ndarray) -> np.ndarray:
        """out[pos] += values (skipping Dirichlet entries, −1), in array order."""
        pos, values = pos.ravel(), values.ravel()
        keep = pos >= 0
        out += np.bincount(pos[keep], weights=values[keep], minlength=self.n)
        return out

    def matrix(self) -> np.ndarray:
        """∂(contact residual)/∂Δa at the interface unknowns, dense.

        The normal part by complex steps of the point kernel (the projection's Newton
        in complex arithmetic: exact, its implicit dependence included); the friction
        part by the chain rule through λ_k (complex steps of the point shares) and
        v_T (linear in Δa; ∂φ/∂v_T by complex steps).
        """
        dt = float(self.dt.value)
        cu, cv = 0.5 * self.beta2 * dt**2, self.beta1 * dt
        n = self.n
        u0, u1, v1 = self._state()
        kernel, groups, pos, lam_kernel, node = self._normal(u1, v1)
        out = DenseEntries(n)
        if not len(pos):  # no slave point has a projection: no contact
            return out.matrix()
        both = jacobian(partial(normal_and_shares, *kernel.args, **kernel.keywords), groups,
                        cu, cv)
        size = pos.shape[1] * pos.shape[2]
        J, Jl = both[:, :size], both[:, size:]  # the forces' and the nodal shares'
        rows = pos.reshape(len(J), -1)
        out.block(rows, rows, J)
        if not self.spec.friction:
            return out.matrix()
        lam = self._nodal_forces(lam_kernel, groups, node)
        fr = self._friction(u0, v1, lam)
        if fr is None:
            return out.matrix()
        # dλ/dΔa (slave nodes × interface), from the points' shares.
        cols = np.broadcast_to(rows[:, None, :], Jl.shape)
        nodes = np.broadcast_to(node[:, :, None], Jl.shape)
        keep = cols >= 0
        dlam = np.bincount((nodes * n + cols)[keep], weights=Jl[keep],
                           minlength=len(self.node_pos) * n).reshape(-1, n)
        k, t, N0 = fr["k"], fr["t"], fr["N0"]
        gdim = t.shape[1]
        # ∂force/∂v_T by complex steps of the law (2 components).
        D = np.zeros((len(k), gdim, gdim))
        for c in range(gdim):
            v = fr["v_T"].astype(complex)
            v[:, c] += 1j * H
            D[:, :, c] = self.law.friction.traction(lam[k], v).imag / H
        B = cv * np.einsum("kij,kj,kl->kil", D, t, t)  # ∂force/∂(slave node Δa)
        # Rows: the slave node (−force) and the master nodes of f₀ (+N0 force).
        row_pos = np.concatenate([fr["pos_s"][:, None, :], fr["pos_m"]], axis=1)
        sign = np.concatenate([-np.ones((len(k), 1)), N0], axis=1)  # (k, 1 + nn)
        # λ part: force = unit · λ.
        dforce_lam = fr["unit"][:, :, None] * dlam[k][:, None, :]  # (k, gdim, n)
        for r in range(row_pos.shape[1]):
            rp = row_pos[:, r, :]
            vals = sign[:, r, None, None] * dforce_lam
            rr = np.broadcast_to(rp[:, :, None], vals.shape)
            cc = np.broadcast_to(np.arange(n)[None, None, :], vals.shape)
            ok = rr >= 0
            out.add((rr * n + cc)[ok], vals[ok])
        # v_T part: slave node columns (B), master f₀ node columns (−N0_j B).
        col_pos = row_pos
        col_sign = np.concatenate([np.ones((len(k), 1)), -N0], axis=1)
        for r in range(row_pos.shape[1]):
            for c in range(col_pos.shape[1]):
                block = (sign[:, r] * col_sign[:, c])[:, None, None] * B
                out.block(row_pos[:, r, :], col_pos[:, c, :], block)
        return out.matrix()

    def precheck(self, x: np.ndarray, step: np.ndarray) -> int:
        """Newton's slip guard (:mod:`breakwater.contact.slipguard`) at the slave nodes.

        Where Newton's step (the next iterate is ``x − step``) would reverse a slave
        node's slip velocity (relative to the master material point under its
        projection at the start of the step, along the tangent there) from outside the
        stick band χ, the node's tangential step is cut so that it lands at zero slip
        velocity, where the stick tangent is exact. The slip velocity is linear in Δa,
        so the landing is exact.

        Args:
            x: The current iterate (Δa at the interface unknowns).
            step: Newton's step, changed in place where cut.

        Returns:
            The nodes corrected (the same on every rank).
        """
        if not self.spec.friction:
            return 0
        u0, _, v1 = self._state(x)
        facet, N0, t0 = self._frozen(u0)
        keep = np.flatnonzero((facet >= 0) & np.all(self.node_pos >= 0, axis=1))
        if not len(keep):
            return 0
        pos, N, t = self.node_pos[keep], N0[keep], t0[keep]
        dv = self.beta1 * float(self.dt.value)
        ext = np.append(step, 0.0)
        pos_m = self.pos_m[facet[keep]]
        v_m = np.einsum("kn,knd->kd", N, v1[pos_m])
        y_m = np.einsum("kn,knd->kd", N, ext[pos_m])
        y_s = ext[pos]
        c0 = np.sum((v1[pos] - v_m) * t, axis=1)
        c1 = c0 - dv * np.sum((y_s - y_m) * t, axis=1)
        fix = (c0 * c1 < 0) & (np.abs(c0) > self.law.friction.stick_band)
        if not fix.any():
            return 0
        # The slave's step: normal part kept, tangential part landing at c = 0.
        t, ys = t[fix], y_s[fix]
        along = (np.sum(y_m[fix] * t, axis=1) + c0[fix] / dv)[:, None]
        step[pos[fix]] = ys - t * np.sum(ys * t, axis=1)[:, None] + t * along
        return int(fix.sum())

    def penetration(self, y: np.ndarray) -> str | None:
        """Why the step's solution Δa = y leaves a slave node beyond what the search sees.

        :class:`breakwater.contact.penetration.StepCheck` (None: it does not); the same on every
        rank.
        """
        u, v, a, da = self._values(self.u, self.v, self.a, self.da)
        da[:-1] = y
        dt = float(self.dt.value)
        # u₁ as GN22.update computes it (gn22_kinematics): the next step's u₀ bit for bit.
        u1 = u + (dt * v + 0.5 * dt**2 * a + 0.5 * self.beta2 * dt**2 * da)
        return self.step_check(u, u1, lambda: (*self._frozen(u), self._frozen_projected))

    def resultant(self, accepted: bool = True) -> np.ndarray:
        """∫ t_s: the force the master exerts on the slave (N, or N/m in plane strain).

        Args:
            accepted: At the stepper's accepted state (u, v); False: at the current
                Newton iterate of the step.
        """
        normal, friction = self.resultants(accepted)
        return normal + friction

    def resultants(self, accepted: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """The normal (pressure) and friction parts of :meth:`resultant`."""
        u0, u1, v1 = self._state(accepted=accepted)
        kernel, groups, _, lam_kernel, node = self._normal(u1, v1)
        nn = self.slave.X.shape[1]
        # The slave's nodal residual is −∫ t_s N_k, and Σ_k N_k = 1.
        normal = -kernel(groups)[:, :nn].sum(axis=(0, 1))
        friction = np.zeros_like(normal)
        if self.spec.friction:
            fr = self._friction(u0, v1, self._nodal_forces(lam_kernel, groups, node),
                                accepted)
            if fr is not None:
                friction = fr["force"].sum(axis=0)
        return normal, friction

    def slip_velocities(self) -> tuple[np.ndarray, np.ndarray]:
        """The slave nodes in contact at the current iterate and their slip velocities.

        Returns:
            Their interface positions ``(k, gdim)`` (−1: Dirichlet) and ``v_T``, the
            tangential velocity relative to the master (``(k, gdim)``; none without
            friction).
        """
        if not self.spec.friction:
            return np.zeros((0, self.node_pos.shape[1]), np.int64), np.zeros((0, 2))
        u0, u1, v1 = self._state()
        _, groups, _, lam_kernel, node = self._normal(u1, v1)
        fr = self._friction(u0, v1, self._nodal_forces(lam_kernel, groups, node))
        if fr is None:
            return np.zeros((0, self.node_pos.shape[1]), np.int64), np.zeros((0, 2))
        return fr["pos_s"], fr["v_T"]

    def energies(self) -> tuple[float, float]:
        """The penalty energy and the friction power at the accepted state (the ledger).

        ``∫ ½ ε_n ⟨−g_n⟩₊²`` on the normal integration points and
        ``Σ_k μ λ_k |v_T|²/sqrt(|v_T|² + χ²)`` on the slave nodes.
        """
        state = self.state()
        closed = state["gap"] <= 0
        energy = float(np.sum(state["weight"][closed]
                              * self.law.normal.energy(state["gap"][closed])))
        power = 0.0
        if self.spec.friction:
            u0, u1, v1 = self._state(accepted=True)
            _, groups, _, lam_kernel, node = self._normal(u1, v1)
            lam = self._nodal_forces(lam_kernel, groups, node)
            fr = self._friction(u0, v1, lam, accepted=True)
            if fr is not None:
                power = float(np.sum(self.law.friction.power(lam[fr["k"]], fr["v_T"])))
        return energy, power

    def state(self, accepted: bool = True) -> dict[str, np.ndarray]:
        """Every normal integration point (every rank), as :meth:`resultant`.

        Returns:
            ``x`` (current position), ``gap`` (g_n; NaN without a projection),
            ``pressure``, ``weight`` (reference length), ``facet`` (master facet, −1:
            none), ``xi`` (its local coordinate).
        """
        _, u1, v1 = self._state(accepted=accepted)
        self._normal(u1, v1)  # the points of this state (cached: the search once)
        p = self._normal_points
        points = p["all_x"]
        total = len(points)
        out: dict[str, Any] = {"x": points, "weight": p["all_weight"],
                               "gap": np.full(total, np.nan), "pressure": np.zeros(total),
                               "facet": np.full(total, -1), "xi": np.zeros(total)}
        if len(p["index"]):
            x_s, xi, _, x_bar, n = contact_geometry(p["Ns"], p["xi"], p["xs"], p["xm"], 2,
                                                    self._reference(p))
            gap = self.law.gap(x_s, x_bar, n)
            i = p["index"]
            out["gap"][i] = gap
            out["pressure"][i] = self.law.normal.pressure(gap)
            out["facet"][i] = p["facet"]
            out["xi"][i] = xi
        return out
