"""The ledger's numerical-dissipation entry: what one GN22 step loses to the scheme.

Computed from the scheme's discrete energy identity (derivation in
:mod:`forms.gn22_energy`), term by term and not as the balance's remainder:

- bulk: −(β₁ − ½) Δt v̄·MΔa + ½(β₂ − β₁) Δt² Δa·(Mā + Cv̄): one form over the bodies
  (:func:`bulk_form`, the reference solver) or four dot products with the products
  M v̄, M Δa and K v̄ of the fast solver's cached M, K (:func:`bulk_coefficients`);
- contact: the penalty's trapezoidal error where the active set switches within a step,
  and the friction traction on the mismatch between the slip increment and Δt × the
  slip velocity the law saw, one form over each conforming pair's interface
  (:class:`breakwater.contact.pairstate.ConformingEnergy`, the pair's ledger terms).

The ledger's balance, E(t) − E(0) + D_R + D_F + D_num − W, then vanishes to the
equilibrium's residual, and checks that the solved state, the ledger's energies and its
external work are those of one and the same discrete system.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dolfinx import fem

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/

if TYPE_CHECKING:
    from breakwater.stepping.gn22 import GN22

__all__ = ["bulk_coefficients", "bulk_form"]


def bulk_form(stepper: GN22) -> fem.Form | None:
    """The bulk share of the last step's numerical dissipation, one form over the bodies.

    Reads the stepper's state after :meth:`~breakwater.stepping.gn22.GN22.update`: ``v``, ``a``
    at the end of the step, its ``Δa`` (``da``) and ``Δt`` (``dt``). None with
    β₁ = β₂ = ½, where both coefficients vanish.
    """
    s, m = stepper, stepper.model
    β1, β2 = s.params.beta1, s.params.beta2
    if β1 == β2 == 0.5:
        return None
    return m.form(sum(forms.gn22_bulk_dissipation(b.ρ, m.α, m.β, b.λ, b.μ, s.v[i], s.a[i],
                                                  s.da[i], s.dt, β1, β2, b.dx)
                      for i, b in enumerate(m.bodies)))


def bulk_coefficients(dt: float, beta1: float, beta2: float, alpha: float,
                      beta: float) -> tuple[float, float, float, float]:
    """The bulk share as four dot products: its coefficients ``(k₁, k₂, k₃, k₄)``.

    With g = β₁ − ½, c = ½(β₂ − β₁), C = αM + βK, ā = a₁ − ½Δa and the symmetry of M
    and K (x·My = y·Mx)::

        D_bulk = −g Δt v̄·MΔa + c Δt² Δa·(M ā + C v̄)
               = (cαΔt² − gΔt) Δa·Mv̄ + cΔt² Δa·M(a₁ − ½Δa) + cβΔt² Δa·Kv̄
               = k₁ Δa·(Mv̄) + k₂ a₁·(MΔa) + k₃ Δa·(MΔa) + k₄ Δa·(Kv̄),

        k₁ = cαΔt² − gΔt,   k₂ = cΔt²,   k₃ = −½cΔt²,   k₄ = cβΔt²,

    the same quadratic form as :func:`forms.gn22_bulk_dissipation` (whose kernel is the
    element-wise sum of these products), from the products M v̄, M Δa, K v̄ that the
    Rayleigh power α v̄·Mv̄ + β v̄·Kv̄ shares. All four vanish with β₁ = β₂ = ½.

    Args:
        dt: The step's Δt.
        beta1: β₁.
        beta2: β₂.
        alpha: Rayleigh mass coefficient α (1/s).
        beta: Rayleigh stiffness coefficient β (s).

    """
    g, c = beta1 - 0.5, 0.5 * (beta2 - beta1)
    return c * alpha * dt**2 - g * dt, c * dt**2, -0.5 * c * dt**2, c * beta * dt**2

