"""Energy terms for the energy ledger, as scalar forms.

Stored energies (J per metre in plane strain):
kinetic ½∫ρ v·v, strain ½∫σ(u):ε(u), penalty ½∫ε_n⟨−g_n⟩₊².
Powers (W per metre), integrated in time by the ledger:
Rayleigh dissipation ∫ αρ v·v + β σ(v):ε(v), friction dissipation ∫ −t_T·v_T ≥ 0,
external power ∫ ρ b·v + ∫ t·v.
"""

from __future__ import annotations

import ufl

from .contact import ContactLaw, tangential_part
from .elasticity import strain, stress


def kinetic_energy(ρ, v, dx: ufl.Measure) -> ufl.Form:
    """Kinetic energy ½ ∫ ρ v·v dx."""
    return 0.5 * ρ * ufl.dot(v, v) * dx


def strain_energy(u, λ, μ, dx: ufl.Measure) -> ufl.Form:
    """Strain energy ½ ∫ σ(u):ε(u) dx."""
    return 0.5 * ufl.inner(stress(u, λ, μ), strain(u)) * dx


def penalty_energy(law: ContactLaw, u_s, u_m, n, dS: ufl.Measure) -> ufl.Form:
    """Energy stored in the normal penalty, ½ ∫ ε_n ⟨−g_n⟩₊² dS = ½ ∫ p²/ε_n dS."""
    return law.normal.energy(law.gap(u_s, u_m, n)) * dS


def rayleigh_power(α, β, ρ, v, λ, μ, dx: ufl.Measure) -> ufl.Form:
    """Power dissipated by Rayleigh damping, ∫ αρ v·v + β σ(v):ε(v) dx ≥ 0."""
    return (α * ρ * ufl.dot(v, v) + β * ufl.inner(stress(v, λ, μ), strain(v))) * dx


def friction_power(law: ContactLaw, u_s, u_m, v_s, v_m, n, dS: ufl.Measure) -> ufl.Form:
    """Power dissipated by friction, ∫ −t_T·v_T dS ≥ 0 (∫ μ p |v_T|² / sqrt(|v_T|² + χ²) dS)."""
    return law.friction.power(law.pressure(u_s, u_m, n), tangential_part(v_s - v_m, n)) * dS


def external_power(ρ, b, v, dx: ufl.Measure) -> ufl.Form:
    """Power of a body force per unit mass, ∫ ρ b·v dx.

    Surface loads add :func:`forms.elasticity.surface_traction` evaluated on ``v``.
    """
    return ρ * ufl.dot(b, v) * dx
