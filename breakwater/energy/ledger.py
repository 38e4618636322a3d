"""The energy ledger of a GN22 run, written every step.

Stored: kinetic ½∫ρv·v, strain ½∫σ:ε and penalty ½∫p²/ε_n. Cumulative: Rayleigh
dissipation, friction dissipation and external work. For each step,

- external work  ΔW = ∫ ρb·Δu + ∫ ½(t₀ + t₁)·Δu  (exact for piecewise-linear loading),
- Rayleigh       ΔD_R = Δt ∫ αρ v̄·v̄ + β σ(v̄):ε(v̄), v̄ = ½(v₀ + v₁),
- friction       ΔD_F = ½Δt (P_F(t₀) + P_F(t₁)), P_F = ∫ μp |v_T|²/sqrt(|v_T|² + χ²),

- numerical     ΔD_num, the scheme's share, from GN22's discrete energy identity
  (:mod:`breakwater.energy.dissipation`, derived in :mod:`forms.gn22_energy`); its interface
  part (penalty switching, slip increment against Δt v_T) is also kept on its own,
  ``numerical_dissipation_contact``,

and the balance error is E(t) − E(0) + D_R + D_F + D_num − W: it vanishes to the
equilibrium's residual for any β₁, β₂ (it is not defined to vanish; each entry has its
own formula). D_num is zero with β₁ = β₂ = ½ on a problem without contact switching or
slip-velocity changes.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import dolfinx
import numpy as np
from dolfinx import fem

from breakwater.energy.bulkenergy import bulk_terms
from breakwater.stepping.gn22 import GN22

FIELDS = ("kinetic", "strain", "penalty", "rayleigh_dissipation", "friction_dissipation",
          "external_work", "balance_error", "numerical_dissipation",
          "numerical_dissipation_contact")


@dataclass
class Energies:
    """One row of the ledger (J, or J/m in plane strain)."""

    kinetic: float = 0.0
    strain: float = 0.0
    penalty: float = 0.0
    rayleigh_dissipation: float = 0.0
    friction_dissipation: float = 0.0
    external_work: float = 0.0
    balance_error: float = 0.0
    numerical_dissipation: float = 0.0
    numerical_dissipation_contact: float = 0.0

    @property
    def stored(self) -> float:
        """Kinetic + strain + penalty energy."""
        return self.kinetic + self.strain + self.penalty

    def as_dict(self) -> dict[str, float]:
        """The fields by name (see :data:`FIELDS`)."""
        return {name: getattr(self, name) for name in FIELDS}


class EnergyLedger:
    """Energy bookkeeping for a :class:`~breakwater.stepping.gn22.GN22` stepper.

    Call :meth:`record` once after ``initialise`` and once after every step (right
    after ``update``: the numerical entry reads the step's ``Δa`` and ``Δt``).

    The terms over the whole mesh (kinetic, strain, Rayleigh, external work, the bulk
    numerical dissipation) come from :mod:`breakwater.energy.bulkenergy`: on the fast solver
    from its cached M, K and load vectors, on the reference solver from UFL forms; the
    interface terms from the stepper's pairs (:attr:`~breakwater.stepping.gn22.GN22.contacts`,
    :meth:`breakwater.model.pairs.Pair.energy_terms`).

    Args:
        stepper: The stepper.
        source: Where the whole-mesh terms come from: ``auto``, ``forms`` or
            ``matrices`` (:data:`~breakwater.energy.bulkenergy.SOURCES`).
    """

    def __init__(self, stepper: GN22, source: str = "auto") -> None:
        self.stepper = s = stepper
        m = s.model
        self.u0, self.v0 = m.functions("u_prev"), m.functions("v_prev")
        self._amp0 = [fem.Constant(m.mesh, dolfinx.default_scalar_type(0.0)) for _ in m.loads]
        # The whole-mesh terms: the fast solver's cached M, K, or UFL forms.
        self.bulk = bulk_terms(s, self.u0, self.v0, self._amp0, source)
        # The pairs' terms (breakwater.model.pairs.EnergyTerms): forms over a
        # conforming pair's interface, a general pair's own sums.
        self.pairs = [pair.energy_terms(self.u0, self.v0) for pair in s.contacts]
        self._power0 = 0.0  # the pairs' friction power at the start of the step
        # The end state copied into (u0, v0) after each record: views of the arrays
        # (a Function's storage does not move).
        self._copies = [(a.x.array, b.x.array) for dst, src in ((self.u0, s.u), (self.v0, s.v))
                        for a, b in zip(dst, src, strict=True)]
        self.reference: float | None = None
        self.row = Energies()
        self._t0 = 0.0

    def state(self) -> dict[str, Any]:
        """The running sums and previous-step data, plain numbers (for checkpoints).

        With the previous state ``u0``, ``v0`` (Functions, saved with the fields) this
        is everything :meth:`record` needs to continue.
        """
        return {"reference": self.reference, "row": self.row.as_dict(), "t0": self._t0,
                "amp0": [float(a.value) for a in self._amp0],
                "friction_power": self._power0}

    def restore(self, state: dict[str, Any]) -> None:
        """Continue from a :meth:`state` (``u0``, ``v0`` are set by the caller).

        The model's loads must be set at the state's time first (``set_time``): a
        field that changes at given times is then at the stage the next step starts in.
        """
        self.reference = state["reference"]
        self.row = Energies(**state["row"])
        self._t0 = state["t0"]
        self._power0 = state["friction_power"]
        for a0, value in zip(self._amp0, state["amp0"], strict=True):
            a0.value = value
        self.bulk.sync()  # staged loads: the stage the model holds (set at the state's t)

    def record(self) -> Energies:
        """Update the ledger with the stepper's current state and return the row."""
        s, m = self.stepper, self.stepper.model
        t = float(s.t.value)
        first = self.reference is None
        # Every term at once (one reduction); the step's terms from the second row on.
        values = m.reduce(np.concatenate([self.bulk.local(not first),
                                          *(p.local(not first) for p in self.pairs)]))
        kin, strain, rayleigh, work, bulk = (float(x) for x in values[:5])
        pen, power, contact = (float(sum(column.tolist()))  # the pairs' in order
                               for column in values[5:].reshape(-1, 3).T)
        r = self.row
        if self.reference is None:
            self.reference = kin + strain + pen
        else:
            Δt = t - self._t0
            r.rayleigh_dissipation += Δt * rayleigh
            r.friction_dissipation += 0.5 * Δt * (power + self._power0)
            r.external_work += work
            r.numerical_dissipation += bulk + contact
            r.numerical_dissipation_contact += contact
        r.kinetic, r.strain, r.penalty = kin, strain, pen
        r.balance_error = (r.stored - self.reference + r.rayleigh_dissipation
                           + r.friction_dissipation + r.numerical_dissipation
                           - r.external_work)
        for a, b in self._copies:
            a[:] = b
        # The start of the next step: the loads a₀ took at the start of the run (a load
        # left out of the initial state is applied over the first step), else now.
        start = s.start_amplitudes if first and t == s.start_time else \
            [float(ld.amplitude.value) for ld in m.loads]
        for a0, value in zip(self._amp0, start, strict=True):
            a0.value = value
        self._t0 = t
        self._power0 = power
        return replace(r)

    def destroy(self) -> None:
        """Free the PETSc objects of the bulk terms now (collective)."""
        self.bulk.destroy()
