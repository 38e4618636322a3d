"""What a run measures after each step: one row of ``history.csv``.

:class:`Monitor` is the one object whose :meth:`Monitor.row` the time loop calls per
accepted step (and once for the static state); everything the history records is
measured there. :func:`interface_state` gives the nodal state of every pair (for the
static and peak snapshots).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from dolfinx import fem

from breakwater.config.runspec import OutputSpec
from breakwater.energy.ledger import FIELDS
from breakwater.model.model import ContactModel
from breakwater.model.pairs import Pair
from breakwater.model.pairs import pair_names as names_of
from breakwater.outputs.probes import Probes
from breakwater.outputs.rotation import Rotations
from breakwater.stepping.gn22 import GN22

__all__ = ["Monitor", "interface_state", "pair_names"]


class Monitor:
    """Everything measured on the state after each step: one history row.

    Columns: ``t``, ``dt``, ``newton_iterations``; the probes' columns
    (:class:`~breakwater.outputs.probes.Probes`: ``<probe>_ux``, ``<probe>_uy``,
    ``<pair probe>_<key>``); per contact pair, named by the pair (the case's
    ``[contact.<name>]``; :class:`~breakwater.model.pairs.Pair`), ``<name>_<quantity>``:

    - both kinds: ``<name>_contact_length`` (m, or m² in 3D: the length where
      g_n ≤ 0; of a general pair, the reference length of its integration points
      there), ``<name>_penetration`` (the largest ⟨−g_n⟩₊, m: at the nodes of a
      conforming pair, at the integration points of a general one);
    - a conforming pair: ``<name>_normal_force`` (∫ ε_n ⟨−g_n⟩₊ dS, the normal
      resultant on the slave, N/m in plane strain), ``<name>_tangential_force``
      (∫ t·t_s dS on the slave: 2D along t = (n_y, −n_x), 3D its magnitude);
    - a general pair: ``<name>_force_x``, ``<name>_force_y`` (the resultant ∫ t_s on
      the slave);

    per body ``<body>_rotation`` (its mean rotation, rad:
    :class:`~breakwater.outputs.rotation.Rotations`); then the ledger's
    :data:`~breakwater.energy.ledger.FIELDS`.

    Args:
        model: The contact model.
        stepper: The GN22 stepper (its ``u``, ``v`` are measured, and its pairs,
            :attr:`~breakwater.stepping.gn22.GN22.contacts`).
        output: The probes.

    Attributes:
        probes: The probes.
        rotations: The bodies' rotations.

    """

    def __init__(self, model: ContactModel, stepper: GN22, output: OutputSpec) -> None:
        self.model, self.stepper = model, stepper
        self.probes = Probes(model, output, stepper.contacts)
        self.columns = ["t", "dt", "newton_iterations", *self.probes.columns]
        for pair in stepper.contacts:
            self.columns += pair.columns
        self.rotations = Rotations(model)
        self.columns += [*self.rotations.columns, *FIELDS]

    def row(self, dt: float, iterations: int, energies: Mapping[str, float]) -> dict[str, float]:
        """The history row of the stepper's current state (collective)."""
        s = self.stepper
        r: dict[str, float] = {"t": float(s.t.value), "dt": dt,
                               "newton_iterations": float(iterations)}
        r.update(self.probes.values(s.u))
        for pair in s.contacts:
            r.update(pair.measure())
        r.update(self.rotations.values(s.u))
        r.update({k: float(energies[k]) for k in FIELDS})
        return r


def interface_state(pairs: Sequence[Pair], u: Sequence[fem.Function]
                    ) -> dict[str, np.ndarray]:
    """The nodal state of every pair at ``u``, for the snapshots (every rank; collective).

    Args:
        pairs: The pairs (the stepper's :attr:`~breakwater.stepping.gn22.GN22.contacts`).
        u: The state (one Function per body).

    Returns:
        ``contacts``: the pairs' names, in order; per pair ``contact_<name>_<field>``
        for the fields of :meth:`~breakwater.model.pairs.Pair.snapshot`: ``x`` (node
        coordinates, sorted), ``normal``, ``gap`` (normal gap g_n), ``slip`` (2D: along
        the tangent) and ``pressure`` (ε_n ⟨−g_n⟩₊ at a conforming pair's interface
        nodes; at a general pair's slave nodes the projection of the pressure its
        residual integrates, :func:`breakwater.contact.slavepoints.nodal_pressure`,
        where positive, else 0; and ``pressure_dual``, unclipped).
    """
    data: dict[str, np.ndarray] = {"contacts": np.array([p.name for p in pairs], dtype=str)}
    for p in pairs:
        data.update({f"contact_{p.name}_{k}": a for k, a in p.snapshot(u).items()})
    return data


def pair_names(model: ContactModel) -> list[str]:
    """Names of the conforming pairs (:func:`breakwater.model.pairs.pair_names`)."""
    return names_of([p.spec for p in model.pairs])
