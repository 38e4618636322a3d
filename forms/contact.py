"""Penalty normal contact and regularised Coulomb friction (SPEC §1-2, eqs. 7-15, 23).

Quantities are written for a slave body s pressed on a master body m, on a
conforming interface. Callers pass *restricted* expressions (for an interior-facet
integral, e.g. ``u_s("+")`` and ``u_m("-")``) and the master's outward unit normal
``n`` (pointing from the master into the slave).

- normal gap            g_n = (u_s − u_m)·n + g_0                     (eq. 7)
- penalty pressure      p = ε_n ⟨−g_n⟩₊, active at g_n ≤ 0            (eq. 12)
- relative tangential velocity   v_T = (I − n⊗n)(v_s − v_m)           (eqs. 9-10)
- regularised Coulomb   t_T = −μ p v_T / sqrt(|v_T|² + χ²)           (eqs. 14-15)
- traction on the slave t_s = p n + t_T; the master receives −t_s     (eq. 23)
"""

from __future__ import annotations

import ufl


def normal_gap(u_s, u_m, n, g0=0.0):
    """Normal gap g_n = (u_s − u_m)·n + g_0; negative means penetration.

    Args:
        u_s: Slave displacement on the interface.
        u_m: Master displacement on the interface.
        n: Master outward unit normal (from master into slave).
        g0: Initial gap (m), zero on a conforming interface.

    """
    return ufl.dot(u_s - u_m, n) + g0


def penalty_pressure(g_n, ε_n):
    """Penalty contact pressure p = ε_n ⟨−g_n⟩₊ (Pa).

    The contact is taken as active at ``g_n = 0`` (``≤``), so that the Jacobian of a
    closed but unloaded interface is not singular.
    """
    return ε_n * ufl.conditional(ufl.le(g_n, 0.0), -g_n, 0.0)


def tangential_part(v, n):
    """Tangential projection (I − n⊗n) v."""
    return v - ufl.dot(v, n) * n


def slip_direction(v_T, χ):
    """Regularised sign of the slip velocity φ(v_T) = v_T / sqrt(|v_T|² + χ²) (eq. 15).

    Args:
        v_T: Relative tangential velocity (m/s).
        χ: Regularisation velocity (m/s); χ → 0 recovers Coulomb's law.

    """
    return v_T / ufl.sqrt(ufl.dot(v_T, v_T) + χ**2)


def friction_traction(p, v_T, μ, χ):
    """Regularised Coulomb traction on the slave, t_T = −μ p φ(v_T) (Pa, eq. 14)."""
    return -μ * p * slip_direction(v_T, χ)


def contact_traction(u_s, u_m, v_s, v_m, n, ε_n, μ, χ, g0=0.0):
    """Total interface traction on the slave, t_s = p n + t_T (Pa).

    Args:
        u_s: Slave displacement on the interface.
        u_m: Master displacement on the interface.
        v_s: Slave velocity on the interface.
        v_m: Master velocity on the interface.
        n: Master outward unit normal.
        ε_n: Normal penalty (N/m³).
        μ: Friction coefficient; pass 0 for frictionless contact.
        χ: Regularisation velocity (m/s).
        g0: Initial gap (m).

    """
    p = penalty_pressure(normal_gap(u_s, u_m, n, g0), ε_n)
    v_T = tangential_part(v_s - v_m, n)
    return p * n + friction_traction(p, v_T, μ, χ)


def contact_residual(t_s, w_s, w_m, dS: ufl.Measure) -> ufl.Form:
    """Contact contribution to the residual, −∫ t_s · (w_s − w_m) dS (eq. 23).

    The slave receives ``t_s`` and the master ``−t_s`` (action and reaction).
    """
    return -ufl.dot(t_s, w_s - w_m) * dS
