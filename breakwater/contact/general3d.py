"""General contact pairs in 3-D: two surfaces of triangles that need not match.

The 3-D kind of :mod:`breakwater.contact.general` (issue 25), written the same way: the
slave's integration points (:class:`~breakwater.contact.surfacesearch3d.SurfaceSearch3D`:
mortar segments or Gauss points per slave face) are projected onto the master surface in
the current configuration (closest point, finite sliding), the normal gap is
``g_n = (x_s − x̄_m)·n̄`` with n̄ the master's unit outward normal ``x_ξ × x_η/|x_ξ × x_η|``
at the projection, the penalty traction ``t = ε_n⟨−g_n⟩₊ n̄``; the slave receives
``−∫ t N_s``, the master ``+∫ t N̄_m`` (action and reaction).

The pair is a provider of the fast solver (:mod:`breakwater.stepping.condensed`), as the
2-D pair: ``vector()`` and ``matrix()`` give f_c and its exact Jacobian on the interface
unknowns (:mod:`breakwater.contact.forcekernels3d`: a complex step per local DOF, the
projection's Newton differentiated), every rank evaluating the same points in the same
order on the gathered state (the result does not depend on the partition).

Friction (isotropic regularised Coulomb, the paper's law and χ) acts at the slave nodes,
the slip a tangent vector relative to the master material point under the node at the
start of the step (:mod:`breakwater.contact.friction3d`), its Jacobian consistent. The
2-D pair's slip guard is, with its crawl points (:class:`~.newtonaids.CrawlPoints`: a
reversal lands at zero slip, a step into the law's curved zone on the law, a slip
crawling along the saturated law linearises the law further along); its slip memory is
not (Newton starts at GN22's predictor). The outputs are measured at the slave
nodes (:class:`SlaveNodes3D`): gap, law pressure ε_n⟨−g_n⟩₊, tangential velocity and
the law's friction traction at their projection, the slip relative to the master
material point under them as meshed; pair probes are refused in one line.
"""

from __future__ import annotations

import logging
import weakref
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from dolfinx import fem

from breakwater.common.arrays import first_by_position
from breakwater.common.errors import CaseError
from breakwater.contact import (
    coupling,
    forcekernels,
    forcekernels3d,
    friction3d,
    newtonaids,
    searchkernels3d,
)
from breakwater.contact.facing import facing
from breakwater.contact.nodalpressure3d import VertexPressure
from breakwater.contact.projection3d import shape, surface, unit_normal
from breakwater.contact.searchkernels import current
from breakwater.contact.surfaces import SurfacePair
from breakwater.contact.surfacesearch3d import SurfaceSearch3D, area_element
from breakwater.model.pairs import FieldNodes, StaticMeasures, facet_size, settlement

if TYPE_CHECKING:
    from breakwater.model.layout import MonolithicLayout
    from breakwater.model.model import ContactModel

__all__ = ["QUANTITIES", "SlaveNodes3D", "SurfaceContact3D", "SurfaceForces3D", "nodal_gaps",
           "reference_gaps3d", "smallest_gap"]

QUANTITIES = ("force_x", "force_y", "force_z", "contact_area", "penetration")
"""The history quantities of a 3-D general pair (columns ``<name>_<quantity>``)."""

OVERLAP = 1e-3
"""A slave node meshed deeper inside the master than this fraction of the face under it
is an overlap of the meshes (as :data:`breakwater.contact.penetration.OVERLAP`)."""

NODE_INSIDE = 1e-6
"""How far (in ξ, η) a slave node's projection may fall past a master face's edge and
still be on it (the integration points': :data:`~breakwater.contact.projection.INSIDE`).
A node on a symmetry plane lies on the master's boundary edge, and its closest point on
the curved face found past it by more than 1e-9: measured on Hertz's quarter model, 6 of
the 20 nodes inside 0.9 a (all on the planes x = 0 and z = 0) had no gap with INSIDE, none
with 1e-6 (a millionth of a face)."""

log = logging.getLogger("breakwater.contact.general3d")
_OVERLAP_WARNED: weakref.WeakKeyDictionary[Any, set[str]] = weakref.WeakKeyDictionary()
"""Per mesh (the models of a run share it), the pairs whose overlap was warned of (the
relaxation's steppers and the run's check each: the line was printed twice)."""

class _NoSlip:
    """The slip memory of a frictionless pair (:class:`~.newtonaids.SlipMemory`): none."""

    slip = None

    def predict(self, y: np.ndarray) -> int:
        return 0

    def converged(self, y: np.ndarray) -> None:
        """Nothing to keep."""

    def accept(self) -> None:
        """Nothing to keep."""

    def saved(self) -> None:
        return None

    def load(self, saved: Any) -> None:
        """Nothing to load."""


class _AllFacets:
    """The master faces in use (:class:`~.surfacesearch.FacetsInUse`): all, always."""

    def __init__(self, count: int) -> None:
        self.mask = np.ones(count, bool)


class SurfaceForces3D(SurfaceSearch3D, newtonaids.Regularised):
    """A 3-D general pair as a provider of the fast solver: f_c and ∂f_c/∂Δa.

    Args: those of :class:`~breakwater.contact.surfacesearch.SurfaceSearch`.
    """

    def __init__(self, model: ContactModel, spec: SurfacePair, layout: MonolithicLayout,
                 interface: np.ndarray,
                 state: tuple[Sequence[fem.Function], Sequence[fem.Function],
                              Sequence[fem.Function], Sequence[fem.Function]],
                 dt: fem.Constant, beta1: float, beta2: float) -> None:
        super().__init__(model, spec, layout, interface, state, dt, beta1, beta2)
        self.memory = _NoSlip()
        self.in_use = _AllFacets(len(self.master.X))
        # The projection of the step the last vector() was of (the accepted state's
        # friction is that step's, as the 2-D pair's).
        self._step_frozen: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self.crawl = newtonaids.CrawlPoints(len(self.node_pos), 2, friction3d.slip_guard)

    def _friction(self, u0: np.ndarray, v1: np.ndarray, lam: np.ndarray,
                  accepted: bool = False, iterate: bool = False) -> dict[str, Any] | None:
        """The slave nodes' friction (:mod:`~breakwater.contact.friction3d`; None: none).

        Args:
            u0: Displacements at the start of the step (the master points).
            v1: Velocities of the iterate.
            lam: The slave nodes' normal forces.
            accepted: At the accepted state: the projection of the step accepted.
            iterate: Newton's (f_c, its Jacobian): the law's tangent lines at the crawl
                points (:attr:`crawl`); else the law itself.
        """
        if not self.spec.friction:
            return None
        fz = (self._step_frozen if accepted and self._step_frozen is not None
              else friction3d.frozen(self, u0))
        _, _, mu, chi = self._law
        lam_f, scale = newtonaids.friction_normals(lam, fz[0])
        k, c, force, unit = friction3d.friction(
            lam_f, *fz, self._node_pos, self._pm, v1, mu, chi,
            self.crawl.at if iterate else self.crawl.none)
        return {"frozen": fz, "lam": lam_f, "scale": scale, "k": k, "c": c, "force": force,
                "unit": unit}

    def vector(self, accepted: bool = False) -> np.ndarray:
        """The contact residual at the interface unknowns (the same on every rank).

        Args:
            accepted: At the stepper's accepted state (u, v) instead of the iterate.
        """
        u0, u1, v1 = self._state(accepted=accepted)
        p = self._normal(u1)
        out = np.asarray(p["out"]).copy()
        if self.spec.friction:
            self._step_frozen = friction3d.frozen(self, u0)
            fr = self._friction(u0, v1, p["lam"], iterate=not accepted)
            assert fr is not None
            facet0, N0, _ = fr["frozen"]
            friction3d.add_friction(out, fr["k"], fr["force"], facet0, N0, self._node_pos,
                                    self._pm)
        return out

    def _jacobian(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`matrix` on the unknowns it couples: ``(act, A[act, act])``."""
        dt = self.step_dt()
        u0, u1, v1 = self._state()
        p = self._normal(u1)
        eps, g0, mu, chi = self._law
        fr = self._friction(u0, v1, p["lam"])
        extra = (np.zeros(0, np.int64) if fr is None else friction3d.friction_dofs(
            fr["k"], fr["frozen"][0], self._node_pos, self._pm))
        act, A, rows, dpw = forcekernels3d.jacobian(
            self._sX, self._mX, self._ps, self._pm, u1, p["slave_facet"], p["facet"],
            p["Ns"], p["xi"], p["weight"], p["gap"], self.small_rotations, eps, g0,
            0.5 * self.beta2 * dt**2, extra)
        if fr is not None and len(fr["k"]):
            where = np.full(self.n + 1, -1, np.int64)
            where[act] = np.arange(len(act))
            facet0, N0, T0 = fr["frozen"]
            friction3d.friction_jacobian(
                A, where, fr["k"], fr["c"], fr["unit"], fr["lam"], p["lam"], fr["scale"],
                facet0, N0, T0, self._node_pos, self._pm, mu, chi, self.beta1 * dt,
                p["slave_facet"], self._node_of, p["Ns"], rows, dpw)
        return act, A

    def matrix(self) -> np.ndarray:
        """∂(contact residual)/∂Δa at the interface unknowns, dense."""
        act, A = self._jacobian()
        out = np.zeros((self.n, self.n))
        out[np.ix_(act, act)] = A
        return out

    def active_jacobian(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`matrix` as ``(act, A)``: the unknowns it couples and its block there."""
        return self._jacobian()

    def left_product(self, X: np.ndarray) -> np.ndarray:
        """X @ :meth:`matrix` from the matrix's structure."""
        act, A = self._jacobian()
        return forcekernels.left_product(  # type: ignore[no-any-return]
            np.ascontiguousarray(X, dtype=float), act, A)

    def precheck(self, x: np.ndarray, step: np.ndarray,
                 bulk: coupling.BulkStiffness | None = None) -> int:
        """Newton's slip guard at the slave nodes (:func:`~.friction3d.slip_guard`).

        The 2-D pair's (:meth:`~breakwater.contact.general.SurfaceForces.precheck`, its
        arguments and return): crawl points (:class:`~.newtonaids.CrawlPoints`) until
        :meth:`true_law`, at the nodes whose law holds their slip against the bulk.
        """
        if not self.spec.friction:
            return 0
        return newtonaids.slip_guard(self, x, step, lambda u0: friction3d.frozen(self, u0),
                                     bulk)

    def true_law(self, crawl: bool = True) -> bool:
        """The iterates' friction is the law itself again; whether it was not."""
        return self.crawl.drop(crawl)

    def reach(self) -> np.ndarray | None:
        """None: the step's contact may touch any interface unknown."""
        return None

    def resolution(self, y: np.ndarray) -> float:
        """The round-off of f_c at y: the friction's (:func:`~.friction3d.round_off`).

        0 without friction: the normal part's round-off stays below the Newton's
        tolerances.
        """
        if not self.spec.friction:
            return 0.0
        u0, u1, v1 = self._state(y)
        fr = self._friction(u0, v1, self._normal(u1)["lam"])
        assert fr is not None
        return friction3d.round_off(self, y, fr["lam"], fr["k"], fr["c"], fr["frozen"])

    def penetration(self, y: np.ndarray) -> str | None:
        """Why the step's solution Δa = y leaves a slave node deeper than half a search radius.

        Deeper, the node may leave the search (its projection within a radius): the
        step is refused and retried smaller (None: it does not; every rank the same).
        """
        u, v, a, da = self._start(y)
        dt = self.step_dt()
        u1 = u + (dt * v + 0.5 * dt**2 * a + 0.5 * self.beta2 * dt**2 * da)
        x = self.node_X + u1[self.node_pos]
        gap, _, _ = nodal_gaps(self, x, current(self._mX, self._pm, u1))
        depth = -np.nan_to_num(gap, nan=0.0)
        k = int(np.argmax(depth)) if len(depth) else 0
        if len(depth) and depth[k] > 0.5 * self.radius:
            where = ", ".join(f"{c:.4g}" for c in self.node_X[k])
            return (f"contact '{self.spec.name}': slave node at ({where}) m would end the "
                    f"step {depth[k]:.3g} m inside the master, beyond half the search "
                    f"radius {self.radius:.3g} m")
        return None


def nodal_gaps(pair: SurfaceSearch3D, x: np.ndarray, xm: np.ndarray,
               radius: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The gap of points ``x`` to the master surface ``xm``, NaN: no projection.

    Within ``radius`` (None: the pair's search radius), along the master's normal at
    the closest point (the reference surface's with small rotations).

    Returns:
        g_n, the master face (−1: none) and (ξ̄, η̄) of each point.
    """
    facet, xi = searchkernels3d.project(np.ascontiguousarray(x), xm,
                                         pair.radius if radius is None else radius, NODE_INSIDE)
    gap = np.full(len(x), np.nan)
    on = facet >= 0
    if on.any():
        nodes = xm[facet[on]]
        x_bar, dx, _ = surface(nodes, xi[on])
        ref = pair._mX[facet[on]] if pair.small_rotations else nodes
        n = unit_normal(surface(ref, xi[on])[1]) if pair.small_rotations else unit_normal(dx)
        gap[on] = np.sum((x[on] - x_bar) * n, axis=1) + pair._law[1]
    return gap, facet, xi


def reference_gaps3d(pair: SurfaceSearch3D, radius: float) -> np.ndarray:
    """Per slave node as meshed, ``((X_k − X̄)·n̄) n̄`` ``(nodes, 3)`` (0: no projection).

    X̄ the closest point of the master surface as meshed within ``radius``, n̄ its unit
    normal there (:class:`breakwater.statics.pseudostep.SlipOrigin`'s landing points).
    """
    X = np.ascontiguousarray(pair.node_X)
    facet, xi = searchkernels3d.project(X, pair._mX, radius, NODE_INSIDE)
    out = np.zeros_like(X)
    on = facet >= 0
    if on.any():
        x_bar, dx, _ = surface(pair._mX[facet[on]], xi[on])
        n = unit_normal(dx)
        out[on] = np.sum((X[on] - x_bar) * n, axis=1)[:, None] * n
    return out


def smallest_gap(pair: SurfaceSearch3D, x: np.ndarray, u: np.ndarray, radius: float) -> float:
    """The smallest gap of the points ``x`` within ``radius`` of the master (inf: none)."""
    gap = nodal_gaps(pair, x, current(pair._mX, pair._pm, u), radius)[0]
    return float(np.nan_to_num(gap, nan=np.inf).min(initial=np.inf))


class SlaveNodes3D:
    """The contact state at a 3-D general pair's slave nodes (its fields and snapshots).

    Each node's master material point under it as meshed (its closest point on the
    reference master surface; nodes with none are left without slip) is found once.

    Args:
        pair: The pair.
    """

    def __init__(self, pair: SurfaceSearch3D) -> None:
        self.pair = pair
        mX = pair._mX
        self.facet0, self.xi0 = searchkernels3d.project(
            np.ascontiguousarray(pair.node_X), mX, pair.radius, NODE_INSIDE)
        on = self.facet0 >= 0
        self.vertex_pressure = VertexPressure(pair._sX, pair.node_of, len(pair.node_X),
                                              area_element)
        self.N0 = np.zeros((len(on), mX.shape[1]))
        self.normal0 = np.zeros((len(on), 3))
        if on.any():
            self.N0[on] = shape(self.xi0[on], mX.shape[1])[0]
            self.normal0[on] = unit_normal(surface(mX[self.facet0[on]], self.xi0[on])[1])

    def evaluate(self, u: np.ndarray, v: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """The nodes' state at the interface values ``u``, ``v`` (None: at rest).

        Returns:
            ``x``, ``u_slave``, ``u_master`` (at the node's master material point as
            meshed), ``normal`` (the master's at the current projection; 0: none),
            ``gap`` (NaN: no projection), ``pressure`` (the applied pressure
            ε_n⟨−g_n⟩₊ of the integration points on the nodes:
            :class:`~breakwater.contact.nodalpressure3d.VertexPressure`),
            ``law_pressure`` (ε_n⟨−g_n⟩₊ at the node's own projection), ``slip``
            (``(I − n₀⊗n₀)(u_s − u_m(X̄₀))``), ``slip_velocity``
            (``(I − n̄⊗n̄)(v_s − v̄_m)``) and ``friction_traction``
            (−μ p v_T/sqrt(|v_T|² + χ²), the law's at the node).
        """
        p = self.pair
        v = np.zeros_like(u) if v is None else v
        us, vs = u[p.node_pos], v[p.node_pos]
        x = p.node_X + us
        xm = current(p._mX, p._pm, u)
        gap, facet, xi = nodal_gaps(p, x, xm)
        on = facet >= 0
        normal = np.zeros_like(x)
        v_T = np.zeros_like(x)
        if on.any():
            normal[on] = unit_normal(surface(xm[facet[on]], xi[on])[1])
            Nm = shape(xi[on], xm.shape[1])[0]
            v_bar = np.einsum("kn,knd->kd", Nm, v[p.pos_m[facet[on]]])
            rel = vs[on] - v_bar
            v_T[on] = rel - np.sum(rel * normal[on], axis=1)[:, None] * normal[on]
        um0 = np.einsum("kn,knd->kd", self.N0, u[p.pos_m[np.maximum(self.facet0, 0)]])
        rel0 = us - um0
        n0 = self.normal0
        slip = np.where((self.facet0 >= 0)[:, None],
                        rel0 - np.sum(rel0 * n0, axis=1)[:, None] * n0, 0.0)
        eps, _, mu, chi = p._law
        law = np.where(on, eps * np.maximum(-np.nan_to_num(gap, nan=1.0), 0.0), 0.0)
        points = p._normal(u)
        pressure = self.vertex_pressure(points["slave_facet"], points["Ns"], points["weight"],
                                        eps * np.maximum(-points["gap"], 0.0))
        speed = np.sqrt(np.sum(v_T * v_T, axis=1) + chi * chi)
        traction = -(mu * pressure / speed)[:, None] * v_T
        return {"x": x, "u_slave": us, "u_master": um0, "normal": normal, "gap": gap,
                "pressure": pressure, "law_pressure": law, "slip": slip, "slip_velocity": v_T,
                "friction_traction": traction}


class SurfaceContact3D(SurfaceForces3D):
    """One 3-D general pair: the fast solver's provider and what the outputs measure on it.

    The 3-D general kind of :class:`breakwater.model.pairs.Pair`.

    Args: those of :class:`~breakwater.contact.surfacesearch.SurfaceSearch`.
    """

    _nodes: SlaveNodes3D | None = None

    @property
    def name(self) -> str:
        """The pair's name (the case's ``[contact.<name>]``)."""
        return self.spec.name

    @property
    def columns(self) -> list[str]:
        """``<name>_force_x``, ``_force_y``, ``_force_z``, ``_contact_area``, ``_penetration``."""
        return [f"{self.name}_{q}" for q in QUANTITIES]

    def _record(self, accepted: bool = True) -> np.ndarray:
        """The pair's sums at the state.

        (penalty energy, contact area, largest ⟨−g_n⟩₊, the normal resultant on the slave
        (3), the friction resultant on it (3), the friction power).
        """
        u0, u1, v1 = self._state(accepted=accepted)
        p = self._normal(u1)
        closed = p["gap"] <= 0.0
        w = p["weight"][closed]
        g = p["gap"][closed]
        eps, _, mu, chi = self._law
        ns = self._sX.shape[1]
        force = -p["forces"][:, :ns].sum(axis=(0, 1)) if len(p["forces"]) else np.zeros(3)
        fr = self._friction(u0, v1, p["lam"], accepted)
        friction, power = np.zeros(3), 0.0
        if fr is not None and len(fr["k"]):
            friction = fr["force"].sum(axis=0)
            power = friction3d.power(fr["lam"], fr["k"], fr["c"], mu, chi)
        return np.array([float(np.sum(w * 0.5 * eps * g * g)), float(w.sum()),
                         float(-g.min(initial=0.0)), *force, *friction, power])

    def measure(self) -> dict[str, float]:
        """The pair's history values at the accepted state (collective)."""
        r = self._record()
        total = r[3:6] + r[6:9]
        return dict(zip(self.columns, (float(total[0]), float(total[1]), float(total[2]),
                                       float(r[1]), float(r[2])), strict=True))

    def resultant(self, accepted: bool = True) -> np.ndarray:
        """∫ t_s: the force the master exerts on the slave (N)."""
        r = self._record(accepted)
        return r[3:6] + r[6:9]

    def resultants(self, accepted: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """The normal and friction parts of :meth:`resultant`."""
        r = self._record(accepted)
        return r[3:6].copy(), r[6:9].copy()

    def sliding_velocities(self, d: np.ndarray, speed: float) -> tuple[np.ndarray, np.ndarray]:
        """Velocities that start the slave nodes in contact sliding along d (a release).

        :meth:`breakwater.contact.general.SurfaceContact.sliding_velocities` of a 3-D
        pair: the slip along d's part in each node's tangent plane.

        Returns:
            The interface positions set and their velocities (flat).
        """
        u0, u1, v1 = self._state()
        fr = self._friction(u0, v1, self._normal(u1)["lam"])
        if fr is None or not len(fr["k"]):
            return np.zeros(0, np.int64), np.zeros(0)
        facet, N0, T0 = fr["frozen"]
        return newtonaids.sliding_velocities(self._node_pos, self._pm, facet, N0, T0,
                                             fr["k"], d, speed, self.n)

    def energies(self) -> tuple[float, float]:
        """The penalty energy and the friction power at the accepted state (the ledger).

        ``∫ ½ ε_n ⟨−g_n⟩₊²`` and ``Σ_k μ λ_k |c|²/sqrt(|c|² + χ²)``.
        """
        r = self._record()
        return float(r[0]), float(r[9])

    def energy_terms(self, u0: Sequence[fem.Function], v0: Sequence[fem.Function]
                     ) -> _Energy:
        """The pair's ledger terms (``u0``, ``v0`` unused)."""
        return _Energy(self)

    def state(self, accepted: bool = True) -> dict[str, np.ndarray]:
        """Every integration point (every rank).

        Returns:
            ``x``, ``weight`` (reference area), ``gap`` (NaN: no projection),
            ``pressure``, ``facet`` (−1: none), ``xi`` ``(K, 2)`` and ``slave_facet``
            (−1: no projection).
        """
        _, u1, _ = self._state(accepted=accepted)
        p = self._normal(u1)
        total = len(p["all_x"])
        out: dict[str, Any] = {"x": p["all_x"], "weight": p["all_weight"],
                               "gap": np.full(total, np.nan), "pressure": np.zeros(total),
                               "facet": np.full(total, -1), "xi": np.zeros((total, 2)),
                               "slave_facet": np.full(total, -1)}
        i = p["index"]
        out["gap"][i] = p["gap"]
        out["pressure"][i] = self._law[0] * np.maximum(-p["gap"], 0.0)
        out["facet"][i] = p["facet"]
        out["xi"][i] = p["xi_bar"]
        out["slave_facet"][i] = p["slave_facet"]
        return out

    def _slave_nodes(self) -> SlaveNodes3D:
        if self._nodes is None:
            self._nodes = SlaveNodes3D(self)
        return self._nodes

    def snapshot(self, u: Sequence[fem.Function]) -> dict[str, np.ndarray]:
        """The slave nodes' state, sorted by coordinates.

        ``x``, ``normal``, ``gap``, ``slip`` (vector), ``pressure`` (the integration
        points' on the nodes, :class:`~breakwater.contact.nodalpressure3d.VertexPressure`)
        and ``pressure_dual`` (the same: it is never negative, nothing to clip).
        """
        s = self._slave_nodes().evaluate(self.interface_values(u))
        order = np.lexsort(self.node_X.T[::-1])
        return {"x": self.node_X[order], "normal": s["normal"][order], "gap": s["gap"][order],
                "slip": s["slip"][order], "pressure": s["pressure"][order],
                "pressure_dual": s["pressure"][order]}

    def field_nodes(self) -> FieldNodes:
        """The slave surface, the slave's degree and the slave surface's nodes."""
        return FieldNodes(self.spec.slave_surface, self.model.body(self.spec.slave).index,
                          self.node_X)

    def field_values(self, u: Sequence[fem.Function], v: Sequence[fem.Function] | None
                     ) -> dict[str, np.ndarray]:
        """:meth:`SlaveNodes3D.evaluate` at the slave nodes."""
        return self._slave_nodes().evaluate(self.interface_values(u),
                                            None if v is None else self.interface_values(v))

    def static_measures(self, u: Sequence[fem.Function]) -> StaticMeasures:
        """The static measures (as the 2-D pair's, at the slave nodes and faces)."""
        state = self.state()
        closed = state["gap"] <= 0
        penetration = float(-state["gap"][closed].min(initial=0.0))
        X = np.concatenate([self._sX, self._mX]).reshape(-1, 3)
        penetration = penetration if penetration > 1e-12 * float(np.ptp(X, axis=0).max()) \
            else 0.0
        sizes = facet_size(self._sX[:, :3])
        nodes = self._slave_nodes()
        s = nodes.evaluate(self.interface_values(u))
        E = (self.model.body(self.spec.slave).spec.material.E,
             self.model.body(self.spec.master).spec.material.E)
        on = nodes.facet0 >= 0
        return StaticMeasures(
            penalty=self.spec.penalty, element_size=float(sizes.mean()) if len(sizes) else 0.0,
            young_moduli=E, static_penetration=penetration,
            settlement=settlement(s["u_slave"][on], s["u_master"][on], nodes.normal0[on]),
            penetration_size=float(sizes.min()) if len(sizes) else None)

    def static_check(self) -> str | None:
        """Why the pair cannot start from the meshed configuration (None: it can).

        A slave node meshed inside the master deeper than half the search radius (what
        the search sees, as :meth:`penetration`); one deeper than :data:`OVERLAP` of
        the master face under it is warned about (the static state pushes the bodies
        apart by it). Before them, a slave surface that faces no master face
        (:func:`breakwater.contact.facing.facing`). The same on every rank (collective).
        """
        X = np.ascontiguousarray(self.node_X)
        gap, facet, _ = nodal_gaps(self, X, self._mX)
        on = np.flatnonzero(facet >= 0)
        why = facing(self.model, self.spec, bool(np.any(gap[on] < 0)))
        if why is not None or not len(on):
            return why
        depth = -gap[on]  # the deepest node (any partition's)
        k = first_by_position(X, on[depth >= depth.max() - 1e-9 * self.radius])
        where = ", ".join(f"{c:.4g}" for c in X[k])
        if -gap[k] > 0.5 * self.radius:
            return (f"contact '{self.spec.name}': slave node at ({where}) m starts "
                    f"{-gap[k]:.3g} m inside the master '{self.spec.master}', beyond half "
                    f"the search radius ({self.radius:.3g} m): the meshes overlap; mesh "
                    "the bodies apart or in contact")
        size = facet_size(self._mX[facet[on], :3])
        warned = _OVERLAP_WARNED.setdefault(self.model.mesh, set())
        if np.any(depth > OVERLAP * size) and self.spec.name not in warned:
            warned.add(self.spec.name)  # once a run, not at each stepper's check
            if self.comm.rank == 0:
                log.warning("contact '%s': the meshes overlap: slave node at (%s) m starts %.3g "
                            "m inside the master '%s'; the static state pushes the bodies apart "
                            "by it", self.spec.name, where, -gap[k], self.spec.master)
        return None

    def probe(self, point: Sequence[float], name: str) -> Any:
        """Refused: pair probes of a 3-D general pair are not implemented."""
        raise CaseError(f"pair probe '{name}': pair probes of a 3-D general pair "
                        f"('{self.spec.name}') are not implemented; use a body probe "
                        "([output.probes]) on each side")


class _Energy:
    """A 3-D general pair's ledger terms (rank 0's share is the whole, as the 2-D pair's)."""

    def __init__(self, contact: SurfaceContact3D) -> None:
        self.contact = contact

    def local(self, step: bool) -> np.ndarray:
        """The rank's share (:meth:`breakwater.model.pairs.EnergyTerms.local`; collective)."""
        energy, power = self.contact.energies()
        return np.array([energy, power, 0.0]) if self.contact.comm.rank == 0 else np.zeros(3)
