"""A friction law's regularisation velocity χ far outside the run's velocities (warned).

The regularised Coulomb law (SPEC, eqs. 14-15) is ``t_T = −μ p φ(v)``,
``φ(v) = v/sqrt(v² + χ²)``: Coulomb friction μp for slip speeds v ≫ χ, a viscous dashpot
``μ p v/χ`` for v ≪ χ. Both ends of χ have a scale in the run
(:func:`regularisation_warning`):

- **χ too large.** The run's speed scale is ``V = |g| T + max |v₀|`` (T the end time,
  v₀ the bodies' initial velocities): the speed a body falling freely for the whole run
  would reach. A body driven by forces of the order of its weight (a caisson sliding on
  its mound, a block on an incline) slides slower than that. At ``χ ≥ V`` the law
  carries at most ``φ(V) = 1/√2`` of μp at any slip slower than V: friction is a weak
  dashpot, not Coulomb's, and nothing can stick. χ = 1e6 m/s on the Goda case (V =
  1.47 m/s) ran without a word. Not checked without gravity and initial velocities
  (V = 0: only the loads move the bodies).
- **χ too small.** A GN22 step's slip velocity is computed from its displacements:
  ``v₁ = v₀ + Δt((1 − β₁) a₀ + β₁ a₁)``, ``a₁ = 2(u₁ − u₀ − Δt v₀ − ½Δt²(1 − β₂) a₀)/(β₂Δt²)``,
  so ``∂v₁/∂u₁ = 2β₁/(β₂ Δt)``, and a displacement of size U is resolved to ε U
  (ε = 2.2e-16, double precision): the slip velocities carry a round-off of
  ``δv = 2β₁ ε U/(β₂ Δt)``. Where the law's stick band (|v| < χ, where it is smooth)
  comes near it, the friction at a sticking node turns with the last bits of u
  (its stick tangent μp/χ·2β₁/(β₂Δt) ≫ the bulk's) and the Newton iterations do not
  converge. U is at least the contact's static penetration under the slave's weight,
  ``δ = ρ |g| H/ε_n`` (H the slave body's extent along g), the scale used. The
  failures begin above δv itself, measured on the sliding-block example (a general pair; δ
  = 5.9e-8 m, the static penetration the run reports): at Δt = 1e-3 s (δv = 2.6e-20 m/s)
  it runs at χ = 1e-19 m/s and fails its static state from 1e-20 down; at Δt = 1e-4 s (δv
  = 2.6e-19 m/s; 4.2e-18 at its cut-backs' 6.25e-6 s) it runs at 1e-14 and fails its first
  steps from 1e-15 down, 4000 δv. Warned below :data:`MARGIN` δv. The Goda case (δ =
  9.2e-6 m, Δt = 1e-4 s: δv = 4.0e-17 m/s) failed its first step at χ = 1e-30 with no hint
  (226 s, or 19 s for a 2-step run); the paper's χ = 1e-10 m/s is 250 MARGIN δv.
  Not checked without gravity (δ = 0).

Both are warnings, not refusals: V and δ are scales, not bounds on what a run does. A run
checks its model (:func:`model_warnings`, from :class:`breakwater.run.session.Session`):
a case's and one built in Python alike (before 2026-11-29 a case's build checked its case,
and a model built in Python was not checked), the lines logged once when the run starts
and kept in the summary's ``mesh.warnings``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping, Sequence

    from breakwater.casefile.settings import CaseSettings
    from breakwater.config.runspec import TimeSpec
    from breakwater.model.model import ContactModel

__all__ = ["MARGIN", "ROUND_OFF", "case_warnings", "model_warnings", "regularisation_warning",
           "speed_scale", "velocity_roundoff"]

ROUND_OFF = 2.0**-52
"""Double precision's relative round-off ε (numpy.finfo(float).eps)."""

MARGIN = 1e4
"""χ below MARGIN times the velocities' round-off δv is warned about: the module doc's
measured failures reach 4000 δv."""


def speed_scale(gravity: float, end_time: float, initial_speed: float = 0.0) -> float:
    """The run's speed scale V = |g| T + max |v₀| (m/s): the module doc."""
    return gravity * end_time + initial_speed


def velocity_roundoff(penetration: float, dt: float, beta1: float, beta2: float) -> float:
    """The round-off of a GN22 step's velocities, δv = 2β₁ ε δ/(β₂ Δt) (m/s): the module doc.

    Args:
        penetration: The displacement scale δ (m): the penalty's static penetration
            ρ |g| H/ε_n under the slave's weight.
        dt: The time step Δt (s).
        beta1: GN22's β₁.
        beta2: GN22's β₂.
    """
    return 2.0 * beta1 * ROUND_OFF * penetration / (beta2 * dt)


def regularisation_warning(pair: str, chi: float, friction: float, speed: float,
                           roundoff: float) -> str | None:
    """One line if a frictional pair's χ is at least V or below :data:`MARGIN` δv.

    Args:
        pair: The ``[contact.<pair>]`` name.
        chi: Its regularisation χ (m/s).
        friction: Its μ (0: no friction law, nothing to check).
        speed: The run's speed scale V (:func:`speed_scale`; 0: not checked).
        roundoff: The velocities' round-off δv (:func:`velocity_roundoff`; 0: not checked).

    Returns:
        The warning, naming ``contact.<pair>.regularisation`` and the order of magnitude
        to set, or None.
    """
    if friction <= 0.0:
        return None
    key = f"contact.{pair}.regularisation"
    if speed > 0.0 and chi >= speed:
        return (f"{key} = {chi:g} m/s is not below the run's speed scale V = {speed:.3g} m/s "
                f"(|g|·end_time + the largest initial speed): the friction law carries at "
                f"most μp/√2 at any slip slower than V, a weak dashpot μp·v/χ instead of "
                f"Coulomb friction; set it far below V, e.g. 1e-10 m/s (the paper's)")
    if chi < MARGIN * roundoff:
        advice = max(1e-10, 10.0 ** math.ceil(math.log10(10.0 * MARGIN * roundoff)))
        return (f"{key} = {chi:g} m/s is below {MARGIN:g} times the round-off of the slip "
                f"velocities, {roundoff:.2g} m/s (2β₁/β₂·ε·δ/Δt, δ the penalty's static "
                f"penetration under the slave's weight, Δt = time.dt): the friction law's "
                f"stick band comes near round-off and the Newton iterations may not "
                f"converge; set it to {advice:g} m/s or more (the paper's 1e-10)")
    return None


def case_warnings(case: CaseSettings, sizes: dict[str, dict[str, Any]]) -> list[str]:
    """:func:`regularisation_warning` of every contact pair of a case.

    Args:
        case: The case (its gravity, time, bodies and contact tables).
        sizes: The bodies' ``extent`` by name
            (:func:`~breakwater.outputs.bodysizes.body_sizes`).
    """
    t = case.time
    v0 = max((math.hypot(*b.initial_velocity) for b in case.bodies), default=0.0)
    return _warnings(case.gravity, t, v0, {b.name: b.density for b in case.bodies},
                     ((c.name, c.slave, c.penalty, c.friction, c.regularisation)
                      for c in case.contact), sizes)


def model_warnings(model: ContactModel, time: TimeSpec,
                   sizes: Mapping[str, Mapping[str, Any]]) -> list[str]:
    """:func:`regularisation_warning` of every contact pair of a model, run with ``time``.

    Args:
        model: The model (its gravity, initial velocities, bodies and pairs): a case's,
            or one built in Python.
        time: The run's time settings.
        sizes: The bodies' ``extent`` by name
            (:func:`~breakwater.outputs.bodysizes.body_sizes`).
    """
    v0 = max((math.hypot(*v) for _, v in model.initial.velocities), default=0.0)
    pairs = [(p.spec.interface, p.spec.slave, p.spec.penalty, p.spec.friction,
              p.spec.regularisation) for p in model.pairs]
    pairs += [(p.name, p.slave, p.penalty, p.friction, p.regularisation)
              for p in model.surface_pairs]
    return _warnings([float(g) for g in model.gravity.value], time, v0,
                     {b.spec.name: b.spec.material.density for b in model.bodies}, pairs,
                     sizes)


def _warnings(gravity: Sequence[float], t: TimeSpec, v0: float, density: Mapping[str, float],
              pairs: Iterable[tuple[str, str, float, float, float]],
              sizes: Mapping[str, Mapping[str, Any]]) -> list[str]:
    """The lines of the pairs ``(name, slave, penalty, friction, regularisation)``."""
    g = math.hypot(*gravity)
    speed = speed_scale(g, t.end_time, v0)
    lines = []
    for name, slave, penalty, friction, chi in pairs:
        roundoff = 0.0
        if g > 0.0 and slave in sizes:  # H: the slave's extent along g
            height = sum(abs(gk) / g * e for gk, e in zip(gravity, sizes[slave]["extent"],
                                                        strict=False))
            roundoff = velocity_roundoff(density[slave] * g * height / penalty, t.dt,
                                         t.beta1, t.beta2)
        line = regularisation_warning(name, chi, friction, speed, roundoff)
        if line is not None:
            lines.append(line)
    return lines
