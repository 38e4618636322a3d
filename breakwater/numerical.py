"""The ledger's numerical-dissipation entry: what one GN22 step loses to the scheme.

Computed from the scheme's discrete energy identity (derivation in
:mod:`forms.gn22_energy`), term by term and not as the balance's remainder:

- bulk: −(β₁ − ½) Δt v̄·MΔa + ½(β₂ − β₁) Δt² Δa·(Mā + Cv̄), one form over the bodies;
- contact: the penalty's trapezoidal error where the active set switches within a step,
  and the friction traction on the mismatch between the slip increment and Δt × the
  slip velocity the law saw, one form over the interfaces.

The ledger's balance, E(t) − E(0) + D_R + D_F + D_num − W, then vanishes to the
equilibrium's residual, and checks that the solved state, the ledger's energies and its
external work are those of one and the same discrete system.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dolfinx import fem

from . import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/

if TYPE_CHECKING:
    from .gn22 import GN22


class NumericalDissipation:
    """The numerical dissipation of the step a :class:`~breakwater.gn22.GN22` just took.

    Reads the stepper's state after :meth:`~breakwater.gn22.GN22.update`: ``u``, ``v``,
    ``a`` at the end of the step, its ``Δa`` (``da``) and ``Δt`` (``dt``), and the
    state at the start of the step, ``u0``, ``v0`` (the ledger's copies).

    Args:
        stepper: The stepper.
        u0: Displacements at the start of the step (one Function per body).
        v0: Velocities at the start of the step.

    """

    def __init__(self, stepper: GN22, u0: list[fem.Function], v0: list[fem.Function]) -> None:
        self.stepper = s = stepper
        m = s.model
        β1, β2 = s.params.beta1, s.params.beta2
        # With β₁ = β₂ = ½ both coefficients vanish: no form to assemble.
        self._bulk = None if β1 == β2 == 0.5 else m.form(sum(
            forms.gn22_bulk_dissipation(b.ρ, m.α, m.β, b.λ, b.μ, s.v[i], s.a[i], s.da[i],
                                        s.dt, β1, β2, b.dx)
            for i, b in enumerate(m.bodies)))
        self._contact = m.form(sum(
            forms.gn22_contact_dissipation(
                p.law, u0[p.slave]("+"), u0[p.master]("-"), v0[p.slave]("+"),
                v0[p.master]("-"), s.u[p.slave]("+"), s.u[p.master]("-"),
                s.v[p.slave]("+"), s.v[p.master]("-"), p.n, s.dt, p.dS)
            for p in m.pairs)) if m.pairs else None

    @property
    def compiled(self) -> list[fem.Form | None]:
        """The bulk and the contact forms (None: nothing to assemble), for a batch."""
        return [self._bulk, self._contact]

    def step(self) -> tuple[float, float]:
        """The bulk and the contact share of the last step's numerical dissipation (J/m)."""
        bulk, contact = self.stepper.model.assemble_many(self.compiled)
        return float(bulk), float(contact)
