"""The search of a general contact pair: its surfaces, integration points and projections.

The first two jobs of :class:`breakwater.contact.general.SurfaceContact` (see
:mod:`breakwater.contact.general` for the scheme): :class:`InterfaceValues` reads the
step's state at the pair's interface unknowns (every rank, one reduction), and
:class:`SurfaceSearch` gathers the pair's two surfaces, cuts the slave into integration
points and projects them onto the master in the current configuration (the paper's
eqs. 5-7), with the start-of-step projection of the slave nodes that friction uses.
Whether the pair's bodies start overlapped beyond what the search sees is the pair's
static check (:meth:`breakwater.contact.general.SurfaceContact.static_check`, which the
static stage calls).
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Iterator, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common.arrays import equal_at, key_of, read_only, unchanged
from breakwater.contact import forcekernels, searchkernels
from breakwater.contact.penetration import allowed_depth, search_radius
from breakwater.contact.projection import FacetGrid, project, shape
from breakwater.contact.surfaces import Surface, SurfacePair, gather_surface, warn_first_order

if TYPE_CHECKING:
    from breakwater.common.timings import Timings
    from breakwater.model.layout import MonolithicLayout
    from breakwater.model.model import ContactModel

__all__ = ["InterfaceValues", "LawFloats", "SurfaceSearch", "outward"]


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


class InterfaceValues:
    """The step's state at a pair's interface unknowns, the same on every rank.

    Args:
        comm: The model's communicator.
        layout: The stacked-vector layout.
        interface: Global stacked indices of the interface unknowns (sorted).
        state: ``(u, v, a, Δa)``, one Function per body each.
        dt: The step size constant.
        beta1: GN22 β₁.
        beta2: GN22 β₂.

    Attributes:
        slip_origin: A map of v₁ at the interface unknowns to the velocity the slip is
            measured from (None: v₁ itself): the static relaxation's frictional stage
            (:class:`breakwater.statics.pseudostep.SlipOrigin`); the dynamics never sets it.
    """

    slip_origin: Callable[[np.ndarray], np.ndarray] | None = None

    def __init__(self, comm: MPI.Comm, layout: MonolithicLayout, interface: np.ndarray,
                 state: tuple[Sequence[fem.Function], Sequence[fem.Function],
                              Sequence[fem.Function], Sequence[fem.Function]],
                 dt: fem.Constant, beta1: float, beta2: float) -> None:
        self.comm = comm
        self.n = n = len(interface)
        self.u, self.v, self.a, self.da = state
        self.dt, self.beta1, self.beta2 = dt, beta1, beta2
        # Owned entries of each body at the interface unknowns (for the reduction).
        self._owned = []
        for i, gi in enumerate(layout.global_index):
            local = np.arange(layout.sizes[i])
            pos = np.searchsorted(interface, gi[local])
            pos = np.minimum(pos, max(n - 1, 0))
            hit = interface[pos] == gi[local] if n else np.zeros(len(local), bool)
            self._owned.append((local[hit], pos[hit]))
        # The state Functions' arrays (a view per access otherwise: 8 per evaluation).
        self._arrays = {id(f): f.x.array for fs in state for f in fs}
        # u, v, a of the step the Newton is solving (begin_step to end_step), and its
        # iterate: then no reduction per evaluation.
        self._step: np.ndarray | None = None
        self._iterate: np.ndarray | None = None
        self._step_dt: float | None = None
        # The last iterate's (u₀, u₁, v₁) (:meth:`_state`), with the step's kept state
        # and Δt it was computed from.
        self._last_state: tuple[np.ndarray | None, float, np.ndarray,
                                tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None
        # The accepted state within recording() (gathered once there).
        self._recording = False
        self._accepted: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    @contextlib.contextmanager
    def recording(self) -> Iterator[None]:
        """Within: the accepted state is gathered once (collective on entry's first use).

        The outputs of an accepted step read it several times (the history row's
        resultant and measures, the ledger's energies: a reduction each), and nothing
        changes the state Functions while they do.
        """
        self._recording, self._accepted = True, None
        try:
            yield
        finally:
            self._recording, self._accepted = False, None

    def begin_step(self) -> None:
        """Gather u, v, a of the staged step once, for the Newton's evaluations (collective).

        Until :meth:`end_step`, an evaluation at an iterate given by :meth:`at` reads
        them instead of gathering the state Functions (they do not change within a
        step; Δa is the iterate itself): the same numbers, without a reduction.
        """
        self._step = self._values(self.u, self.v, self.a)
        self._step.flags.writeable = False
        self._step_rows = tuple(self._step)  # one (read-only) view each: u₀ is one object
        self._iterate = None
        self._step_dt = float(self.dt.value)

    def at(self, y: np.ndarray) -> bool:
        """Evaluate at the iterate y until the next call, within a step.

        Returns:
            False outside :meth:`begin_step`/:meth:`end_step` (nothing kept: the
            evaluations read the Δa Functions).
        """
        if self._step is None:
            return False
        self._iterate = y
        return True

    def end_step(self) -> None:
        """The Newton is done: evaluations gather the state Functions again."""
        self._step = self._iterate = None
        self._step_dt = None

    def step_dt(self) -> float:
        """Δt, read once per step within :meth:`begin_step`/:meth:`end_step`.

        The constant's value costs a microsecond, and it is read a few times per
        Newton iteration.
        """
        return float(self.dt.value) if self._step_dt is None else self._step_dt

    @staticmethod
    def _positions(interface: np.ndarray, dofs: np.ndarray) -> np.ndarray:
        """Interface position of each DOF, −1 where it is not an unknown (Dirichlet)."""
        if not len(interface):
            return np.full(dofs.shape, -1, np.int64)
        at = np.minimum(np.searchsorted(interface, dofs), len(interface) - 1)
        return np.where(interface[at] == dofs, at, -1)


    def _state(self, y: np.ndarray | None = None, accepted: bool = False
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """u₀, u₁ and v₁ of the step at the interface unknowns (every rank; a trailing 0).

        v₁ through :attr:`slip_origin` where it is set (a general pair's every use of
        v₁ is its slip: the friction, the slip guard and memory, the round-off).

        Args:
            y: Δa at the interface unknowns; None: read from the Δa Functions.
            accepted: The accepted state instead: u₀ = u₁ = u, v₁ = v.
        """
        u0, u1, v1 = self._kinematics(y, accepted)
        return (u0, u1, v1) if self.slip_origin is None else (u0, u1, self.slip_origin(v1))

    def _kinematics(self, y: np.ndarray | None, accepted: bool
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`_state` without :attr:`slip_origin`."""
        if accepted:
            if self._accepted is not None:
                return self._accepted
            u, v = self._values(self.u, self.v)
            if self._recording:
                self._accepted = (u, u, v)
            return u, u, v
        dt = self.step_dt()
        iterate = (self._iterate if y is None else y) if self._step is not None else None
        last = self._last_state
        if (iterate is not None and last is not None and last[0] is self._step
                and last[1] == dt and unchanged(last[2], iterate)):
            # The residual, the Jacobian, the guard and the round-off estimate of one
            # Newton iterate read the same state (within a step: no reduction).
            return last[3]
        # GN22's update (stepping.gn22.gn22_update), its operations in its order: the
        # accepted state is then the converged iterate's u₁, v₁ bit for bit, and the
        # outputs' evaluations there find the Newton's last search (_normal's cache).
        c_a, c_u, c_v = 0.5 * dt**2, 0.5 * self.beta2 * dt**2, self.beta1 * dt
        if iterate is not None:
            u, v, a = self._step_rows
            u1, v1 = searchkernels.iterate_state(u, v, a, iterate, dt, c_a, c_u, c_v)
        else:
            u, v, a, da = self._start(y)
            u1, v1 = u + (dt * v + c_a * a + c_u * da), v + (dt * a + c_v * da)
        out = (u, read_only(u1), read_only(v1))
        if iterate is not None:
            self._last_state = (self._step, dt, key_of(iterate), out)
        return out

    def _start(self, y: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """u, v, a at the start of the step and Δa = y (every rank; a trailing 0).

        Within :meth:`begin_step`/:meth:`end_step` the kept u, v, a and the iterate
        (y, or the one given to :meth:`at`); otherwise the state Functions, Δa
        replaced by y where it is given.
        """
        if self._step is not None:
            y = self._iterate if y is None else y
            if y is not None:
                u, v, a = self._step_rows
                return u, v, a, np.append(y, 0.0)
        u, v, a, da = self._values(self.u, self.v, self.a, self.da)
        if y is not None:
            da[:-1] = y
        return u, v, a, da

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
                array = self._arrays.get(id(f))
                out[k, pos] = (f.x.array if array is None else array)[local]
        self.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        return out


class LawFloats:
    """A pair's contact law (``law``, which a stage may replace) and its numbers as floats."""

    law: Any
    _law_floats: tuple[Any, tuple[float, float, float, float]] | None = None

    @property
    def _law(self) -> tuple[float, float, float, float]:
        """ε_n, g₀, μ and χ of :attr:`law` (which a stage may replace) as floats."""
        law = self.law
        if self._law_floats is None or self._law_floats[0] is not law:
            self._law_floats = (law, tuple(float(x) for x in (  # type: ignore[assignment]
                law.normal.ε_n, law.normal.g0, law.friction.μ, law.friction.χ)))
        assert self._law_floats is not None
        return self._law_floats[1]


class SurfaceSearch(InterfaceValues, LawFloats):
    """A general pair's surfaces, integration points and projections (the module doc).

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
        super().__init__(model.comm, layout, interface, state, dt, beta1, beta2)
        self.model, self.spec = model, spec
        self.small_rotations = spec.rotations == "small"
        self._edge = _EDGE if spec.integration == "nodes" else 1e-9
        self.law = forms.ContactLaw.of(spec)
        slave = gather_surface(model, layout, spec.slave, (spec.slave_surface,))
        master = gather_surface(model, layout, spec.master, spec.master_groups)
        warn_first_order(model, spec, (slave, master))
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
        self._outward, self._deepest = outward(slave), allowed_depth(master, self.radius)
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
        self._normal_points: dict[str, Any]  # the points and normal part of _normal_key
        self._frozen_data: tuple[np.ndarray, np.ndarray, np.ndarray]
        # The kernels' arrays (contiguous, typed) and the law's parameters.
        self._sX, self._mX = (np.ascontiguousarray(x.X, dtype=float) for x in (slave, master))
        self._ps, self._pm = (np.ascontiguousarray(p, dtype=np.int64)
                              for p in (self.pos_s, self.pos_m))
        self._node_of = np.ascontiguousarray(self.node_of, dtype=np.int64)
        self._node_pos = np.ascontiguousarray(self.node_pos, dtype=np.int64)
        self.in_use = FacetsInUse(self._sX, self._mX, self._ps, self._pm, self.radius,
                                  self._edge)
        self._law_floats = None
        # Integration points that do not move (nodes, gauss): once.
        self._fixed_points: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None
        if spec.integration != "segments" or not len(master.X):
            f, xi, w = self._integration(slave.X, master.X)
            self._fixed_points = (f, xi, w, np.ascontiguousarray(shape(xi, slave.X.shape[1])[0]))
        self._no_points = (np.zeros(0, np.int64), np.zeros(0), np.zeros(0),
                           np.zeros((0, slave.X.shape[1])))
        self._frozen_projected = np.zeros(0, bool)  # of _frozen_data: not a nearest end
        # The start-of-step projection of the last step solved (see _friction).
        self._step_frozen: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None


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

    def _points(self, u1: np.ndarray) -> dict[str, Any]:
        """The integration points and the data of those with a projection (compiled).

        Args:
            u1: Displacements at the interface unknowns (a trailing 0).
        """
        t0 = time.perf_counter()
        f0, xi0, w0, N0 = self._fixed_points or self._no_points
        g, w = self._gauss
        (_, points, weight, on, f_s, f_m, Ns, xi, w_on, restricted) = searchkernels.search(
            self._sX, self._mX, self._ps, self._pm, u1, self._fixed_points is None, f0, xi0,
            w0, N0, self.radius, self._edge, g, w, self.in_use.mask, self._outward,
            self._deepest)
        self.searches += 1
        elapsed = time.perf_counter() - t0
        self.search_seconds += elapsed
        if self.timings is not None:
            self.timings.seconds["contact_search"] += elapsed
        return {"index": on, "facet": f_m, "slave_facet": f_s, "Ns": Ns, "xi": xi,
                "weight": w_on, "all_x": points, "all_weight": weight,
                "use": self.in_use.dofs() if restricted else None}

    def _frozen(self, u0: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The projection of each slave node at the start of the step (cached).

        A node with no projection (beyond the master's end) takes the nearest master
        vertex within the search radius (ξ̄₀ = ±1).

        Returns:
            Per slave node: the master facet f₀ (−1: none), its shape functions at ξ̄₀
            and the unit tangent there, in the configuration at the start of the step.
        """
        if unchanged(self._frozen_key, u0):  # within a step: the step's (read-only) u₀
            return self._frozen_data
        xm = self._mX + u0[self._pm]
        normals = searchkernels.node_normals(searchkernels.current(self._sX, self._ps, u0),
                                             self._node_of, self._outward, len(self.node_X))
        facet, N0, t0, self._frozen_projected = searchkernels.frozen(
            self.node_X + u0[self._node_pos], xm, self._mX if self.small_rotations else xm,
            self.radius, normals, self._deepest)
        self._frozen_key = key_of(u0)
        self._frozen_data = (facet, N0, t0)
        return self._frozen_data

    def normal_forces(self, u1: np.ndarray) -> np.ndarray:
        """The slave nodes' normal forces λ_k = ∫ p N_k at the state u1 (node order).

        At the residual's own integration points (:meth:`_normal`).

        Args:
            u1: Displacements at the interface unknowns (a trailing 0).
        """
        return np.asarray(self._normal(u1)["lam"])

    def _normal(self, u1: np.ndarray) -> dict[str, Any]:
        """The normal part of the state u1 (cached: the search once per state).

        Returns:
            :meth:`_points`' dict with ``out`` (f_c's normal part), ``lam`` (the slave
            nodes' normal forces ∫ p N_k), ``forces`` (each point's nodal forces),
            ``gap`` and ``xi_bar`` (the points' g_n and refined ξ̄).
        """
        if unchanged(self._normal_key, u1):
            return self._normal_points
        if self._normal_key is not None and self.in_use.same_search(
                self._normal_points, self._normal_key, u1):
            self._normal_key = key_of(u1)
            return self._normal_points
        p = self._points(u1)
        eps, g0, _, _ = self._law
        p["out"], p["lam"], p["forces"], p["gap"], p["xi_bar"] = forcekernels.residual(
            self._sX, self._mX, self._ps, self._pm, u1, p["slave_facet"], p["facet"], p["Ns"],
            p["xi"], p["weight"], self.small_rotations, eps, g0, self._node_of,
            len(self._node_pos))
        self._normal_key, self._normal_points = key_of(u1), p
        return p


def outward(surface: Surface) -> np.ndarray:
    """Per facet, +1 where ``(t_y, −t_x)`` points out of its cell, else −1 (2-D)."""
    chord = surface.X[:, 1] - surface.X[:, 0]
    side = np.sum((surface.X.mean(axis=1) - surface.interior)
                  * np.stack([chord[:, 1], -chord[:, 0]], 1), axis=1)
    return np.ascontiguousarray(np.where(side >= 0, 1.0, -1.0))


class FacetsInUse:
    """The master facets a general pair's search may be restricted to.

    All of them, unless a stepper's Newton marks the contact's near ones in
    :attr:`mask` (:meth:`breakwater.contact.general.SurfaceForces.reach`). A search
    restricted to them (:func:`~breakwater.contact.searchkernels.search`) is the whole
    search wherever the others are beyond reach, and reads the unknowns of :meth:`dofs`
    alone.

    Args:
        sX: The slave facets' reference nodes.
        mX: The master's.
        pos_s: The slave facets' interface positions.
        pos_m: The master's.
        radius: The search radius.
        edge: The projections' tolerance beyond a master facet's ends.
    """

    def __init__(self, sX: np.ndarray, mX: np.ndarray, pos_s: np.ndarray, pos_m: np.ndarray,
                 radius: float, edge: float) -> None:
        self.mask = np.ones(len(mX), bool)
        self._sX, self._mX, self._ps, self._pm = sX, mX, pos_s, pos_m
        self._radius, self._edge = radius, edge
        self._dofs: tuple[int, np.ndarray] | None = None

    def dofs(self) -> tuple[int, np.ndarray]:
        """The number of facets in use and the interface positions a search on them reads.

        The slave's and theirs; the number names the set (the marks only grow).
        """
        count = int(np.count_nonzero(self.mask))
        if self._dofs is None or self._dofs[0] != count:
            pos = np.concatenate([self._ps.ravel(), self._pm[self.mask].ravel()])
            self._dofs = (count, np.unique(pos[pos >= 0]))
        return self._dofs

    def same_search(self, p: dict[str, Any], key: np.ndarray, u1: np.ndarray) -> bool:
        """Whether the search and the normal part at u1 are ``p``, found at ``key``.

        They are where ``p``'s search was restricted to the facets in use, those are the
        same, u1 equals the key at every unknown that search and the point kernels read
        (:meth:`dofs`), and at u1 the others are still beyond reach. A Newton on the
        unknowns within reach (:mod:`breakwater.stepping.reach`) ends on such a state:
        its solution differs from its last iterate at the far unknowns alone.
        """
        use = p["use"]
        if use is None or use[0] != np.count_nonzero(self.mask):
            return False
        at = use[1]
        return bool(equal_at(key, u1, at) and searchkernels.beyond_reach(
            searchkernels.current(self._sX, self._ps, u1),
            searchkernels.current(self._mX, self._pm, u1), self.mask, self._radius,
            self._edge))
