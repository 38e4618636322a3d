"""One wave's pressure on the caisson over time: Goda(–Takahashi) peaks, a force-time profile.

**Peaks** (:func:`breakwater.loads.wavepressure.goda_pressure` for the wave's H and T at
the :class:`~breakwater.storms.waves.Site`): Goda's (1974, 2000) pressures with the
wave's own height in place of H_max; with ``site.berm_width`` given, Takahashi, Tanimoto
& Shimosako's (1994) extended formula, α* = max(α₂, α_I) in p₁. The front shape is
Goda's profile divided by p₁ (p₃/p₁ = α₃, p₄/p₁ = 1 − h_c/η*: the same with or without
α_I), the uplift at the seaward edge p_u has neither α₂ nor α_I.

**Force-time profile** (τ = t − start, the time since the wave's force began)::

    p₁(τ) = p₁,G sin(π τ/τ₀) + (p₁,GT − p₁,G) Λ(τ)       0 <= τ < τ₀, else 0
    p_u(τ) = p_u sin(π τ/τ₀)                             0 <= τ < τ₀, else 0
    Λ(τ)  = max(0, 1 − |τ − τ₀/2| / (τ₁/2))               (a triangle of base τ₁)
    τ₀ = k₀ T,   τ₁ = k₁ τ₀

with p₁,G Goda's p₁ (α₂: the standing, quasi-static part) and p₁,GT the Goda–Takahashi
p₁ (α*: the impulsive part is the excess p₁,GT − p₁,G, present only when α_I > α₂). The
peak, at τ₀/2, is Goda–Takahashi's p₁, so the peak of the horizontal force P(τ) is the
Goda(–Takahashi) P of the wave.

What this follows and what it does not (**read before relying on the durations**):

- The shape, a quasi-static hump of Goda's pressure with a short triangular impulsive
  peak of the Goda–Takahashi excess on top, is the structure of the PARI model used for
  sliding computations by Shimosako & Takahashi (1994, Rep. PHRI 33(3), in Japanese;
  1999, Proc. Coastal Structures '99, 363–371) and summarised in Takahashi (2002,
  "Design of vertical breakwaters", PARI ref. doc. 34, §4.5). We could not read the
  equations of those sources in this work: the sine hump, the triangle's position at
  the crest and both durations below are **our choices, not theirs**.
- τ₀ = k₀ T, default k₀ = ½: under a linear standing wave the horizontal force on the
  wall is ∝ cos ωt, landward for half a period (the trough's seaward half cycle is left
  out: the rigid model slides landward only). The PARI model uses a shorter, H/h-
  dependent duration, which we recall as k₀ = 0.5 − H/(8h) but could not check: pass
  ``ForceProfile(duration_fraction=...)`` to use another value.
- τ₁ = k₁ τ₀, default k₁ = 0.1: an assumption of this implementation (no source
  checked). It matters only with ``site.berm_width`` and α_I > α₂; sliding from a
  short peak grows with its impulse ½ (p₁,GT − p₁,G) τ₁, so test its effect.

**Resultants per metre** (:class:`Resultants`): with the front shape s(z) (s(0) = 1),
the horizontal force and its moment about the heel (the base's landward edge, z = −h')::

    P(τ) = p₁(τ) ∫ s dz,         M_P(τ) = p₁(τ) ∫ s (z + h') dz
    U(τ) = ½ p_u(τ) B,           M_U(τ) = ⅔ U(τ) B

(the integrals exact for the piecewise-linear shape; the same as
:attr:`~breakwater.loads.wavepressure.GodaPressure.force` and ``moment`` per unit p₁).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from breakwater.loads.wavepressure import GodaPressure, goda_pressure
from breakwater.storms.waves import Site, Wave, WaveLoad

__all__ = ["ForceProfile", "PulseHistory", "Resultants", "resultants", "wave_load"]


@dataclass(frozen=True)
class ForceProfile:
    """The durations of the force-time profile (module docstring: our choices).

    Attributes:
        duration_fraction: k₀ = τ₀/T, in (0, 1].
        impulse_fraction: k₁ = τ₁/τ₀, in (0, 1].

    """

    duration_fraction: float = 0.5
    impulse_fraction: float = 0.1

    def __post_init__(self) -> None:
        for name in ("duration_fraction", "impulse_fraction"):
            value = getattr(self, name)
            if not 0.0 < value <= 1.0:
                raise ValueError(f"{name}: must be in (0, 1] (got {value!r})")


@dataclass(frozen=True)
class PulseHistory:
    """τ ↦ a sin(πτ/τ₀) + b Λ(τ) on [0, τ₀), 0 elsewhere (module docstring).

    Attributes:
        standing: a, the amplitude of the sine hump.
        impulsive: b >= 0, the height of the triangle centred on τ₀/2.
        duration: τ₀ (s).
        impulse_duration: τ₁ (s), the triangle's base.

    """

    standing: float
    impulsive: float
    duration: float
    impulse_duration: float

    def __call__(self, τ: float) -> float:
        """The value at τ (s since the wave's force began)."""
        if not 0.0 <= τ < self.duration:
            return 0.0
        value = self.standing * math.sin(math.pi * τ / self.duration)
        if self.impulsive > 0.0:
            value += self.impulsive * max(0.0, 1.0 - abs(τ - 0.5 * self.duration)
                                          / (0.5 * self.impulse_duration))
        return value

    @property
    def peak(self) -> float:
        """The largest value, a + b at τ₀/2."""
        return self.standing + self.impulsive

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """Where the history is not smooth (its ends and the triangle's corners)."""
        if self.impulsive <= 0.0:
            return (0.0, self.duration)
        c, w = 0.5 * self.duration, 0.5 * self.impulse_duration
        return (0.0, c - w, c, c + w, self.duration)


def wave_load(wave: Wave, site: Site, profile: ForceProfile | None = None) -> WaveLoad:
    """One wave's load: Goda(–Takahashi) pressures with the force-time profile.

    Args:
        wave: The wave (H, T, start).
        site: The site (Goda's geometry; ``berm_width``: Takahashi's α_I).
        profile: The durations (default :class:`ForceProfile`).

    Raises:
        GodaRangeError: The wave or the site outside Goda's range (e.g. H above the
            breaking limit), naming the input.

    """
    profile = ForceProfile() if profile is None else profile
    goda = _goda(wave, site, impulsive=False)
    total = goda.p1 if site.berm_width is None else _goda(wave, site, impulsive=True).p1
    τ0 = profile.duration_fraction * wave.period
    τ1 = profile.impulse_fraction * τ0
    front = tuple((z, p / goda.p1) for z, p in goda.front_points())
    p1 = PulseHistory(goda.p1, max(total - goda.p1, 0.0), τ0, τ1)
    uplift = PulseHistory(goda.uplift, 0.0, τ0, τ1)
    return WaveLoad(wave=wave, front=front, p1=p1, uplift=uplift, duration=τ0)


def _goda(wave: Wave, site: Site, impulsive: bool) -> GodaPressure:
    """Goda's pressures of the wave at the site (Takahashi's α_I with ``impulsive``)."""
    return goda_pressure(wave.height, wave.period, site.depth, site.toe_depth,
                         site.berm_depth, site.crest_height, angle=site.angle,
                         breaking_depth=site.breaking_depth, factors=site.factors,
                         density=site.density, gravity=site.gravity, impulsive=impulsive,
                         berm_width=site.berm_width if impulsive else None)


@dataclass(frozen=True)
class Resultants:
    """The resultants per metre of a :class:`WaveLoad` over time (module docstring).

    Attributes:
        load: The wave's load.
        base_width: B (m): the uplift's triangle.
        toe_depth: h' (m): the heel at z = −h'.
        force_per_p1: ∫ s dz (m): P = p₁ × this.
        moment_per_p1: ∫ s (z + h') dz (m²): M_P about the heel = p₁ × this.

    """

    load: WaveLoad
    base_width: float
    toe_depth: float
    force_per_p1: float
    moment_per_p1: float

    def force(self, τ: float) -> float:
        """P(τ), the horizontal force (N/m)."""
        return self.load.p1(τ) * self.force_per_p1

    def moment(self, τ: float) -> float:
        """M_P(τ), the horizontal force's moment about the heel (N m/m)."""
        return self.load.p1(τ) * self.moment_per_p1

    def uplift(self, τ: float) -> float:
        """U(τ) = ½ p_u(τ) B (N/m)."""
        return 0.5 * self.load.uplift(τ) * self.base_width

    def uplift_moment(self, τ: float) -> float:
        """M_U(τ) = ⅔ U(τ) B about the heel (N m/m)."""
        return 2.0 / 3.0 * self.uplift(τ) * self.base_width


def resultants(load: WaveLoad, site: Site) -> Resultants:
    """The resultants of ``load`` on the caisson of ``site`` (exact for the linear shape)."""
    h1 = site.toe_depth
    force = moment = 0.0
    for (z0, s0), (z1, s1) in zip(load.front, load.front[1:], strict=False):
        dz = z1 - z0
        force += 0.5 * (s0 + s1) * dz
        # ∫ s (z + h') dz of a linear s: exact by Simpson's rule (a quadratic).
        zm, sm = 0.5 * (z0 + z1), 0.5 * (s0 + s1)
        moment += dz / 6.0 * (s0 * (z0 + h1) + 4.0 * sm * (zm + h1) + s1 * (z1 + h1))
    return Resultants(load=load, base_width=site.base_width, toe_depth=h1,
                      force_per_p1=force, moment_per_p1=moment)
