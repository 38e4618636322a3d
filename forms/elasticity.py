"""Linear isotropic elastodynamics (the paper's §4, eqs. 16-22).

The semi-discrete balance is ``M a + C v + K u = f``: :func:`inertia` gives the ``M``
term, :func:`elastic_residual` the ``K`` term, :func:`rayleigh_damping` the
``C = αM + βK`` term, :func:`body_force` and :func:`surface_traction` the load ``f``.
Each is its own form, so the constant bulk operators can be assembled and factored
apart from the interface terms.
"""

from __future__ import annotations

import ufl


def lame_from_shear(G: float, ν: float) -> tuple[float, float]:
    """Lamé parameters (λ, μ) from the shear modulus and Poisson's ratio.

    Args:
        G: Shear modulus (Pa).
        ν: Poisson's ratio (-), in (-1, 1/2).

    Returns:
        ``(λ, μ)`` in Pa, with ``μ = G`` and ``λ = 2Gν / (1 - 2ν)``.

    """
    return 2.0 * G * ν / (1.0 - 2.0 * ν), G


def lame_from_young(E: float, ν: float) -> tuple[float, float]:
    """Lamé parameters (λ, μ) from Young's modulus and Poisson's ratio.

    Args:
        E: Young's modulus (Pa).
        ν: Poisson's ratio (-), in (-1, 1/2).

    Returns:
        ``(λ, μ)`` in Pa.

    """
    return lame_from_shear(E / (2.0 * (1.0 + ν)), ν)


def strain(u: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """Small-strain tensor ε(u) = sym(∇u)."""
    return ufl.sym(ufl.grad(u))


def stress(u: ufl.core.expr.Expr, λ: ufl.core.expr.Expr | float,
           μ: ufl.core.expr.Expr | float) -> ufl.core.expr.Expr:
    """Isotropic Hooke's law σ = 2με + λ tr(ε) I (plane strain in 2D, eq. 17)."""
    ε = strain(u)
    return 2.0 * μ * ε + λ * ufl.tr(ε) * ufl.Identity(len(u))


def stress_3d(u: ufl.core.expr.Expr, λ: ufl.core.expr.Expr | float,
              μ: ufl.core.expr.Expr | float) -> ufl.core.expr.Expr:
    """The 3 × 3 stress tensor; in 2D plane strain, with σ_zz = λ tr ε (ε_zz = 0)."""
    σ = stress(u, λ, μ)
    if len(u) == 3:
        return σ
    return ufl.as_matrix([[σ[0, 0], σ[0, 1], 0.0],
                          [σ[1, 0], σ[1, 1], 0.0],
                          [0.0, 0.0, λ * ufl.tr(strain(u))]])


def von_mises(σ3: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """Von Mises stress sqrt(3/2 s:s) of a 3 × 3 stress tensor, s its deviator."""
    s = ufl.dev(σ3)
    return ufl.sqrt(1.5 * ufl.inner(s, s))


def elastic_residual(u, w, λ, μ, dx: ufl.Measure) -> ufl.Form:
    """Internal virtual work ∫ σ(u) : ε(w) dx (the ``K u`` term)."""
    return ufl.inner(stress(u, λ, μ), strain(w)) * dx


def inertia(ρ, a, w, dx: ufl.Measure) -> ufl.Form:
    """Inertial virtual work ∫ ρ a · w dx (the ``M a`` term)."""
    return ρ * ufl.dot(a, w) * dx


def rayleigh_damping(α, β, ρ, v, w, λ, μ, dx: ufl.Measure) -> ufl.Form:
    """Rayleigh damping ``C v`` with C = αM + βK: ∫ αρ v·w + β σ(v):ε(w) dx."""
    return α * inertia(ρ, v, w, dx) + β * elastic_residual(v, w, λ, μ, dx)


def body_force(ρ, b, w, dx: ufl.Measure) -> ufl.Form:
    """External virtual work of a body force per unit mass: ∫ ρ b · w dx."""
    return ρ * ufl.dot(b, w) * dx


def surface_traction(t, w, ds: ufl.Measure) -> ufl.Form:
    """External virtual work of a surface traction: ∫ t · w ds."""
    return ufl.dot(t, w) * ds
