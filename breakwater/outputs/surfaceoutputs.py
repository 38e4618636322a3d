"""Outputs of general contact pairs: pair probes, ParaView fields, snapshots, quality.

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
- ``pressure`` ε_n⟨−g_n⟩₊, ``slip_velocity`` v_T = (I − n̄⊗n̄)(v_s − v̄_m) relative
  to the master material point under the projection, and ``friction_traction``
  −μ p v_T/sqrt(|v_T|² + χ²) on the slave: the pair's law (:class:`forms.ContactLaw`)
  evaluated at the point.
- ``slip``: the tangential displacement of the slave point relative to the master
  material point X̄₀ under it in the reference configuration (its closest point on
  the master surface of the mesh), ``(I − n₀⊗n₀)(u_s − u_m(X̄₀))`` with n₀ the master's
  outward normal at X̄₀; the probes' scalar slip is its component along
  ``t₀ = (n₀_y, −n₀_x)``. For matching meshes X̄₀ is the slave point itself, so this
  is the conforming pairs' slip (:class:`~breakwater.outputs.probes.PairProbe`); on a flat
  master it is the sliding distance at any slip; on a curved master, under finite
  sliding, it is the chord of the path (the paper's eqs. 8-9 integrate the path instead).
  X̄₀ is fixed by the mesh, so a resumed run needs nothing saved.

:class:`SurfaceProbe` is a pair probe of a general pair (the columns of a conforming
one), :class:`SurfaceFields` its ParaView fields (``contact_<pair>.bp``, P_k fields
on the slave surface, nodal values), :func:`surface_state` its arrays of the
``.npz`` snapshots and :func:`quality_inputs` the measures of its contact-quality
report (:mod:`breakwater.outputs.quality`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import dolfinx
import numpy as np
from dolfinx import fem

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common.errors import MeshError
from breakwater.config.runspec import PairProbeSpec
from breakwater.contact.general import SurfaceContact
from breakwater.contact.projection import FacetGrid, closest_point, curve, project, shape
from breakwater.model.mesh import group_tag
from breakwater.model.model import ContactModel
from breakwater.outputs import quality
from breakwater.outputs.checkpoint import match_nodes

__all__ = ["ROUND_OFF", "SlavePoints", "SurfaceFields", "SurfaceProbe",
           "quality_inputs", "surface_state"]

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

    def __init__(self, contact: SurfaceContact, pos: np.ndarray, N: np.ndarray,
                 X: np.ndarray) -> None:
        self.contact, self.pos, self.N = contact, pos, N
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
    def nodes(cls, contact: SurfaceContact) -> SlavePoints:
        """The slave surface's nodes (:attr:`SurfaceContact.node_X` order)."""
        m = len(contact.node_X)
        return cls(contact, contact.node_pos[:, None, :], np.ones((m, 1)),
                   contact.node_X[:, None, :])

    @classmethod
    def at(cls, contact: SurfaceContact, point: np.ndarray, name: str) -> SlavePoints:
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
                (:meth:`~breakwater.contact.general.SurfaceContact.interface_values`).
            v: Velocities there (None: at rest).

        Returns:
            ``x`` (current position), ``u_slave``, ``u_master`` (at X̄₀), ``normal``
            (the master's normal at the projection, the pair's), ``gap``, ``pressure``,
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
        # The current projection, refined as SurfaceContact.state() does; where there
        # is none, the master material point X̄₀.
        facet, xi = project(xs, xm, FacetGrid(xm, c.radius))
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
        pressure = np.where(on, law.normal.pressure(gap), 0.0)
        v_T = forms.tangential_part(vs - v_bar, n)
        return {"x": xs, "u_slave": us, "u_master": um0, "normal": n, "gap": gap,
                "pressure": pressure, "slip": forms.tangential_part(rel, n0),
                "slip_t": np.sum(rel * t0, axis=1), "slip_velocity": v_T,
                "friction_traction": law.friction.traction(pressure, v_T)}


class SurfaceProbe:
    """A pair probe of a general pair: the columns of :class:`~breakwater.outputs.probes.PairProbe`.

    ``slip`` (along t₀), ``opening`` (the normal gap g_n, positive open),
    ``slave_ux``, ``slave_uy`` (the slave point) and ``master_ux``, ``master_uy``
    (the master material point under it in the reference configuration).

    Args:
        contact: The general pair (a provider of the stepper's fast solver).
        spec: The probe (its point on the slave surface).
    """

    def __init__(self, contact: SurfaceContact, spec: PairProbeSpec) -> None:
        self.name = spec.name
        self.contact = contact
        self.points = SlavePoints.at(contact, np.asarray(spec.point, float), spec.name)

    def value(self, u: Sequence[fem.Function]) -> dict[str, float]:
        """Slip, opening and both sides' displacements for the state ``u`` (collective)."""
        s = self.points.evaluate(self.contact.interface_values(u))
        us, um = s["u_slave"][0], s["u_master"][0]
        return {"slip": float(s["slip_t"][0]), "opening": float(s["gap"][0]),
                "slave_ux": float(us[0]), "slave_uy": float(us[1]),
                "master_ux": float(um[0]), "master_uy": float(um[1])}


SCALARS = ("pressure", "gap")
"""The scalar contact fields written for ParaView (conforming and general pairs)."""
VECTORS = ("slip", "slip_velocity", "friction_traction")
"""The vector contact fields written for ParaView."""


def group_fields(model: ContactModel, group: str, degree: int, nodes: np.ndarray
                 ) -> tuple[dict[str, fem.Function], np.ndarray]:
    """The contact fields as P_degree Functions on the submesh of a facet group.

    Also returns the index of each of ``nodes`` among their (scalar) dofs. The fields
    are :data:`SCALARS` and :data:`VECTORS`.

    Args:
        model: The contact model.
        group: The facet group (gmsh physical name).
        degree: The Lagrange degree of the fields.
        nodes: The points where the contact state is evaluated, shape ``(n, gdim)``.
    """
    msh, gdim = model.mesh, model.gdim
    fdim = msh.topology.dim - 1
    assert model.mesh_data.facet_tags is not None
    facets = model.mesh_data.facet_tags.find(group_tag(model.mesh_data, group, fdim))
    sub = dolfinx.mesh.create_submesh(msh, fdim, facets)[0]
    S = fem.functionspace(sub, ("Lagrange", degree))
    V = fem.functionspace(sub, ("Lagrange", degree, (gdim,)))
    values = {k: fem.Function(S, name=k) for k in SCALARS}
    values.update({k: fem.Function(V, name=k) for k in VECTORS})
    # The blocked space has the scalar space's dof layout: one index per node.
    x = S.tabulate_dof_coordinates()[:, :gdim]
    extent = max(float(np.ptp(nodes, axis=0).max()), 1e-300) if len(nodes) else 1.0
    return values, match_nodes(nodes, x, 1e-8 * extent)


class SurfaceFields:
    """The contact state of a general pair as P_k fields on its slave surface (ParaView).

    The slave surface's facets form a line mesh (a submesh of the mesh's facets); its
    P_k nodes are the slave surface's nodes, where the fields hold the pointwise state
    of :class:`SlavePoints` (nodal values, interpolated between them; the residual
    integrates the law at its own points, so the integral of ``pressure`` equals the
    normal resultant to the interpolation error). Fields and file name as the
    conforming pairs' (:class:`~breakwater.outputs.writers.InterfaceFields`).

    Args:
        model: The contact model.
        contact: The general pair.
    """

    def __init__(self, model: ContactModel, contact: SurfaceContact) -> None:
        spec = contact.spec
        self.filename = f"contact_{spec.name}.bp"
        self.contact = contact
        self.points = SlavePoints.nodes(contact)
        degree = model.body(spec.slave).V.ufl_element().embedded_superdegree
        self.values, self._index = group_fields(model, spec.slave_surface, degree,
                                                self.points.X)
        self.functions = list(self.values.values())

    def update(self, u: Sequence[fem.Function], v: Sequence[fem.Function] | None = None
               ) -> None:
        """Evaluate the fields of the state ``(u, v)`` (one Function per body; collective)."""
        state = self.points.evaluate(self.contact.interface_values(u),
                                     None if v is None else self.contact.interface_values(v))
        for k, f in self.values.items():
            shape_ = (len(self._index), f.function_space.dofmap.index_map_bs)
            f.x.array.reshape(shape_)[:] = state[k][self._index].reshape(shape_)


def surface_state(contacts: Sequence[SurfaceContact], u: Sequence[fem.Function]
                  ) -> dict[str, np.ndarray]:
    """The slave nodes' contact state of every general pair (every rank; collective).

    Returns:
        ``surface_<name>_x`` (reference coordinates of the slave surface's nodes,
        sorted), ``_normal`` (the master's current normal), ``_gap``, ``_slip`` (2-D:
        along t₀) and ``_pressure``: the arrays of the ``.npz`` snapshots.
    """
    data: dict[str, np.ndarray] = {}
    for c in contacts:
        points = SlavePoints.nodes(c)
        state = points.evaluate(c.interface_values(u))
        order = np.lexsort(points.X.T[::-1])
        key = f"surface_{c.spec.name}"
        data[f"{key}_x"] = points.X[order]
        data[f"{key}_normal"] = state["normal"][order]
        data[f"{key}_gap"] = state["gap"][order]
        data[f"{key}_slip"] = state["slip_t"][order]
        data[f"{key}_pressure"] = state["pressure"][order]
    return data


def quality_inputs(model: ContactModel, contacts: Sequence[SurfaceContact],
                   u: Sequence[fem.Function]) -> list[quality.PairInputs]:
    """The static measures of each general pair's contact quality (collective).

    Args:
        model: The contact model.
        contacts: The general pairs (the stepper's providers).
        u: The static state: the stepper's displacements, which the pairs' own
            integration points (:meth:`SurfaceContact.state`) are measured on too.

    As the conforming pairs' (:func:`breakwater.outputs.summary.quality_inputs`), on the slave
    surface: h is the mean length of its facets (reference), the static penetration
    the largest ⟨−g_n⟩₊ of the residual's integration points
    (:meth:`SurfaceContact.state`, the history's ``<name>_penetration``), and the
    settlement the mean over its nodes of ½(u_s + u_m(X̄₀))·n₀. A static penetration
    below :data:`ROUND_OFF` of the surfaces' extent counts as none: the gap is a
    difference of coordinates of that size, whose round-off (≈ 1e-16 of it) a pair
    touching in the undeformed state shows as a penetration (measured 6e-19 m), and
    against a zero settlement it would read as a too soft penalty.
    """
    inputs = []
    for c in contacts:
        spec = c.spec
        state: dict[str, Any] = c.state()
        closed = state["gap"] <= 0  # NaN (no projection): open
        X = np.concatenate([c.slave.X, c.master.X]).reshape(-1, model.gdim)
        noise = ROUND_OFF * float(np.ptp(X, axis=0).max())
        penetration = float(-state["gap"][closed].min(initial=0.0))
        facets = max(len(c.slave.X), 1)
        points = SlavePoints.nodes(c)
        nodal = points.evaluate(c.interface_values(u))
        inputs.append(quality.PairInputs(
            name=spec.name, penalty=spec.penalty,
            element_size=float(state["weight"].sum()) / facets,
            young_moduli=(model.body(spec.slave).spec.material.E,
                          model.body(spec.master).spec.material.E),
            static_penetration=penetration if penetration > noise else 0.0,
            settlement=quality.settlement(nodal["u_slave"], nodal["u_master"],
                                          points.normal0),
            penetration_column=f"{spec.name}_penetration"))
    return inputs
