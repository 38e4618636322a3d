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
result does not depend on the partition. The Jacobian is exact: the derivative a complex
step per local DOF of a (slave facet, master facet) point takes, with the projection's
Newton differentiated too, so the implicit dependence of ξ̄ on the nodes is included.
The per-iteration work (the search, f_c, its Jacobian, the slip guard) runs in compiled
kernels (:mod:`breakwater.contact.searchkernels`, :mod:`breakwater.contact.forcekernels`)
with the arithmetic of the NumPy references (:mod:`breakwater.contact.projection`,
:mod:`breakwater.contact.pointkernels`; ``tests/test_contactkernels.py``).

The pair's jobs are layered: :class:`~breakwater.contact.surfacesearch.SurfaceSearch`
(the surfaces, the integration points and their projections, the state at the
interface unknowns), :class:`SurfaceForces` (the provider: f_c, its Jacobian, the slip
guard and the step's penetration check) and :class:`SurfaceContact` (what the outputs
measure: resultants, energies, the integration points' state; the general kind of
:class:`breakwater.model.pairs.Pair`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from dolfinx import fem

from breakwater.contact import (
    coupling,
    forcekernels,
    newtonaids,
    recordkernels,
    searchkernels,
    slavepoints,
)
from breakwater.contact.conforming import RELEASE
from breakwater.contact.facing import facing
from breakwater.contact.penetration import StepCheck, allowed_depth, initial_overlap
from breakwater.contact.surfaces import SurfacePair
from breakwater.contact.surfacesearch import SurfaceSearch
from breakwater.model.pairs import FieldNodes, StaticMeasures

if TYPE_CHECKING:
    from breakwater.model.layout import MonolithicLayout
    from breakwater.model.model import ContactModel

__all__ = ["QUANTITIES", "SurfaceContact", "SurfaceEnergy", "SurfaceForces", "nodal_friction",
           "start_slip"]

QUANTITIES = ("force_x", "force_y", "contact_length", "penetration")
"""The history quantities of a general pair (columns ``<name>_<quantity>``)."""


_NO_NODES = np.zeros(0, np.int64)
_NO_PAIRS = np.zeros((0, 2))


def scatter_add(out: np.ndarray, pos: np.ndarray, values: np.ndarray) -> np.ndarray:
    """out[pos] += values (skipping Dirichlet entries, −1), in array order; out returned."""
    pos, values = pos.ravel(), values.ravel()
    keep = pos >= 0
    out += np.bincount(pos[keep], weights=values[keep], minlength=len(out))
    return out


def nodal_friction(pair: SurfaceForces, lam: np.ndarray,
                   frozen: tuple[np.ndarray, np.ndarray, np.ndarray], v1: np.ndarray,
                   lin: np.ndarray) -> tuple[Any, ...]:
    """A general pair's friction normals and nodal friction at an iterate (kept).

    :func:`~.newtonaids.friction_normals` and
    :func:`~breakwater.contact.forcekernels.friction` of the slave nodes' normal forces
    ``lam``, the start-of-step projection ``frozen``,
    the velocities ``v1`` and the crawl points ``lin``. The residual and the Jacobian
    of one Newton iterate ask for the same: kept while those are the same objects (v₁
    read-only; λ a new array per search), the crawl points unchanged
    (:attr:`~.newtonaids.CrawlPoints.version`) and the law the same.

    Returns:
        ``(λ̂, s, k, v_T, force, unit)``: the scaled forces λ̂ = s λ and the scale, then
        the kernel's.
    """
    _, _, mu, chi = pair._law
    key = (pair.crawl.version, mu, chi)
    kept = pair._kept_friction
    if (kept is not None and kept[0] is lam and kept[1] is frozen and kept[2] is v1
            and kept[3] is lin and kept[4] == key):
        return kept[5]  # type: ignore[no-any-return]
    facet, N0, t0 = frozen
    lam_f, s = newtonaids.friction_normals(lam, facet)
    out = (lam_f, s, *forcekernels.friction(lam_f, facet, N0, t0, pair._node_pos, pair._pm,
                                            v1, mu, chi, lin))
    if not v1.flags.writeable:
        pair._kept_friction = (lam, frozen, v1, lin, key, out)
    return out



class SurfaceForces(SurfaceSearch, newtonaids.Regularised):
    """A general pair as a provider of the fast solver's interface: f_c and ∂f_c/∂Δa.

    Args: those of :class:`~breakwater.contact.surfacesearch.SurfaceSearch`.

    Attributes:
        memory: The slave nodes' slip velocities of the last accepted step, Newton's
            start of the next (:class:`~breakwater.contact.newtonaids.SlipMemory`).
    """

    def __init__(self, model: ContactModel, spec: SurfacePair, layout: MonolithicLayout,
                 interface: np.ndarray,
                 state: tuple[Sequence[fem.Function], Sequence[fem.Function],
                              Sequence[fem.Function], Sequence[fem.Function]],
                 dt: fem.Constant, beta1: float, beta2: float) -> None:
        super().__init__(model, spec, layout, interface, state, dt, beta1, beta2)
        self.memory = newtonaids.SlipMemory(self)
        self.step_check = StepCheck(spec, self.radius, allowed_depth(self.master, self.radius),
                                    self.node_X, self.node_pos, self.master.X, self.pos_m)
        # The master facets of reach(), marked in place: the searches' facets in use.
        self.in_use.mask = np.zeros(len(self.master.X), bool)
        # _friction at the accepted state of a recording(): (that state, λ, the forces).
        self._accepted_friction: tuple[Any, np.ndarray, dict[str, np.ndarray] | None] | None \
            = None
        self.crawl = newtonaids.CrawlPoints(len(self.node_pos))
        # nodal_friction's last: (λ, frozen, v₁, crawl points, key, result).
        self._kept_friction: tuple[Any, ...] | None = None

    def _friction(self, u0: np.ndarray, v1: np.ndarray, λ: np.ndarray,
                  accepted: bool = False) -> dict[str, np.ndarray] | None:
        """The nodal friction forces (None: no slave node in contact).

        Per slave node k in contact (λ_k > 0, a projection at the start of the step),
        the force ``−μ λ_k φ(v_T)`` (:class:`forms.ContactLaw`'s friction with the
        nodal normal force λ_k in place of the pressure; λ scaled where the contact
        ends within a facet, :func:`~.newtonaids.friction_normals`), with
        ``v_T = t₀ ⊗ t₀ (v_k − v̄_m(ξ̄₀))`` (:func:`~breakwater.contact.forcekernels.friction`).

        Args:
            u0: Displacements at the start of the step (the projection ξ̄₀).
            v1: Velocities of the iterate.
            λ: The slave nodes' normal forces.
            accepted: At the accepted state: the projection of the step that was
                accepted (the force the step applied: where the interface sticks,
                φ(v_T) turns a change of t₀ of 1e-10 into an O(1) change of the
                force), or, before any step, that of the state itself.
        """
        kept = self._accepted_friction
        if accepted and kept is not None and kept[0] is self._accepted and kept[1] is λ:
            return kept[2]  # within recording(): the history row's and the ledger's
        if accepted and self._step_frozen is not None:
            facet, N0, t0 = self._step_frozen
        else:
            facet, N0, t0 = self._frozen(u0)
        _, _, mu, chi = self._law
        λ_f, _ = newtonaids.friction_normals(λ, facet)
        k, v_T, force, unit = forcekernels.friction(λ_f, facet, N0, t0, self._node_pos,
                                                    self._pm, v1, mu, chi, self.crawl.none)
        out = None if not len(k) else {
            "k": k, "pos_s": self.node_pos[k], "pos_m": self.pos_m[facet[k]], "N0": N0[k],
            "t": t0[k], "v_T": v_T, "force": force, "unit": unit, "lam": λ_f}
        if accepted and self._accepted is not None:
            self._accepted_friction = (self._accepted, λ, out)
        return out

    # --- the provider ---------------------------------------------------------------

    def vector(self, accepted: bool = False) -> np.ndarray:
        """The contact residual at the interface unknowns (the same on every rank).

        Args:
            accepted: At the stepper's accepted state (u, v) instead of the iterate.
        """
        u0, u1, v1 = self._state(accepted=accepted)
        p = self._normal(u1)
        out = p["out"].copy()
        if self.spec.friction:
            self._step_frozen = frozen = self._frozen(u0)
            _, _, k, _, force, _ = nodal_friction(
                self, p["lam"], frozen, v1, self.crawl.none if accepted else self.crawl.at)
            if len(k):
                forcekernels.add_friction(out, k, force, frozen[0], frozen[1], self._node_pos,
                                          self._pm)
        return out

    def left_product(self, X: np.ndarray) -> np.ndarray:
        """X @ :meth:`matrix` from the matrix's structure.

        The matrix couples only the DOFs of the points in contact and of the slave
        nodes' start-of-step master facets (``act``): ``X[:, act] @ A[act, act]`` in the
        columns ``act``, O(rows(X) · |act|²) instead of the dense product's O(n³)
        (:func:`~breakwater.contact.forcekernels.left_product`).
        """
        act, A = self._jacobian()
        return forcekernels.left_product(np.ascontiguousarray(X, dtype=float), act, A)

    def active_jacobian(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`matrix` as ``(act, A)``: the unknowns it couples and its block there."""
        return self._jacobian()

    def matrix(self) -> np.ndarray:
        """∂(contact residual)/∂Δa at the interface unknowns, dense.

        The normal part by the complex steps' derivatives of the point kernel (the
        projection's Newton differentiated: exact, its implicit dependence included);
        the friction part by the chain rule through λ_k (the points' shares) and v_T
        (linear in Δa; ∂φ/∂v_T by complex steps)
        (:func:`~breakwater.contact.forcekernels.jacobian`).
        """
        act, A = self._jacobian()
        out = np.zeros((self.n, self.n))
        out[np.ix_(act, act)] = A
        return out

    def _jacobian(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`matrix` on the unknowns it couples: ``(act, A[act, act])``."""
        dt = self.step_dt()
        cu, cv = 0.5 * self.beta2 * dt**2, self.beta1 * dt
        u0, u1, v1 = self._state()
        p = self._normal(u1)
        eps, g0, mu, chi = self._law
        facet = N0 = t0 = None
        k = np.zeros(0, np.int64)
        v_T = unit = np.zeros((0, 2))
        lam = p["lam"]
        if self.spec.friction and len(p["index"]):
            frozen = facet, N0, t0 = self._frozen(u0)
            lam, s, k, v_T, _, unit = nodal_friction(self, lam, frozen, v1, self.crawl.at)
            unit = unit * s  # the friction's λ̂ = s λ, s taken as a constant: dλ̂ = s dλ
        if facet is None:
            facet, N0, t0 = np.zeros(0, np.int64), np.zeros((0, 1)), np.zeros((0, 2))
        return forcekernels.jacobian(
            self._sX, self._mX, self._ps, self._pm, u1, p["slave_facet"], p["facet"], p["Ns"],
            p["xi"], p["weight"], p["gap"], self.small_rotations, eps, g0, self._node_of,
            len(self._node_pos), cu, cv, bool(self.spec.friction), lam, k, v_T, unit,
            facet, N0, t0, self._node_pos, mu, chi)

    def precheck(self, x: np.ndarray, step: np.ndarray,
                 bulk: coupling.BulkStiffness | None = None) -> int:
        """Newton's slip guard at the slave nodes (:func:`~.newtonaids.slip_guard`).

        A slave node's slip velocity (relative to the master point under its start-of-step
        projection, along the tangent there; linear in Δa) that reverses from outside the
        stick band lands at zero, one in the law's curved zone on the law; one crawling
        along the saturated law stays, the next iterates' law linearised further along
        until :meth:`true_law` (:mod:`breakwater.contact.guardkernels`); at the nodes
        whose law holds their slip against the bulk (:mod:`~breakwater.contact.coupling`).

        Args:
            x: The current iterate (Δa at the interface unknowns).
            step: Newton's step, changed in place where cut.
            bulk: The bulk's stiffness on the unknowns (None: the guard acts everywhere).

        Returns:
            The nodes whose step changed (the same on every rank).
        """
        if not self.spec.friction:
            return 0
        return newtonaids.slip_guard(self, x, step, self._frozen, bulk)

    def true_law(self, crawl: bool = True) -> bool:
        """The iterates' friction is the law itself again; whether it was not."""
        return self.crawl.drop(crawl)

    def reach(self) -> np.ndarray | None:
        """The interface unknowns this step's contact may touch (within a step).

        The slave's DOFs and those of the master facets whose node box comes within
        twice the search radius of a slave facet's at the start of the step (kept from
        step to step: the set only grows). A projection is accepted within one radius,
        so a step that moves the slave less than a radius relative to the master finds
        no other facet; one that does is caught by the Newton on these unknowns
        (:class:`breakwater.stepping.reach.NearContact`), which then solves them all.

        Returns:
            Sorted interface positions; None outside :meth:`begin_step`/:meth:`end_step`.
        """
        if self._step is None:
            return None
        u0 = self._step_rows[0]
        searchkernels.mark_near(searchkernels.current(self._sX, self._ps, u0),
                                searchkernels.current(self._mX, self._pm, u0),
                                2.0 * self.radius, self.in_use.mask)
        return self.in_use.dofs()[1]  # kept while no facet is added

    def resolution(self, y: np.ndarray) -> float:
        """The round-off of f_c at y (:func:`breakwater.contact.newtonaids.resolution`)."""
        return newtonaids.resolution(self, y)

    def penetration(self, y: np.ndarray) -> str | None:
        """Why the step's solution Δa = y leaves a slave node beyond what the search sees.

        :class:`breakwater.contact.penetration.StepCheck` (None: it does not); the same on every
        rank.
        """
        u, v, a, da = self._start(y)
        dt = self.step_dt()
        # u₁ as GN22.update computes it (gn22_kinematics): the next step's u₀ bit for bit.
        u1 = u + (dt * v + 0.5 * dt**2 * a + 0.5 * self.beta2 * dt**2 * da)
        return self.step_check(u, u1, lambda: (*self._frozen(u), self._frozen_projected))



class SurfaceContact(SurfaceForces):
    """One general pair: the fast solver's provider and what the outputs measure on it.

    The general kind of :class:`breakwater.model.pairs.Pair`.

    Args: those of :class:`~breakwater.contact.surfacesearch.SurfaceSearch`.
    """

    _field_points: slavepoints.SlavePoints | None = None  # the slave nodes, on first use
    # The last state() and the search (_normal's dict) it was built from.
    _state_of: tuple[dict[str, Any], dict[str, np.ndarray]] | None = None
    # The last _record() of a recording: (the accepted state, the search, the record).
    _record_of: tuple[Any, dict[str, Any], np.ndarray] | None = None

    @property
    def name(self) -> str:
        """The pair's name (the case's ``[contact.<name>]``)."""
        return self.spec.name

    @property
    def columns(self) -> list[str]:
        """``<name>_force_x``, ``_force_y``, ``_contact_length``, ``_penetration``."""
        return [f"{self.name}_{q}" for q in QUANTITIES]

    def measure(self) -> dict[str, float]:
        """The pair's history values at the accepted state (collective).

        The resultant on the slave (:meth:`resultant`), the reference length of the
        integration points where g_n ≤ 0 and the largest ⟨−g_n⟩₊ there.
        """
        r = self._record()
        return dict(zip(self.columns, (
            float(r[4] + r[6]), float(r[5] + r[7]), float(r[2]), float(r[3])), strict=True))

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
        r = self._record(accepted)
        return r[4:6].copy(), r[6:8].copy()

    def _record(self, accepted: bool = True) -> np.ndarray:
        """:func:`~breakwater.contact.recordkernels.pair_record` at the state (collective).

        Within a :meth:`recording` of the accepted state: once (the history row's
        resultant and measures, the ledger's energies).
        """
        u0, u1, v1 = self._state(accepted=accepted)
        p = self._normal(u1)
        kept = self._record_of
        if accepted and kept is not None and kept[0] is self._accepted and kept[1] is p:
            return kept[2]
        eps, _, mu, chi = self._law
        fr = self._friction(u0, v1, p["lam"], accepted) if self.spec.friction else None
        k, v_T, force, λ_f = ((fr["k"], fr["v_T"], fr["force"], fr["lam"]) if fr is not None
                              else (_NO_NODES, _NO_PAIRS, _NO_PAIRS, p["lam"]))
        r = recordkernels.pair_record(p["index"], p["gap"], p["all_weight"], p["forces"],
                                      self.slave.X.shape[1], eps, k, λ_f, v_T, force, mu, chi)
        if accepted and self._accepted is not None:
            self._record_of = (self._accepted, p, r)
        return r

    def sliding_velocities(self, d: np.ndarray, speed: float) -> tuple[np.ndarray, np.ndarray]:
        """Velocities that start the slave nodes in contact sliding along d (a release).

        At the current iterate, each node in contact (the friction's) slips at ``speed``
        along its tangent, in the direction of d
        (:func:`~breakwater.contact.newtonaids.sliding_velocities`: a held component's
        share is its master's).

        Args:
            d: The unit sliding direction of the slave relative to the master.
            speed: The slip speed.

        Returns:
            The interface positions set and their velocities (flat).
        """
        none = np.zeros(0, np.int64), np.zeros(0)
        if not self.spec.friction:
            return none
        u0, u1, v1 = self._state()
        fr = self._friction(u0, v1, self._normal(u1)["lam"])
        if fr is None:
            return none
        facet, N0, t0 = self._frozen(u0)  # the projection _friction took
        return newtonaids.sliding_velocities(self._node_pos, self._pm, facet, N0,
                                             t0[:, None, :], fr["k"], d, speed, self.n)

    def energies(self) -> tuple[float, float]:
        """The penalty energy and the friction power at the accepted state (the ledger).

        ``∫ ½ ε_n ⟨−g_n⟩₊²`` on the normal integration points and
        ``Σ_k μ λ_k |v_T|²/sqrt(|v_T|² + χ²)`` on the slave nodes.
        """
        r = self._record()
        return float(r[0]), float(r[1])

    def energy_terms(self, u0: Sequence[fem.Function], v0: Sequence[fem.Function]
                     ) -> SurfaceEnergy:
        """The pair's ledger terms (:class:`SurfaceEnergy`; ``u0``, ``v0`` unused)."""
        return SurfaceEnergy(self)

    # --- the outputs at the slave surface's material points (contact.slavepoints) ---

    def snapshot(self, u: Sequence[fem.Function]) -> dict[str, np.ndarray]:
        """The slave nodes' state (:func:`breakwater.contact.slavepoints.snapshot`)."""
        return slavepoints.snapshot(self, u)

    def field_nodes(self) -> FieldNodes:
        """The slave surface, the slave's degree and the slave surface's nodes."""
        if self._field_points is None:
            self._field_points = slavepoints.SlavePoints.nodes(self)
        return FieldNodes(self.spec.slave_surface, self.model.body(self.spec.slave).index,
                          self._field_points.X)

    def field_values(self, u: Sequence[fem.Function], v: Sequence[fem.Function] | None
                     ) -> dict[str, np.ndarray]:
        """:meth:`breakwater.contact.slavepoints.SlavePoints.evaluate` at the slave nodes."""
        if self._field_points is None:
            self._field_points = slavepoints.SlavePoints.nodes(self)
        return self._field_points.evaluate(self.interface_values(u),
                                           None if v is None else self.interface_values(v))

    def static_measures(self, u: Sequence[fem.Function]) -> StaticMeasures:
        """:func:`breakwater.contact.slavepoints.static_measures` at ``u``."""
        E = (self.model.body(self.spec.slave).spec.material.E,
             self.model.body(self.spec.master).spec.material.E)
        return slavepoints.static_measures(self, self.state(), u, E)

    def static_check(self) -> str | None:
        """Why the pair cannot start from the meshed configuration (None: it can).

        A slave surface that faces no master facet
        (:func:`breakwater.contact.facing.facing`), else bodies overlapped beyond what
        the search sees (:func:`breakwater.contact.penetration.initial_overlap`; surfaces
        turned towards each other but meshed through each other are this case);
        collective.
        """
        overlap = initial_overlap(self.model, self.spec)
        return facing(self.model, self.spec, overlap is not None) or overlap

    def probe(self, point: Sequence[float], name: str) -> slavepoints.SurfaceProbe:
        """A :class:`breakwater.contact.slavepoints.SurfaceProbe` at ``point``."""
        return slavepoints.SurfaceProbe(self, np.asarray(point, float), name)

    def state(self, accepted: bool = True) -> dict[str, np.ndarray]:
        """Every normal integration point (every rank), as :meth:`resultant`.

        Returns:
            ``x`` (current position), ``gap`` (g_n; NaN without a projection),
            ``pressure``, ``weight`` (reference length), ``facet`` (master facet, −1:
            none), ``xi`` (its local coordinate), ``slave_facet`` (the slave facet of a
            point with a projection, −1: none).
        """
        _, u1, _ = self._state(accepted=accepted)
        p = self._normal(u1)  # the points of this state (cached: the search once)
        if self._state_of is not None and self._state_of[0] is p:
            return self._state_of[1]  # the same search: the measures and the ledger's
        points = p["all_x"]
        total = len(points)
        out: dict[str, Any] = {"x": points, "weight": p["all_weight"],
                               "gap": np.full(total, np.nan), "pressure": np.zeros(total),
                               "facet": np.full(total, -1), "xi": np.zeros(total),
                               "slave_facet": np.full(total, -1)}
        if len(p["index"]):
            gap = p["gap"]
            i = p["index"]
            out["gap"][i] = gap
            out["pressure"][i] = self.law.normal.pressure(gap)
            out["facet"][i] = p["facet"]
            out["xi"][i] = p["xi_bar"]
            out["slave_facet"][i] = p["slave_facet"]
        self._state_of = (p, out)
        return out


def start_slip(pair: SurfaceContact,
               frozen: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
    """Slip velocities that carry a static state's friction into the dynamics.

    At the pair's current state, the static state at rest (the frictional relaxation's
    ``_creep``), whose last step's projection was ``frozen`` (None: the state's
    own): per slave node in contact, the speed where the law gives the friction
    of that step (the inverse law ``χ f/sqrt(1 − f²)``, f = |F|/(μλ)), at most
    :data:`RELEASE` χ, along the tangent of the state's own projection (the one
    the dynamics starts with), against F; where frozen is None, the state's own slip,
    capped at RELEASE χ.

    Measured on the Goda caisson meshed apart (2026-11-28): a node that slides in
    the static state (a base corner under its Poisson expansion) kept its static
    slip over the pseudo time, 9e-6 m/s (1e5 χ) among nodes at rest; Rayleigh
    damping's β K v gave it 1.7e5 m/s² at t = 0, the first step stored 0.84 J/m of
    strain over the static state's 0.112 and the ledger counted −0.84 J/m of
    numerical dissipation. At RELEASE χ the law carries μλ to 5e-5. And a slave
    node on a master vertex takes the other facet's tangent when its projection
    is made again at the state itself: the static stage's slip u/τ includes the
    penalty's overlap, whose share along a tangent 2e-6 rad off gave that node
    4.15 N/m of friction instead of −0.05.

    Set as the velocities of the slave node's free components and, for its held ones (a
    node on a ``[fixed]`` group), of its master facet's nodes
    (:func:`~breakwater.contact.newtonaids.slip_velocities_at`, issue 25): a block held
    along x by a side fixed along x, whose corner node's static friction is the base's
    slip under it, lost that friction and its reaction on the base at t = 0 (|a₀| 22 m/s²,
    the friction resultant −132, 50, −138, 39 N/m over the first steps).

    Returns:
        The interface positions set and their velocities (flat).
    """
    none = np.zeros(0, np.int64), np.zeros(0)
    if not pair.spec.friction:
        return none
    u0, u1, v1 = pair._state()
    lam = pair._normal(u1)["lam"]
    now = pair._friction(u0, v1, lam)
    if now is None:
        return none  # none in contact
    _, _, mu, chi = pair._law
    facet, N0, _ = pair._frozen(u0)  # the projection _friction took
    if frozen is None:
        speed = np.linalg.norm(now["v_T"], axis=1)
        cap = RELEASE * chi
        return newtonaids.slip_velocities_at(
            pair._node_pos, pair._pm, facet, N0, now["k"],
            now["v_T"] * (cap / np.maximum(speed, cap))[:, None], pair.n)
    λ_f, _ = newtonaids.friction_normals(lam, frozen[0])
    k, _, F_k, _ = forcekernels.friction(λ_f, *frozen, pair._node_pos, pair._pm, v1, mu,
                                         chi, pair.crawl.none)
    force = np.zeros((len(pair.node_pos), 2))
    force[k] = F_k
    F = force[now["k"]]
    f = np.minimum(np.linalg.norm(F, axis=1) / (mu * now["lam"][now["k"]]), 1.0)
    speed = np.minimum(chi * f / np.sqrt(np.maximum(1.0 - f * f, 1e-300)), RELEASE * chi)
    against = -np.sign(np.einsum("kd,kd->k", F, now["t"]))
    return newtonaids.slip_velocities_at(pair._node_pos, pair._pm, facet, N0, now["k"],
                                         (against * speed)[:, None] * now["t"], pair.n)


class SurfaceEnergy:
    """A general pair's ledger terms: :meth:`SurfaceContact.energies` as a rank's share.

    The pair's energies are the same on every rank: rank 0's share is the whole, the
    others' zero, so that the ledger's one reduction over the ranks gives them
    exactly. No numerical dissipation share: the pair's law is not a form.

    Args:
        contact: The pair.
    """

    def __init__(self, contact: SurfaceContact) -> None:
        self.contact = contact

    def local(self, step: bool) -> np.ndarray:
        """The rank's share (:meth:`breakwater.model.pairs.EnergyTerms.local`; collective)."""
        energy, power = self.contact.energies()
        first = self.contact.comm.rank == 0
        return np.array([energy, power, 0.0]) if first else np.zeros(3)
