"""A general pair's outputs at fixed material points of its slave surface.

A general pair (:mod:`breakwater.contact.general`) has no node pairs; its outputs are
measured at material points of the slave surface (its nodes, or a probe's point) by
:class:`SlavePoints`, from the pair's own surfaces and the values of the state at its
interface unknowns (gathered on every rank, so every rank computes the same numbers):

- ``gap``: the normal gap g_n = (x_s − x̄_m)·n̄ at the closest point x̄_m of the master
  surface in the current configuration (the paper's eq. 7; positive open), as the residual's
  integration points measure it. A point with no projection (out of contact: past
  the end of the master surface, beyond a convex corner, or farther than the search
  radius) measures it to the master material point under it in the reference
  configuration, along the master's current normal there; its pressure is zero.
  With ``rotations = "small"`` the normal is the reference surface's, as in the
  residual.
- ``law_pressure`` ε_n⟨−g_n⟩₊, ``slip_velocity`` v_T = (I − n̄⊗n̄)(v_s − v̄_m)
  relative to the master material point under the projection: the pair's law
  (:class:`forms.ContactLaw`) evaluated at the point.
- ``pressure``: at the slave nodes, the nodal values of the pressure the residual
  integrates (:func:`nodal_pressure`: p_k = ∫ p N_k / ∫ N_k, the dual-basis
  (biorthogonal) projection of the mortar methods, ``pressure_dual``) where they are
  positive, else 0: the law ε_n⟨−g_n⟩₊ is never a tension, and a negative p_k (a P2
  vertex just past the contact's edge, whose N_k < 0 on the far half of its facet
  where the pressure is) is a weight of the projection, not a traction; at another
  point (a probe's), the law's. ``friction_traction`` −μ p v_T/sqrt(|v_T|² + χ²) on
  the slave, with that p.
- ``slip``: the tangential displacement of the slave point relative to the master
  material point X̄₀ under it in the reference configuration (its closest point on
  the master surface of the mesh), ``(I − n₀⊗n₀)(u_s − u_m(X̄₀))`` with n₀ the master's
  outward normal at X̄₀; the probes' scalar slip is its component along
  ``t₀ = (n₀_y, −n₀_x)``. For matching meshes X̄₀ is the slave point itself, so this
  is the conforming pairs' slip (:class:`~breakwater.contact.pairstate.ConformingProbe`);
  on a flat master it is the sliding distance at any slip; on a curved master, under
  finite sliding, it is the chord of the path (the paper's eqs. 8-9 integrate the path
  instead). X̄₀ is fixed by the mesh, so a resumed run needs nothing saved.

:class:`SurfaceProbe` is a pair probe of a general pair, :func:`snapshot` the arrays of
its ``.npz`` snapshots and :func:`static_measures` the measures of its contact-quality
report; :class:`breakwater.contact.general.SurfaceContact` gives them as the general
kind of :class:`breakwater.model.pairs.Pair`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from dolfinx import fem

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common.errors import MeshError
from breakwater.contact import searchkernels
from breakwater.contact.projection import (
    INSIDE,
    FacetGrid,
    closest_point,
    curve,
    project,
    shape,
)
from breakwater.model.pairs import PROBE_KEYS, StaticMeasures, facet_size, settlement

if TYPE_CHECKING:
    from breakwater.contact.surfacesearch import SurfaceSearch

__all__ = ["ROUND_OFF", "SlavePoints", "SurfaceProbe", "nodal_pressure", "snapshot",
           "static_measures", "tributary"]

ROUND_OFF = 1e-12
"""A static penetration below this fraction of the surfaces' extent is round-off."""


def _normal(tangent: np.ndarray) -> np.ndarray:
    """Unit outward normal (t_y, −t_x)/|t| of master facets oriented as the pair's."""
    n = np.stack([tangent[:, 1], -tangent[:, 0]], axis=1)
    return n / np.linalg.norm(n, axis=1)[:, None]


def _nearest(points: np.ndarray, nodes: np.ndarray, radius: float
             ) -> tuple[np.ndarray, np.ndarray]:
    """The closest point of each point on a surface of facets, always one.

    The projection (:func:`~breakwater.contact.projection.project`) where there is one, else
    the nearest point of any facet, its ends included (every facet tried).
    """
    facet, xi = project(points, nodes, FacetGrid(nodes, radius))
    for k in np.flatnonzero(facet < 0):
        p = np.repeat(points[k][None], len(nodes), axis=0)
        x = np.clip(np.real(closest_point(p, nodes)), -1, 1)
        d = np.linalg.norm(curve(nodes, x)[0] - p, axis=1)
        facet[k] = int(np.argmin(d))
        xi[k] = x[facet[k]]
    return facet, xi


def tributary(X: np.ndarray, node_of: np.ndarray, n_nodes: int) -> np.ndarray:
    """D_k = ∫ N_k ds over the slave surface (reference configuration).

    The diagonal of the dual (biorthogonal) basis's mortar matrix, ∫ ψ_j N_k = δ_jk D_k
    (Wohlmuth 2000; Popp et al. 2010 for quadratic elements): on a straight P2 facet of
    length h, h/6 at each vertex and 2h/3 at the mid-edge node (Simpson's weights),
    positive on the curved facets of a second-order mesh too. Gauss rule of 5 points
    per facet (exact for the straight facets' quadratics; the curved facets'
    Jacobian to round-off at the curvatures of a mesh).

    Args:
        X: The slave facets' reference nodes, ``(F, nn, gdim)``.
        node_of: The slave node of each facet node, ``(F, nn)``.
        n_nodes: The number of slave nodes.
    """
    g, w = np.polynomial.legendre.leggauss(5)
    N, dN, _ = shape(g, X.shape[1])
    jac = np.linalg.norm(np.einsum("qa,fad->fqd", dN, X), axis=2) * w
    return np.bincount(node_of.ravel(), weights=(jac @ N).ravel(), minlength=n_nodes)


def nodal_pressure(forces: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The slave nodes' pressure p_k = λ_k / D_k from their normal forces λ_k = ∫ p N_k.

    ``p_h = Σ_k p_k N_k`` is the dual-basis projection of the pressure the residual
    integrates (at its own integration points, ``λ``): exact in the mean,
    ``∫ p_h = Σ_k p_k D_k = Σ_k λ_k = ∫ p`` (the normal resultant's magnitude on a
    flat master), and at each node a weighted mean of p over the node's facets, weight
    N_k: second-order accurate where p is smooth. Where the integration is
    ``nodes`` (the law at the nodes, Gauss–Lobatto weights), p_k is the law at the
    node. The consistent L² projection (M p = λ, M the slave surface's mass matrix)
    was measured against it on the Hertz problem (docs/general-contact.md): less
    accurate inside the contact (0.67 % of p₀ against 0.29 %) and keeping most of a
    first-order geometry's node-to-node oscillation (10 % against 4.6 %). A P2
    vertex function is negative over part of its facets, so a vertex just past the
    contact's edge may read a negative value (measured −1.0 % of p₀, −5 % with a
    penalty overlap of 3e-5 of the contact half-width; −1.5 kPa against 53 kPa at the
    caisson's edge of ``examples/goda_nonmatching.toml`` with ε_n = 1.01e11 N/m³):
    :meth:`SlavePoints.evaluate`'s ``pressure`` is it where positive, else 0 (its
    ``pressure_dual`` is this, unclipped).

    Args:
        forces: λ_k, ``(n_nodes,)``.
        weights: D_k (:func:`tributary`).
    """
    return forces / weights


class SlavePoints:
    """Contact kinematics and the law at fixed material points of the slave surface.

    Each point is a combination ``Σ_k N_k x_k`` of slave surface nodes (its facet's
    shape functions at the point, or a single node).

    Args:
        contact: The general pair.
        pos: Interface positions of the points' nodes, shape ``(m, nn, gdim)``.
        N: The nodes' weights, shape ``(m, nn)``.
        X: Reference coordinates of the nodes, shape ``(m, nn, gdim)``.

    Attributes:
        X: Reference coordinates of the points, ``(m, gdim)``.
        normal0: The master's outward normal at X̄₀ (reference), ``(m, gdim)``.
    """

    def __init__(self, contact: SurfaceSearch, pos: np.ndarray, N: np.ndarray,
                 X: np.ndarray) -> None:
        self.contact, self.pos, self.N = contact, pos, N
        self.weights: np.ndarray | None = None  # D_k where the points are the slave nodes
        self.X = np.einsum("kn,knd->kd", N, X)
        master = contact.master
        if not len(master.X):
            raise MeshError(f"contact '{contact.spec.name}': the master surface has no facet")
        self.facet0, xi0 = _nearest(self.X, master.X, contact.radius)
        self.xi0 = xi0
        self.N0 = shape(xi0, master.X.shape[1])[0]
        self.pos0 = contact.pos_m[self.facet0]
        _, dx, _ = curve(master.X[self.facet0], xi0)
        self.normal0 = _normal(dx)

    @classmethod
    def nodes(cls, contact: SurfaceSearch) -> SlavePoints:
        """The slave surface's nodes (:attr:`SurfaceSearch.node_X` order)."""
        m = len(contact.node_X)
        points = cls(contact, contact.node_pos[:, None, :], np.ones((m, 1)),
                     contact.node_X[:, None, :])
        points.weights = tributary(contact.slave.X, contact.node_of, m)
        return points

    @classmethod
    def at(cls, contact: SurfaceSearch, point: np.ndarray, name: str) -> SlavePoints:
        """The material point of the slave surface at ``point`` (reference coordinates).

        Raises:
            MeshError: The point is not on the slave surface.
        """
        s = contact.slave
        x = np.asarray(point, float)[None, : s.X.shape[2]]
        extent = max(float(np.ptp(s.X.reshape(-1, s.X.shape[2]), axis=0).max()), 1e-300)
        facet, xi = project(x, s.X, FacetGrid(s.X, 1e-6 * extent))
        if facet[0] < 0:
            where = tuple(float(c) for c in np.asarray(point).ravel())
            raise MeshError(f"pair probe '{name}': point {where} is not on the slave "
                            f"surface '{contact.spec.slave_surface}' of contact "
                            f"'{contact.spec.name}'")
        N = shape(xi, s.X.shape[1])[0]
        return cls(contact, contact.pos_s[facet], N, s.X[facet])

    def evaluate(self, u: np.ndarray, v: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """The points' contact state (see the module doc).

        Args:
            u: Displacements at the interface unknowns
                (:meth:`~breakwater.contact.general.SurfaceSearch.interface_values`).
            v: Velocities there (None: at rest).

        Returns:
            ``x`` (current position), ``u_slave``, ``u_master`` (at X̄₀), ``normal``
            (the master's normal at the projection, the pair's), ``gap``,
            ``law_pressure``, ``pressure`` (at the slave nodes :func:`nodal_pressure`
            where positive, else 0; at other points the law's), ``pressure_dual``
            (:func:`nodal_pressure` unclipped, at the slave nodes: Σ_k D_k p_k = ∫ p),
            ``slip`` (vector), ``slip_t`` (along t₀), ``slip_velocity`` and
            ``friction_traction``.
        """
        c = self.contact
        m = c.master
        v = np.zeros_like(u) if v is None else v
        us = np.einsum("kn,knd->kd", self.N, u[self.pos])
        vs = np.einsum("kn,knd->kd", self.N, v[self.pos])
        um0 = np.einsum("kn,knd->kd", self.N0, u[self.pos0])
        xs = self.X + us
        rel = us - um0
        n0 = self.normal0
        t0 = np.stack([n0[:, 1], -n0[:, 0]], axis=1)
        xm = m.X + u[c.pos_m]
        # The current projection, refined as SurfaceSearch.state() does; where there
        # is none, the master material point X̄₀.
        # (Compiled: projection.project's facets, its ξ to 1e-13, tests/test_contactkernels;
        # 1.1 ms a ParaView write on the separately meshed Goda case in Python.)
        facet, xi = searchkernels.project(xs, xm, c.radius, INSIDE)
        on = facet >= 0
        facet = np.where(on, facet, self.facet0)
        xi = np.where(on, xi, self.xi0)
        if on.any():
            xi[on] = np.real(closest_point(xs[on], xm[facet[on]], xi[on], iterations=2,
                                           tol=0.0))
        x_bar, dx, _ = curve(xm[facet], xi)
        if c.small_rotations:  # the reference surface's normal, as the residual's
            dx = curve(m.X[facet], xi)[1]
        n = _normal(dx)
        v_bar = np.einsum("kn,knd->kd", shape(xi, m.X.shape[1])[0], v[c.pos_m[facet]])
        law = c.law
        gap = law.gap(xs, x_bar, n)
        at_points = np.where(on, law.normal.pressure(gap), 0.0)
        dual = at_points if self.weights is None else \
            nodal_pressure(c.normal_forces(u), self.weights)
        pressure = np.maximum(dual, 0.0)  # a negative p_k is a weight, not a tension
        v_T = forms.tangential_part(vs - v_bar, n)
        return {"x": xs, "u_slave": us, "u_master": um0, "normal": n, "gap": gap,
                "law_pressure": at_points, "pressure": pressure, "pressure_dual": dual,
                "slip": forms.tangential_part(rel, n0),
                "slip_t": np.sum(rel * t0, axis=1), "slip_velocity": v_T,
                "friction_traction": law.friction.traction(pressure, v_T)}


class SurfaceProbe:
    """A pair probe of a general pair (:class:`breakwater.model.pairs.PairProbe`).

    ``slip`` (along t₀), ``opening`` (the normal gap g_n, positive open),
    ``slave_ux``, ``slave_uy`` (the slave point) and ``master_ux``, ``master_uy``
    (the master material point under it in the reference configuration). The values
    are the same on every rank: rank 0's share is the whole, the others' zero.

    Args:
        contact: The general pair.
        point: The probe's point on the slave surface (reference coordinates).
        name: The probe's name (for the messages).

    Raises:
        MeshError: The point is not on the slave surface.
    """

    def __init__(self, contact: SurfaceSearch, point: np.ndarray, name: str) -> None:
        self.contact = contact
        self.points = SlavePoints.at(contact, np.asarray(point, float), name)

    def local(self, u: Sequence[fem.Function]) -> np.ndarray:
        """Rank 0: the six values in the order of the keys; the others: zeros (collective)."""
        s = self.points.evaluate(self.contact.interface_values(u))
        us, um = s["u_slave"][0], s["u_master"][0]
        values = np.array([s["slip_t"][0], s["gap"][0], us[0], us[1], um[0], um[1]])
        return values if self.contact.comm.rank == 0 else np.zeros(len(values))

    def values(self, local: np.ndarray) -> dict[str, float]:
        """The probe's values from the sum over the ranks of :meth:`local`."""
        return dict(zip(PROBE_KEYS, (float(x) for x in local), strict=True))


def snapshot(contact: SurfaceSearch, u: Sequence[fem.Function]) -> dict[str, np.ndarray]:
    """The slave nodes' contact state of a general pair (every rank; collective).

    Returns:
        ``x`` (reference coordinates of the slave surface's nodes, sorted), ``normal``
        (the master's current normal), ``gap``, ``slip`` (2-D: along t₀),
        ``pressure`` (:func:`nodal_pressure` where positive, else 0) and
        ``pressure_dual`` (:func:`nodal_pressure`, unclipped).
    """
    points = SlavePoints.nodes(contact)
    state = points.evaluate(contact.interface_values(u))
    order = np.lexsort(points.X.T[::-1])
    return {"x": points.X[order], "normal": state["normal"][order],
            "gap": state["gap"][order], "slip": state["slip_t"][order],
            "pressure": state["pressure"][order],
            "pressure_dual": state["pressure_dual"][order]}


def static_measures(contact: SurfaceSearch, state: dict[str, np.ndarray],
                    u: Sequence[fem.Function], young_moduli: tuple[float, float]
                    ) -> StaticMeasures:
    """The static measures of a general pair's contact quality (collective).

    Args:
        contact: The pair.
        state: Its integration points at the static state
            (:meth:`breakwater.contact.general.SurfaceContact.state`).
        u: The static state: the stepper's displacements, which the pair's own
            integration points are measured on too.
        young_moduli: The Young's moduli of its bodies (slave, master).

    As the conforming pairs', on the slave surface: h is the mean length of its facets
    (reference), the static penetration the largest ⟨−g_n⟩₊ of the residual's
    integration points (the history's ``<name>_penetration``), and the settlement the
    mean over its nodes of ½(u_s + u_m(X̄₀))·n₀. A static penetration below
    :data:`ROUND_OFF` of the surfaces' extent counts as none: the gap is a difference
    of coordinates of that size, whose round-off (≈ 1e-16 of it) a pair touching in
    the undeformed state shows as a penetration (measured 6e-19 m), and against a zero
    settlement it would read as a too soft penalty. The penetration's facet size is the
    smaller of the slave and the master facet at the point where it is largest (the
    slave surface's smallest facet when nothing penetrates).
    """
    c = contact
    closed = state["gap"] <= 0  # NaN (no projection): open
    X = np.concatenate([c.slave.X, c.master.X]).reshape(-1, c.slave.X.shape[2])
    noise = ROUND_OFF * float(np.ptp(X, axis=0).max())
    penetration = float(-state["gap"][closed].min(initial=0.0))
    penetration = penetration if penetration > noise else 0.0
    facets = max(len(c.slave.X), 1)
    sizes = facet_size(c.slave.X[:, :2])
    at = float(sizes.min(initial=np.inf))
    if penetration > 0:
        k = int(np.flatnonzero(closed)[np.argmin(state["gap"][closed])])
        at = float(min(sizes[state["slave_facet"][k]],
                       facet_size(c.master.X[state["facet"][k], :2])))
    points = SlavePoints.nodes(c)
    nodal = points.evaluate(c.interface_values(u))
    return StaticMeasures(
        penalty=c.spec.penalty, element_size=float(state["weight"].sum()) / facets,
        young_moduli=young_moduli,
        static_penetration=penetration,
        settlement=settlement(nodal["u_slave"], nodal["u_master"], points.normal0),
        penetration_size=at if np.isfinite(at) else None)
