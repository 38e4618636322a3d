"""GN22's numerical dissipation over one step, from the scheme's discrete energy identity.

One GN22 step (see :func:`breakwater.stepping.gn22.gn22_kinematics`) satisfies, with
v̄ = ½(v₀ + v₁), ā = ½(a₀ + a₁), Δa = a₁ − a₀,

    Δu = Δt v̄ + c Δt² Δa,     c = ½(β₂ − β₁)            (the displacement jump)
    Δv = Δt ā + g Δt Δa,      g = β₁ − ½                 (the velocity jump)

and equilibrium M a + C v + K u + f_c(u, v) = f at both ends of the step. The mean of
the two equilibria, dotted with Δu, is exact:

    Δu·M ā + Δu·C v̄ + Δu·K ū + Δu·f̄_c = Δu·f̄,

with Δu·K ū = ΔE_strain (K is linear and symmetric) and Δu·f̄ the ledger's external
work. With the two jumps,

    Δu·M ā = ΔE_kinetic − g Δt v̄·M Δa + c Δt² Δa·M ā,
    Δu·C v̄ = Δt v̄·C v̄ (the ledger's Rayleigh dissipation) + c Δt² Δa·C v̄,

so the energy the ledger's physical entries do not account for over the step is

    D_bulk = −g Δt v̄·M Δa + c Δt² Δa·(M ā + C v̄)          (:func:`gn22_bulk_dissipation`)
    D_contact = Δu·f̄_c − ΔE_penalty − ΔD_friction          (:func:`gn22_contact_dissipation`)

and ΔE + ΔD_R + ΔD_F + D_bulk + D_contact = ΔW holds to the equilibrium's residual.
D_bulk vanishes identically with β₁ = β₂ = ½ (g = c = 0), D_contact where no contact
point switches and the slip velocity is constant over the step.
For a linear undamped unforced problem (M a + K u = 0), substituting the equations
gives Newmark's identity (Hughes, *The Finite Element Method*, 1987, §9.3.3; Krenk,
CMAME 195, 2006): D_bulk = Δ(½ c Δt² a·M a) + g (Δu·K Δu + c Δt² Δa·M Δa), a stored
"algorithmic" term plus a dissipation ≥ 0 for β₂ ≥ β₁ ≥ ½.

What is physical and what is the scheme's on the interface: the penalty energy
½∫p²/ε_n is stored energy and the friction dissipation is the trapezoidal rule of the
law's power ∫ −t_T·v_T (both in the ledger). The scheme's share is what the discrete
contact force does on the step beyond them, pointwise at the interface's quadrature
points:

- normal: −½(p₀ + p₁) Δg_n − Δ(½ p²/ε_n), zero where the contact stays closed (p is then
  linear in g_n) or open; nonzero only where the active set switches within the step
  (positive when a point closes, negative when it opens);
- tangential: −½ t_T₀·(Δj − Δt v_T₀) − ½ t_T₁·(Δj − Δt v_T₁), the friction traction on
  the difference between the scheme's slip increment Δj = Δ(u_s − u_m) and the
  increment Δt v_T of the slip velocity the law was evaluated with.
"""

from __future__ import annotations

import ufl

from .contact import ContactLaw, tangential_part
from .elasticity import strain, stress


def gn22_bulk_dissipation(ρ, α, β, λ, μ, v1, a1, Δa, Δt, beta1: float, beta2: float,
                          dx: ufl.Measure) -> ufl.Form:
    """Bulk numerical dissipation of one GN22 step, −g Δt v̄·MΔa + cΔt² Δa·(Mā + Cv̄).

    With g = β₁ − ½, c = ½(β₂ − β₁), ā = a₁ − ½Δa, C = αM + βK (Rayleigh damping) and
    v̄ = ½(v₀ + v₁) written with the end of the step, v̄ = v₁ − ½Δt a₁ + ½(1 − β₁)Δt Δa
    (GN22's v₀ = v₁ − Δt a₀ − β₁ΔtΔa): three coefficients rather than four, a cheaper
    form over the whole mesh. See the module docstring for the identity it comes from.

    Args:
        ρ: Density.
        α: Rayleigh mass coefficient (1/s).
        β: Rayleigh stiffness coefficient (s).
        λ: First Lamé parameter.
        μ: Shear modulus.
        v1: Velocity at the end of the step.
        a1: Acceleration at the end of the step.
        Δa: Acceleration increment of the step.
        Δt: Step size.
        beta1: β₁.
        beta2: β₂.
        dx: Cell measure of the body.

    """
    g, c = beta1 - 0.5, 0.5 * (beta2 - beta1)
    v̄ = v1 - 0.5 * Δt * a1 + 0.5 * (1.0 - beta1) * Δt * Δa
    ā = a1 - 0.5 * Δa
    # Factored as Δa·(…) to keep the kernel short (it runs over the whole mesh each step).
    inertia = ρ * ufl.dot(Δa, (c * Δt**2 * α - g * Δt) * v̄ + c * Δt**2 * ā)
    damping = c * Δt**2 * β * ufl.inner(stress(v̄, λ, μ), strain(Δa))
    return (inertia + damping) * dx


def gn22_contact_dissipation(law: ContactLaw, u0_s, u0_m, v0_s, v0_m, u1_s, u1_m, v1_s,
                             v1_m, n, Δt, dS: ufl.Measure) -> ufl.Form:
    """Interface share of one GN22 step's numerical dissipation, Δu·f̄_c − ΔE_pen − ΔD_F.

    Written pointwise (see the module docstring): the penalty's trapezoidal error,
    −½(p₀ + p₁)Δg_n − Δ(½p²/ε_n), plus the friction traction on the mismatch between the
    slip increment and Δt × the slip velocity, −½ Σ_k t_Tk·(Δj − Δt v_Tk).

    Args:
        law: The pair's contact law.
        u0_s: Slave displacement at the start of the step (restricted).
        u0_m: Master displacement at the start of the step.
        v0_s: Slave velocity at the start of the step.
        v0_m: Master velocity at the start of the step.
        u1_s: Slave displacement at the end of the step.
        u1_m: Master displacement at the end of the step.
        v1_s: Slave velocity at the end of the step.
        v1_m: Master velocity at the end of the step.
        n: Master outward unit normal.
        Δt: Step size.
        dS: The pair's interface measure (the residual's quadrature).

    """
    g0, g1 = law.gap(u0_s, u0_m, n), law.gap(u1_s, u1_m, n)
    p0, p1 = law.normal.pressure(g0), law.normal.pressure(g1)
    normal = -0.5 * (p0 + p1) * (g1 - g0) - (law.normal.energy(g1) - law.normal.energy(g0))
    Δj = (u1_s - u1_m) - (u0_s - u0_m)
    tangential = 0.0
    for p, v_s, v_m in ((p0, v0_s, v0_m), (p1, v1_s, v1_m)):
        v_T = tangential_part(v_s - v_m, n)
        tangential += -0.5 * ufl.dot(law.friction.traction(p, v_T), Δj - Δt * v_T)
    return (normal + tangential) * dS
