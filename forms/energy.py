"""Energy terms for the energy ledger, as scalar forms.

Stored energies (J per metre in plane strain):
kinetic ½∫ρ v·v, strain ½∫σ(u):ε(u), penalty ½∫ε_n⟨−g_n⟩₊².
Powers (W per metre), integrated in time by the ledger:
Rayleigh dissipation ∫ αρ v·v + β σ(v):ε(v), friction dissipation ∫ −t_T·v_T ≥ 0,
external power ∫ ρ b·v + ∫ t·v.
"""

from __future__ import annotations

import ufl

from .contact import friction_traction, normal_gap, penalty_pressure, tangential_part
from .elasticity import strain, stress


def kinetic_energy(ρ, v, dx: ufl.Measure) -> ufl.Form:
    """Kinetic energy ½ ∫ ρ v·v dx."""
    return 0.5 * ρ * ufl.dot(v, v) * dx


def strain_energy(u, λ, μ, dx: ufl.Measure) -> ufl.Form:
    """Strain energy ½ ∫ σ(u):ε(u) dx."""
    return 0.5 * ufl.inner(stress(u, λ, μ), strain(u)) * dx


def penalty_energy(u_s, u_m, n, ε_n, dS: ufl.Measure, g0=0.0) -> ufl.Form:
    """Energy stored in the normal penalty, ½ ∫ ε_n ⟨−g_n⟩₊² dS = ½ ∫ p²/ε_n dS."""
    p = penalty_pressure(normal_gap(u_s, u_m, n, g0), ε_n)
    return 0.5 * p**2 / ε_n * dS


def rayleigh_power(α, β, ρ, v, λ, μ, dx: ufl.Measure) -> ufl.Form:
    """Power dissipated by Rayleigh damping, ∫ αρ v·v + β σ(v):ε(v) dx ≥ 0."""
    return (α * ρ * ufl.dot(v, v) + β * ufl.inner(stress(v, λ, μ), strain(v))) * dx


def friction_power(u_s, u_m, v_s, v_m, n, ε_n, μ, χ, dS: ufl.Measure, g0=0.0) -> ufl.Form:
    """Power dissipated by friction, ∫ μ p |v_T|² / sqrt(|v_T|² + χ²) dS ≥ 0."""
    p = penalty_pressure(normal_gap(u_s, u_m, n, g0), ε_n)
    v_T = tangential_part(v_s - v_m, n)
    return -ufl.dot(friction_traction(p, v_T, μ, χ), v_T) * dS


def external_power(ρ, b, v, dx: ufl.Measure) -> ufl.Form:
    """Power of a body force per unit mass, ∫ ρ b·v dx.

    Surface loads add :func:`forms.elasticity.surface_traction` evaluated on ``v``.
    """
    return ρ * ufl.dot(b, v) * dx
