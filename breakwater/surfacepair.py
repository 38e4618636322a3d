"""General contact pairs: two surfaces that need not match, with finite sliding (2-D).

SPEC §1, eqs. 5-9 and 12-15: each slave integration point is projected onto the master
surface in the current configuration (closest point, :mod:`breakwater.projection`);
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
positions cancel between the two segments. ``segmented = False`` gives plain
Gauss-point-to-segment integration (Gauss points per slave facet). The master surface
is the exact current image of the master facets (the P2 displacement makes each facet a
quadratic curve, its three nodes the closure DOFs). The slave receives ``−∫ t_s N_s``
and the master ``+∫ t_s N̄_m`` at the projection (action and reaction).

The pair is a provider of the fast solver (:mod:`breakwater.condensed`): ``vector()``
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

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from mpi4py import MPI

from . import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from .mesh import group_tag
from .projection import FacetGrid, closest_point, project, shape

if TYPE_CHECKING:
    from dolfinx import fem

    from .bulk import MonolithicLayout
    from .model import ContactModel

__all__ = ["SurfaceContact", "SurfacePair", "surface_dofs"]

_H = 1e-20  # complex step (no cancellation: any tiny step is exact to round-off)


@dataclass(frozen=True)
class SurfacePair:
    """Penalty contact with regularised Coulomb friction between two surfaces.

    Attributes:
        name: The pair's name (the case's ``[contact.NAME]``).
        slave: Body whose integration points are projected.
        master: Body whose surface (and outward normal) they are projected on.
        slave_surface: Facet group on the slave's boundary.
        master_surface: Facet group on the master's boundary.
        penalty: Normal penalty ε_n (N/m³).
        friction: Coulomb coefficient μ (-).
        regularisation: Regularisation velocity χ (m/s).
        points: Gauss points per integration segment.
        segmented: Cut each slave facet where the master facets' vertices project onto
            it (segment-to-segment integration: exact on a flat patch); False: one
            segment per slave facet (Gauss-point-to-segment).
        radius: Search radius (m): a point farther from the master surface has no
            projection (out of contact); None: the longest master facet.
    """

    name: str
    slave: str
    master: str
    slave_surface: str
    master_surface: str
    penalty: float
    friction: float = 0.0
    regularisation: float = 1e-10
    points: int = 3
    segmented: bool = True
    radius: float | None = None

    gap = 0.0  # the law's g_0: the geometry carries the initial gap of a general pair

    def __post_init__(self) -> None:
        if not self.penalty > 0:
            raise ValueError(f"contact penalty must be > 0 (got {self.penalty})")
        if not self.friction >= 0:
            raise ValueError(f"friction coefficient must be >= 0 (got {self.friction})")
        if not self.regularisation > 0:
            raise ValueError(f"regularisation must be > 0 (got {self.regularisation})")
        if self.slave == self.master:
            raise ValueError("a contact pair needs two different bodies")
        if not self.points >= 1:
            raise ValueError(f"points per facet must be >= 1 (got {self.points})")
        if self.radius is not None and not self.radius > 0:
            raise ValueError(f"search radius must be > 0 (got {self.radius})")


@dataclass
class _Surface:
    """The facets of one surface, gathered on every rank and sorted by coordinates.

    Attributes:
        X: Reference node coordinates, ``(F, nn, gdim)`` (closure order: the two
            vertices, then the mid-edge node).
        dofs: Global stacked indices of the nodes' components, ``(F, nn, gdim)``.
        interior: A point inside each facet's cell, ``(F, gdim)``.
    """

    X: np.ndarray
    dofs: np.ndarray
    interior: np.ndarray


def _surface(model: ContactModel, layout: MonolithicLayout, body: int, group: str) -> _Surface:
    """The facets of a body's facet group (collective)."""
    b = model.bodies[body]
    V, sub = b.V, b.submesh
    tdim = sub.topology.dim
    fdim, gdim = tdim - 1, model.gdim
    sub.topology.create_connectivity(fdim, tdim)
    sub.topology.create_connectivity(tdim, fdim)
    f2c, c2f = sub.topology.connectivity(fdim, tdim), sub.topology.connectivity(tdim, fdim)
    facets = b.facet_tags.find(group_tag(model.mesh_data, group, fdim))
    facets = facets[facets < sub.topology.index_map(fdim).size_local]
    closure = V.dofmap.dof_layout.entity_closure_dofs
    coords = V.tabulate_dof_coordinates()[:, :gdim]
    bs = V.dofmap.index_map_bs
    nn = len(closure(fdim, 0))
    X = np.zeros((len(facets), nn, gdim))
    dofs = np.zeros((len(facets), nn, gdim), np.int64)
    interior = np.zeros((len(facets), gdim))
    for k, f in enumerate(facets):
        c = f2c.links(f)[0]
        local = int(np.flatnonzero(c2f.links(c) == f)[0])
        cell = V.dofmap.cell_dofs(c)
        blocks = cell[closure(fdim, local)]
        X[k] = coords[blocks]
        dofs[k] = layout.global_index[body][(blocks[:, None] * bs + np.arange(gdim))]
        interior[k] = coords[cell].mean(axis=0)
    X, dofs, interior = (np.concatenate(model.comm.allgather(a)) for a in (X, dofs, interior))
    mid = X.mean(axis=1)
    order = np.lexsort(mid.T[::-1])
    return _Surface(X[order], dofs[order], interior[order])


def surface_dofs(model: ContactModel, layout: MonolithicLayout) -> np.ndarray:
    """Global stacked indices of the DOFs of every general pair's two surfaces (local)."""
    fdim = model.mesh.topology.dim - 1
    from dolfinx import fem

    out = []
    for spec in model.surface_pairs:
        for name, group in ((spec.slave, spec.slave_surface),
                            (spec.master, spec.master_surface)):
            b = model.body(name)
            blocks = fem.locate_dofs_topological(
                b.V, fdim, b.facet_tags.find(group_tag(model.mesh_data, group, fdim)))
            bs = b.V.dofmap.index_map_bs
            out.append(layout.global_index[b.index][(blocks[:, None] * bs
                                                     + np.arange(bs)).ravel()])
    return np.concatenate(out) if out else np.zeros(0, np.int64)


def point_forces(law: forms.ContactLaw, Ns: np.ndarray, xs: np.ndarray, vs: np.ndarray,
                 xm: np.ndarray, vm: np.ndarray, xi: np.ndarray, weight: np.ndarray,
                 refine: int = 2) -> np.ndarray:
    """Nodal residual contributions of contact points (real or complex arithmetic).

    Args:
        law: The contact law (float parameters).
        Ns: Slave shape functions at each point, ``(K, nn)``.
        xs: Current slave facet nodes, ``(K, nn, gdim)``; ``vs`` their velocities.
        vs: Slave node velocities.
        xm: Current master facet nodes (oriented: ``(t_y, −t_x)`` is outward), ``vm``
            their velocities.
        vm: Master node velocities.
        xi: The projection's local coordinate on the master facet (Newton's start:
            ``refine`` more Newton steps are taken, in the inputs' arithmetic).
        weight: Reference length weight of each point.
        refine: Newton steps of the projection.

    Returns:
        ``(K, 2 nn, gdim)``: the residual on the slave's nodes, then on the master's.
    """
    x_s = np.einsum("kn,knd->kd", Ns, xs)
    v_s = np.einsum("kn,knd->kd", Ns, vs)
    xi = closest_point(x_s, xm, xi, iterations=refine, tol=0.0)
    N, dN, _ = shape(xi, xm.shape[1])
    x_m = np.einsum("kn,knd->kd", N, xm)
    tangent = np.einsum("kn,knd->kd", dN, xm)
    tangent = tangent / np.sqrt(np.sum(tangent * tangent, axis=1))[:, None]
    n = np.stack([tangent[:, 1], -tangent[:, 0]], axis=1)
    v_m = np.einsum("kn,knd->kd", N, vm)
    t = law.traction(x_s, x_m, n, v_s, v_m) * weight[:, None]
    return np.concatenate([-Ns[:, :, None] * t[:, None, :], N[:, :, None] * t[:, None, :]],
                          axis=1)


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
        self.law = forms.ContactLaw.of(spec)
        self.n = n = len(interface)
        self.u, self.v, self.a, self.da = state
        self.dt, self.beta1, self.beta2 = dt, beta1, beta2
        s, m = model.body(spec.slave).index, model.body(spec.master).index
        slave = _surface(model, layout, s, spec.slave_surface)
        master = _surface(model, layout, m, spec.master_surface)
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
        lengths = np.linalg.norm(master.X[:, 1] - master.X[:, 0], axis=1)
        self.radius = spec.radius if spec.radius is not None else \
            float(lengths.max()) if len(lengths) else 1.0
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

    @staticmethod
    def _positions(interface: np.ndarray, dofs: np.ndarray) -> np.ndarray:
        """Interface position of each DOF, −1 where it is not an unknown (Dirichlet)."""
        if not len(interface):
            return np.full(dofs.shape, -1, np.int64)
        at = np.minimum(np.searchsorted(interface, dofs), len(interface) - 1)
        return np.where(interface[at] == dofs, at, -1)

    # --- the current state ----------------------------------------------------------

    def _state(self) -> tuple[np.ndarray, np.ndarray]:
        """u₁ and v₁ of the step at the interface unknowns (every rank; a trailing 0)."""
        out = np.zeros((4, self.n + 1))
        for k, fns in enumerate((self.u, self.v, self.a, self.da)):
            for f, (local, pos) in zip(fns, self._owned, strict=True):
                out[k, pos] = f.x.array[local]
        self.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        u, v, a, da = out
        dt = float(self.dt.value)
        return (u + dt * v + 0.5 * dt**2 * a + 0.5 * self.beta2 * dt**2 * da,
                v + dt * a + self.beta1 * dt * da)

    def _integration(self, xs: np.ndarray, xm: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The slave integration points: (slave facet, ξ, weight) of each.

        Each slave facet is cut where the master facets' vertices project onto it
        (current configuration, ``segmented``), or not at all; each segment carries
        the Gauss rule. The weight is the reference length.
        """
        s = self.slave
        n_f, nn = s.X.shape[:2]
        facet = [np.arange(n_f), np.arange(n_f)]
        cut = [-np.ones(n_f), np.ones(n_f)]
        if self.spec.segmented and len(xm) and n_f:
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
        """The contact points and the local data of those with a projection (real)."""
        import time

        s, m = self.slave, self.master
        xs_all = s.X + u1[self.pos_s]
        xm_all = m.X + u1[self.pos_m]
        t0 = time.perf_counter()
        point_facet, xi_s, weight = self._integration(xs_all, xm_all)
        Ns, _, _ = shape(xi_s, s.X.shape[1])
        points = np.einsum("kn,knd->kd", Ns, xs_all[point_facet])
        facet, xi = project(points, xm_all, FacetGrid(xm_all, self.radius))
        self.searches += 1
        self.search_seconds += time.perf_counter() - t0
        on = np.flatnonzero(facet >= 0)
        f_s, f_m = point_facet[on], facet[on]
        return {"index": on, "facet": f_m, "Ns": Ns[on], "xs": xs_all[f_s],
                "vs": v1[self.pos_s][f_s], "xm": xm_all[f_m], "vm": v1[self.pos_m][f_m],
                "xi": xi[on], "weight": weight[on],
                "pos": np.concatenate([self.pos_s[f_s], self.pos_m[f_m]], axis=1),
                "all_x": points, "all_weight": weight}

    # --- the provider ---------------------------------------------------------------

    def vector(self) -> np.ndarray:
        """The contact residual at the interface unknowns (the same on every rank)."""
        p = self._points(*self._state())
        f = point_forces(self.law, p["Ns"], p["xs"], p["vs"], p["xm"], p["vm"], p["xi"],
                         p["weight"])
        pos = p["pos"].ravel()
        keep = pos >= 0
        return np.bincount(pos[keep], weights=f.ravel()[keep], minlength=self.n)

    def matrix(self) -> np.ndarray:
        """∂(contact residual)/∂Δa at the interface unknowns, dense (complex step)."""
        p = self._points(*self._state())
        dt = float(self.dt.value)
        cu, cv = 0.5 * self.beta2 * dt**2, self.beta1 * dt
        K, nn, gdim = p["xs"].shape
        local = 2 * nn * gdim
        J = np.zeros((K, local, local))
        xs, vs, xm, vm = (p[k].astype(complex) for k in ("xs", "vs", "xm", "vm"))
        for j in range(local):
            side, rest = divmod(j, nn * gdim)
            node, comp = divmod(rest, gdim)
            x, v = (xs, vs) if side == 0 else (xm, vm)
            x[:, node, comp] += 1j * _H * cu
            v[:, node, comp] += 1j * _H * cv
            f = point_forces(self.law, p["Ns"], xs, vs, xm, vm, p["xi"], p["weight"])
            J[:, :, j] = f.reshape(K, local).imag / _H
            x[:, node, comp] = x[:, node, comp].real
            v[:, node, comp] = v[:, node, comp].real
        rows = p["pos"].reshape(K, local)
        flat = rows[:, :, None] * self.n + rows[:, None, :]
        keep = (rows[:, :, None] >= 0) & (rows[:, None, :] >= 0)
        out = np.bincount(flat[keep], weights=J[keep], minlength=self.n * self.n)
        return out.reshape(self.n, self.n)

    def state(self) -> dict[str, np.ndarray]:
        """Every slave point at the step's current iterate (the same on every rank).

        Returns:
            ``x`` (current position), ``gap`` (g_n; NaN without a projection),
            ``pressure``, ``slip_velocity`` (tangential, relative to the master
            material point), ``weight`` (reference length), ``facet`` (master facet,
            −1: none), ``xi`` (its local coordinate).
        """
        u1, v1 = self._state()
        p = self._points(u1, v1)
        points = p["all_x"]
        total = len(points)
        out: dict[str, Any] = {"x": points, "weight": p["all_weight"],
                               "gap": np.full(total, np.nan), "pressure": np.zeros(total),
                               "slip_velocity": np.zeros((total, points.shape[1])),
                               "facet": np.full(total, -1), "xi": np.zeros(total)}
        if len(p["index"]):
            x_s = np.einsum("kn,knd->kd", p["Ns"], p["xs"])
            v_s = np.einsum("kn,knd->kd", p["Ns"], p["vs"])
            xi = closest_point(x_s, p["xm"], p["xi"], iterations=2, tol=0.0)
            N, dN, _ = shape(xi, p["xm"].shape[1])
            x_m = np.einsum("kn,knd->kd", N, p["xm"])
            tangent = np.einsum("kn,knd->kd", dN, p["xm"])
            tangent /= np.linalg.norm(tangent, axis=1)[:, None]
            n = np.stack([tangent[:, 1], -tangent[:, 0]], axis=1)
            gap = self.law.gap(x_s, x_m, n)
            v_rel = v_s - np.einsum("kn,knd->kd", N, p["vm"])
            i = p["index"]
            out["gap"][i] = gap
            out["pressure"][i] = self.law.normal.pressure(gap)
            out["slip_velocity"][i] = forms.tangential_part(v_rel, n)
            out["facet"][i] = p["facet"]
            out["xi"][i] = xi
        return out
