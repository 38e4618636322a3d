"""What a run measures after each step: one row of ``history.csv``.

:class:`Monitor` is the one object whose :meth:`Monitor.row` the time loop calls per
accepted step (and once for the static state); everything the history records is
measured there. :func:`interface_state` gives the nodal interface data of every
pair (for the static and peak snapshots).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import ufl
from dolfinx import fem

from breakwater import forms  # type: ignore[attr-defined]
from breakwater.config.runspec import OutputSpec
from breakwater.contact.conforming import InterfaceNodes
from breakwater.contact.general import SurfaceContact
from breakwater.energy.ledger import FIELDS
from breakwater.model.model import ContactModel
from breakwater.outputs import quality
from breakwater.outputs.probes import Probes
from breakwater.outputs.surfaceoutputs import surface_state
from breakwater.stepping.gn22 import GN22

__all__ = ["Monitor", "interface_state", "pair_names"]


class Monitor:
    """Everything measured on the state after each step: one history row.

    Columns: ``t``, ``dt``, ``newton_iterations``; the probes' columns
    (:class:`~breakwater.outputs.probes.Probes`: ``<probe>_ux``, ``<probe>_uy``,
    ``<pair probe>_<key>``); per contact pair ``k``: ``contact_length_k`` (length
    where g_n ≤ 0), ``normal_force_k``, ``tangential_force_k`` (resultants on the
    slave), ``penetration_k`` (largest nodal ⟨−g_n⟩₊, m); per general pair ``name``
    (:mod:`~breakwater.contact.general`): ``<name>_force_x``, ``<name>_force_y`` (the
    resultant on the slave), ``<name>_contact_length`` (reference length of the
    integration points where g_n ≤ 0), ``<name>_penetration`` (largest ⟨−g_n⟩₊ there,
    m); the ledger's :data:`~breakwater.energy.ledger.FIELDS`.

    Args:
        model: The contact model.
        stepper: The GN22 stepper (its ``u``, ``v`` are measured).
        output: The probes.
        nodes: Interface nodes of every pair.

    Attributes:
        surfaces: The general pairs (the stepper's providers).
        probes: The probes.

    """

    def __init__(self, model: ContactModel, stepper: GN22, output: OutputSpec,
                 nodes: Sequence[InterfaceNodes]) -> None:
        self.model, self.stepper = model, stepper
        self.nodes = nodes
        self.surfaces = [p for p in getattr(stepper.solver, "providers", ())
                         if isinstance(p, SurfaceContact)]
        self.probes = Probes(model, output, nodes, self.surfaces)
        u, v = stepper.u, stepper.v
        self._contact = []
        for p in model.pairs:
            us, um = u[p.slave]("+"), u[p.master]("-")
            g_n = p.law.gap(us, um, p.n)
            pressure = p.law.normal.pressure(g_n)
            traction = model.traction(p, u, v)
            if model.gdim == 2:
                t = ufl.as_vector((p.n[1], -p.n[0]))
                tangential = ufl.dot(traction, t)
            else:
                tangential = ufl.sqrt(ufl.dot(forms.tangential_part(traction, p.n),
                                              forms.tangential_part(traction, p.n)))
            self._contact.append(tuple(model.form(f * p.dS) for f in (
                p.law.normal.closed(g_n), pressure, tangential)))
        self.columns = ["t", "dt", "newton_iterations", *self.probes.columns]
        for k in range(len(model.pairs)):
            self.columns += [f"contact_length_{k}", f"normal_force_{k}",
                             f"tangential_force_{k}", f"penetration_{k}"]
        for sp in self.surfaces:
            self.columns += [f"{sp.spec.name}_{key}" for key in
                             ("force_x", "force_y", "contact_length", "penetration")]
        self.columns += list(FIELDS)

    def row(self, dt: float, iterations: int, energies: Mapping[str, float]) -> dict[str, float]:
        """The history row of the stepper's current state (collective)."""
        s = self.stepper
        r: dict[str, float] = {"t": float(s.t.value), "dt": dt,
                               "newton_iterations": float(iterations)}
        r.update(self.probes.values(s.u))
        resultants = self.model.assemble_many([c for forms in self._contact for c in forms])
        for k in range(len(self._contact)):
            length, normal, tangential = (float(x) for x in resultants[3 * k: 3 * k + 3])
            r[f"contact_length_{k}"] = length
            r[f"normal_force_{k}"] = normal
            r[f"tangential_force_{k}"] = tangential
        for k, (p, nd) in enumerate(zip(self.model.pairs, self.nodes, strict=True)):
            gap = nd.contact_state(s.u[p.slave].x.array, s.u[p.master].x.array)["gap"]
            r[f"penetration_{k}"] = quality.max_penetration(gap)
        for sp in self.surfaces:
            force = sp.resultant()
            state = sp.state()
            closed = state["gap"] <= 0  # NaN (no projection): open
            name = sp.spec.name
            r[f"{name}_force_x"], r[f"{name}_force_y"] = float(force[0]), float(force[1])
            r[f"{name}_contact_length"] = float(state["weight"][closed].sum())
            r[f"{name}_penetration"] = float(-state["gap"][closed].min(initial=0.0))
        r.update({k: float(energies[k]) for k in FIELDS})
        return r


def interface_state(model: ContactModel, nodes: Sequence[InterfaceNodes],
                    u: Sequence[fem.Function], surfaces: Sequence[SurfaceContact] = ()
                    ) -> dict[str, np.ndarray]:
    """Nodal interface data of every pair (same on all ranks; collective).

    Args:
        model: The contact model.
        nodes: Interface nodes of every conforming pair.
        u: The state (one Function per body).
        surfaces: The general pairs (:attr:`Monitor.surfaces`).

    Returns:
        ``pair<k>_x`` node coordinates (sorted), ``pair<k>_normal``, ``pair<k>_gap``
        (normal gap g_n), ``pair<k>_slip`` (2D: along t = (n_y, −n_x)) and
        ``pair<k>_pressure`` (ε_n ⟨−g_n⟩₊); per general pair the same at the slave
        surface's nodes, ``surface_<name>_x`` ...
        (:func:`~breakwater.outputs.surfaceoutputs.surface_state`).
    """
    data: dict[str, np.ndarray] = {}
    for k, (p, nd) in enumerate(zip(model.pairs, nodes, strict=True)):
        state = nd.contact_state(u[p.slave].x.array, u[p.master].x.array)
        data[f"pair{k}_x"] = nd.x
        data[f"pair{k}_normal"] = nd.normal
        data[f"pair{k}_gap"] = state["gap"]
        if model.gdim == 2:
            data[f"pair{k}_slip"] = np.sum(state["slip"] * nd.tangents[:, 0], axis=1)
        data[f"pair{k}_pressure"] = state["pressure"]
    data.update(surface_state(surfaces, u))
    return data


def pair_names(model: ContactModel) -> list[str]:
    """Names of the contact pairs: the interface group, or the index where it repeats."""
    names = [p.spec.interface for p in model.pairs]
    return [n if names.count(n) == 1 else str(k) for k, n in enumerate(names)]
