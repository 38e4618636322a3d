"""A conforming pair as the outputs measure it: its history columns at a state.

:class:`ConformingPair` is the conforming kind of :class:`breakwater.model.pairs.Pair`
(the general kind is :class:`breakwater.contact.general.SurfaceContact`): the contact
length ``∫ [g_n ≤ 0] dS``, the normal resultant ``∫ ε_n ⟨−g_n⟩₊ dS`` and the tangential
resultant ``∫ t·t_s dS`` on the slave (the traction of the paper's eq. 23; 2D: along
t = (n_y, −n_x), 3D: its magnitude) over the pair's interface, and the largest nodal
penetration ``max ⟨−g_n⟩₊``; and its terms of the energy ledger
(:class:`ConformingEnergy`: UFL forms over the interface).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import ufl
from dolfinx import fem

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.contact.conforming import InterfaceNodes, interface_nodes
from breakwater.model.model import ContactModel, PairData
from breakwater.model.pairs import max_penetration, pair_names

__all__ = ["QUANTITIES", "ConformingEnergy", "ConformingPair", "conforming_pairs"]

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
        self._forms: list[fem.Form] | None = None  # compiled on the first measure

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
        """The pair's history values at (u, v) (collective)."""
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


class ConformingEnergy:
    """A conforming pair's ledger terms: UFL forms over its interface.

    The penalty energy ``∫ ½ ε_n ⟨−g_n⟩₊² dS`` and the friction power
    ``∫ μp |v_T|²/sqrt(|v_T|² + χ²) dS`` at (u, v), and the interface share of the
    step's numerical dissipation (:func:`forms.gn22_contact_dissipation`: the
    penalty's trapezoidal error where the active set switches within the step, the
    friction traction on the slip increment's mismatch), from (u0, v0) to (u, v).

    Args:
        pair: The pair.
        u0: Displacements at the start of the step (the ledger's copies).
        v0: Velocities at the start of the step.
    """

    def __init__(self, pair: ConformingPair, u0: Sequence[fem.Function],
                 v0: Sequence[fem.Function]) -> None:
        m, p, u, v = pair.model, pair.pair, pair.u, pair.v
        s, t = p.slave, p.master
        self.model = m
        self._state = [
            m.form(forms.penalty_energy(p.law, u[s]("+"), u[t]("-"), p.n, p.dS)),
            m.form(forms.friction_power(p.law, u[s]("+"), u[t]("-"), v[s]("+"), v[t]("-"),
                                        p.n, p.dS))]
        self._step = m.form(forms.gn22_contact_dissipation(
            p.law, u0[s]("+"), u0[t]("-"), v0[s]("+"), v0[t]("-"), u[s]("+"), u[t]("-"),
            v[s]("+"), v[t]("-"), p.n, pair.dt, p.dS))

    def local(self, step: bool) -> np.ndarray:
        """The rank's share (:meth:`breakwater.model.pairs.EnergyTerms.local`)."""
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
