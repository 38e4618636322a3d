"""A conforming pair as the outputs measure it: its history columns at a state.

:class:`ConformingPair` is the conforming kind of :class:`breakwater.model.pairs.Pair`
(the general kind is :class:`breakwater.contact.general.SurfaceContact`): the contact
length ``∫ [g_n ≤ 0] dS``, the normal resultant ``∫ ε_n ⟨−g_n⟩₊ dS`` and the tangential
resultant ``∫ t·t_s dS`` on the slave (the traction of the paper's eq. 23; 2D: along
t = (n_y, −n_x), 3D: its magnitude) over the pair's interface, and the largest nodal
penetration ``max ⟨−g_n⟩₊``; its terms of the energy ledger (:class:`ConformingEnergy`:
UFL forms over the interface; where the interface quadrature is nodal, 2D affine P2,
both are evaluated as compiled sums over the interface nodes,
:class:`~breakwater.contact.pairkernels.NodalPairSums`, the forms staying the reference),
its nodal state for the snapshots and the ParaView fields (at the interface nodes, where
the law acts: :meth:`InterfaceNodes.contact_state`), its static measures of contact
quality and its probes (:class:`ConformingProbe`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import ufl
from dolfinx import fem

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common.errors import MeshError
from breakwater.contact.conforming import InterfaceNodes, interface_nodes, mean_facet_length
from breakwater.contact.pairkernels import NodalGather, NodalPairSums, nodal_sums_apply
from breakwater.model.model import ContactModel, PairData
from breakwater.model.pairs import (
    FieldNodes,
    StaticMeasures,
    max_penetration,
    pair_names,
    penetration_facet,
    probe_keys,
    settlement,
)
from breakwater.model.pointprobe import PointProbe

__all__ = ["QUANTITIES", "ConformingEnergy", "ConformingPair", "ConformingProbe",
           "conforming_pairs"]

QUANTITIES = ("contact_length", "normal_force", "tangential_force", "penetration")
"""The history quantities of a conforming pair (columns ``<name>_<quantity>``)."""


class ConformingPair:
    """A conforming pair measured at a state (u, v): its history columns.

    Args:
        model: The contact model.
        pair: The pair's data (one of ``model.pairs``).
        nodes: Its interface nodes.
        name: Its name (:func:`breakwater.model.pairs.pair_names`).
        u: The displacement, one Function per body.
        v: The velocity, one Function per body.
        dt: The stepper's time step.
    """

    def __init__(self, model: ContactModel, pair: PairData, nodes: InterfaceNodes, name: str,
                 u: Sequence[fem.Function], v: Sequence[fem.Function],
                 dt: fem.Constant) -> None:
        self.model, self.pair, self.nodes = model, pair, nodes
        self.name = name
        self.u, self.v, self.dt = u, v, dt
        self._forms: list[fem.Form] | None = None  # compiled on the first use
        self._sums: NodalPairSums | None = None  # built on the first use
        self._nodal: bool | None = None  # whether the quadrature is nodal
        self._gather: NodalGather | None = None

    def nodal_sums(self) -> NodalPairSums | None:
        """The pair's forms as nodal sums (None where the quadrature is not nodal)."""
        if self._nodal is None:
            self._nodal = nodal_sums_apply(self.model)
            if self._nodal:
                self._sums = NodalPairSums(self.model, self.nodes)
        return self._sums

    @property
    def columns(self) -> list[str]:
        """``<name>_contact_length``, ``_normal_force``, ``_tangential_force``, ``_penetration``."""
        return [f"{self.name}_{q}" for q in QUANTITIES]

    def resultant_forms(self) -> list[fem.Form]:
        """The compiled forms of the contact length and the normal and tangential resultants."""
        if self._forms is None:
            m, p, u = self.model, self.pair, self.u
            g_n = p.law.gap(u[p.slave]("+"), u[p.master]("-"), p.n)
            traction = m.traction(p, u, self.v)
            if m.gdim == 2:
                tangential = ufl.dot(traction, ufl.as_vector((p.n[1], -p.n[0])))
            else:
                t = forms.tangential_part(traction, p.n)
                tangential = ufl.sqrt(ufl.dot(t, t))
            self._forms = [m.form(f * p.dS) for f in (
                p.law.normal.closed(g_n), p.law.normal.pressure(g_n), tangential)]
        return self._forms

    def measure(self) -> dict[str, float]:
        """The pair's history values at (u, v) (collective).

        The resultants are the :meth:`resultant_forms`, summed over the nodes
        (:class:`~breakwater.contact.pairkernels.NodalPairSums`) where the quadrature is
        nodal; the penetration is at the nodes, with their averaged normals.
        """
        sums = self.nodal_sums()
        if sums is None:
            return self.measure_forms()
        if self._gather is None:
            self._gather = sums.gatherer([self.u, self.v])
        return dict(zip(self.columns, sums.resultants(self._gather()).tolist(), strict=True))

    def measure_forms(self) -> dict[str, float]:
        """:meth:`measure` from the assembled forms (the reference; collective)."""
        length, normal, tangential = (float(x) for x in
                                      self.model.assemble_many(self.resultant_forms()))
        p = self.pair
        gap = self.nodes.contact_state(self.u[p.slave].x.array,
                                       self.u[p.master].x.array)["gap"]
        return dict(zip(self.columns, (length, normal, tangential, max_penetration(gap)),
                        strict=True))

    def energy_terms(self, u0: Sequence[fem.Function], v0: Sequence[fem.Function]
                     ) -> ConformingEnergy:
        """The pair's ledger terms (:class:`ConformingEnergy`)."""
        return ConformingEnergy(self, u0, v0)

    def _sides(self, f: Sequence[fem.Function]) -> tuple[np.ndarray, np.ndarray]:
        """The slave's and the master's arrays of one Function per body."""
        return f[self.pair.slave].x.array, f[self.pair.master].x.array

    def snapshot(self, u: Sequence[fem.Function]) -> dict[str, np.ndarray]:
        """The interface nodes' state (:meth:`breakwater.model.pairs.Pair.snapshot`)."""
        nd = self.nodes
        state = nd.contact_state(*self._sides(u))
        out = {"x": nd.x, "normal": nd.normal, "gap": state["gap"]}
        if self.model.gdim == 2:
            out["slip"] = np.sum(state["slip"] * nd.tangents[:, 0], axis=1)
        out["pressure"] = state["pressure"]
        return out

    def largest_slip(self, u: Sequence[fem.Function]) -> float:
        """The largest |slip| (I − n⊗n)(u_s − u_m) over the interface nodes (collective)."""
        slip = self.nodes.contact_state(*self._sides(u))["slip"]
        return float(np.linalg.norm(slip, axis=1).max(initial=0.0))

    def field_nodes(self) -> FieldNodes:
        """The interface group, the slave's degree and the interface nodes."""
        return FieldNodes(self.pair.spec.interface, self.pair.slave, self.nodes.x)

    def field_values(self, u: Sequence[fem.Function], v: Sequence[fem.Function] | None
                     ) -> dict[str, np.ndarray]:
        """:meth:`InterfaceNodes.contact_state` at the interface nodes."""
        return self.nodes.contact_state(*self._sides(u),
                                        *(self._sides(v) if v is not None else (None, None)))

    def static_measures(self, u: Sequence[fem.Function]) -> StaticMeasures:
        """h: the interface's length over its facets; δ and s at its nodes.

        The penetration's facet size: the smallest facet at the nodes where δ is largest,
        to within 1 % (:func:`breakwater.model.pairs.penetration_facet`; the interface's
        smallest when nothing penetrates).
        """
        m, p, nd = self.model, self.pair, self.nodes
        us, um = nd.gather(*self._sides(u))
        gap = nd.contact_state(*self._sides(u))["gap"]
        δ = max_penetration(gap)
        at = penetration_facet(gap, nd.facet_size)
        return StaticMeasures(
            penalty=p.spec.penalty, element_size=mean_facet_length(m, p),
            young_moduli=(m.bodies[p.slave].spec.material.E,
                          m.bodies[p.master].spec.material.E),
            static_penetration=δ, settlement=settlement(us, um, nd.normal),
            penetration_size=float(at) if np.isfinite(at) else None)

    def static_check(self) -> str | None:
        """None: the two sides share their interface nodes, so they cannot start overlapped.

        (The model checks, when it builds the pair, that its interface is one of
        facets shared by two cells: :class:`breakwater.model.model.ContactModel`.)
        """
        return None

    def probe(self, point: Sequence[float], name: str) -> ConformingProbe:
        """A :class:`ConformingProbe` at ``point``."""
        return ConformingProbe(self, point, name)


def _tangent(n: np.ndarray) -> np.ndarray:
    """2D unit tangent t = (n_y, −n_x): +x on a horizontal interface with n = +y."""
    return np.array([n[1], -n[0]])


class ConformingProbe:
    """Slip and opening (slave minus master) at a point of a conforming interface.

    The normal is the master's outward normal at the nearest interface node;
    slip is along ``t = (n_y, −n_x)`` in 2D (the tangential magnitude in 3D).
    The sides' displacements are point probes of the two bodies (their traces).

    Args:
        pair: The pair.
        point: The probe's point (reference coordinates).
        name: The probe's name.

    Raises:
        MeshError: The point is not in one of the two bodies.
    """

    def __init__(self, pair: ConformingPair, point: Sequence[float], name: str) -> None:
        m, p, nd = pair.model, pair.pair, pair.nodes
        sides = []
        for side, k in (("slave", p.slave), ("master", p.master)):
            body = m.bodies[k].spec.name
            try:
                sides.append(PointProbe(m, body, point, f"{name}_{side}"))
            except MeshError:
                raise MeshError(f"pair probe '{name}': point {tuple(point)} is not on the "
                                f"interface '{p.spec.interface}' (not in body '{body}')"
                                ) from None
        self.slave, self.master = sides
        x = np.zeros(m.gdim)
        x[:] = np.asarray(point, dtype=float)[: m.gdim]
        self.normal = nd.normal[np.argmin(np.linalg.norm(nd.x - x, axis=1))]
        self.gdim = m.gdim
        self._tangent = _tangent(self.normal) if m.gdim == 2 else None

    def local(self, u: Sequence[fem.Function]) -> np.ndarray:
        """The two sides' displacements at the point, this rank's share (no reduction)."""
        return np.concatenate([self.slave.local_value(u), self.master.local_value(u)])

    def values(self, local: np.ndarray) -> dict[str, float]:
        """Slip, opening and both sides' displacements (:func:`probe_keys`)."""
        us, um = local[: self.slave.size], local[self.slave.size:]
        jump = us - um
        opening = float(jump @ self.normal)
        if self._tangent is not None:
            slip = float(jump @ self._tangent)
        else:
            slip = float(np.linalg.norm(jump - opening * self.normal))
        sides = [float(us[0]), float(us[1]), float(um[0]), float(um[1])]
        if self.gdim == 3:
            sides += [float(us[2]), float(um[2])]
        return dict(zip(probe_keys(self.gdim), (slip, opening, *sides), strict=True))


class ConformingEnergy:
    """A conforming pair's ledger terms: UFL forms over its interface, or their nodal sums.

    The penalty energy ``∫ ½ ε_n ⟨−g_n⟩₊² dS`` and the friction power
    ``∫ μp |v_T|²/sqrt(|v_T|² + χ²) dS`` at (u, v), and the interface share of the
    step's numerical dissipation (:func:`forms.gn22_contact_dissipation`: the
    penalty's trapezoidal error where the active set switches within the step, the
    friction traction on the slip increment's mismatch), from (u0, v0) to (u, v).
    Where the quadrature is nodal the forms are evaluated as sums over the nodes
    (:class:`~breakwater.contact.pairkernels.NodalPairSums`); they stay the reference
    (:meth:`local_forms`).

    Args:
        pair: The pair.
        u0: Displacements at the start of the step (the ledger's copies).
        v0: Velocities at the start of the step.
    """

    def __init__(self, pair: ConformingPair, u0: Sequence[fem.Function],
                 v0: Sequence[fem.Function]) -> None:
        m, p, u, v = pair.model, pair.pair, pair.u, pair.v
        s, t = p.slave, p.master
        self.model, self.u, self.v, self.u0, self.v0 = m, u, v, u0, v0
        self.dt = pair.dt
        self.sums = sums = pair.nodal_sums()
        self._gather = [sums.gatherer([u, v]), sums.gatherer([u, v, u0, v0])] \
            if sums is not None else []
        self._state = [
            m.form(forms.penalty_energy(p.law, u[s]("+"), u[t]("-"), p.n, p.dS)),
            m.form(forms.friction_power(p.law, u[s]("+"), u[t]("-"), v[s]("+"), v[t]("-"),
                                        p.n, p.dS))]
        self._step = m.form(forms.gn22_contact_dissipation(
            p.law, u0[s]("+"), u0[t]("-"), v0[s]("+"), v0[t]("-"), u[s]("+"), u[t]("-"),
            v[s]("+"), v[t]("-"), p.n, pair.dt, p.dS))

    def local(self, step: bool) -> np.ndarray:
        """The rank's share (:meth:`breakwater.model.pairs.EnergyTerms.local`).

        From the nodal sums (the same on every rank: rank 0 gives them, the others 0),
        else from the forms.
        """
        sums = self.sums
        if sums is None:
            return self.local_forms(step)
        gathered = self._gather[step]()
        values = sums.energies(gathered[:2], gathered[2:] if step else None,
                               float(self.dt.value))
        return values if self.model.comm.rank == 0 else np.zeros(3)

    def local_forms(self, step: bool) -> np.ndarray:
        """:meth:`local` from the assembled forms (the reference)."""
        if step:
            return self.model.assemble_local([*self._state, self._step])
        return np.append(self.model.assemble_local(self._state), 0.0)


def conforming_pairs(model: ContactModel, nodes: Sequence[InterfaceNodes],
                     u: Sequence[fem.Function], v: Sequence[fem.Function], dt: fem.Constant
                     ) -> list[ConformingPair]:
    """The model's conforming pairs measured at (u, v), named by :func:`pair_names`.

    Args:
        model: The contact model.
        nodes: The pairs' interface nodes; empty: built here (collective).
        u: The displacement, one Function per body.
        v: The velocity, one Function per body.
        dt: The stepper's time step.
    """
    nodes = nodes or interface_nodes(model)
    names = pair_names([p.spec for p in model.pairs])
    return [ConformingPair(model, p, nd, name, u, v, dt)
            for p, nd, name in zip(model.pairs, nodes, names, strict=True)]
