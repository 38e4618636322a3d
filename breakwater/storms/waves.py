"""The data of a storm: waves, the site, and one wave's load (frozen dataclasses).

A storm is a :class:`WaveTrain`: waves one after the other, each a :class:`Wave` of
height H and period T whose force begins at ``start`` (s from the storm's start). The
:class:`Site` holds Goda's geometry of the breakwater and the water (the inputs of
:func:`breakwater.loads.wavepressure.goda_pressure` other than H and T). A
:class:`WaveLoad` is what one wave applies to the caisson:

- on the seaward face, the pressure ``p(z, τ) = p₁(τ) · shape(z)``, with ``shape`` Goda's
  front profile normalised to 1 at the still water level (``front``: (z above the SWL,
  p/p₁) points, linear between them, 0 outside), and ``p₁(τ)`` the pressure at the SWL at
  the time τ = t − start since the wave's force began (quasi-static and impulsive parts
  alike: Takahashi's extension changes p₁ only, so p₃ = α₃ p₁ and p₄ keep the shape);
- under the base, the triangular uplift, ``p_u(τ)`` at the seaward edge, 0 at the heel.

Both histories are 0 for τ < 0 and for τ >= ``duration``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from breakwater.config.typecheck import check_fields

__all__ = ["Site", "Wave", "WaveLoad", "WaveTrain"]


@dataclass(frozen=True)
class Wave:
    """One wave of a storm.

    Attributes:
        height: H (m), > 0.
        period: T (s), > 0.
        start: When the wave's force begins (s from the storm's start), >= 0.

    """

    height: float
    period: float
    start: float = 0.0

    def __post_init__(self) -> None:
        if not (self.height > 0 and math.isfinite(self.height)):
            raise ValueError(f"wave height must be > 0 (got {self.height!r})")
        if not (self.period > 0 and math.isfinite(self.period)):
            raise ValueError(f"wave period must be > 0 (got {self.period!r})")
        if not (self.start >= 0 and math.isfinite(self.start)):
            raise ValueError(f"wave start must be >= 0 (got {self.start!r})")

    @property
    def end(self) -> float:
        """The start of the next wave when the waves follow one another: start + T."""
        return self.start + self.period


@dataclass(frozen=True)
class WaveTrain:
    """Waves in order of their start, not overlapping (each starts after the last ends).

    Attributes:
        waves: The waves (at least one).

    """

    waves: tuple[Wave, ...]

    def __post_init__(self) -> None:
        if not self.waves:
            raise ValueError("a wave train needs at least one wave")
        for i, (w0, w1) in enumerate(zip(self.waves, self.waves[1:], strict=False)):
            if w1.start < w0.end * (1 - 1e-12):
                raise ValueError(f"wave {i + 2} starts at {w1.start:g} s, before wave "
                                 f"{i + 1} ends ({w0.end:g} s)")

    def __len__(self) -> int:
        return len(self.waves)

    @property
    def duration(self) -> float:
        """The end of the last wave (s)."""
        return self.waves[-1].end


@dataclass(frozen=True)
class Site:
    """Goda's geometry of the breakwater and the water (names as ``[loads.<name>.goda]``).

    Attributes:
        depth: h, water depth in front of the breakwater (m).
        toe_depth: h', depth of the base of the upright section below the SWL (m).
        berm_depth: d, depth above the armour of the foundation (m).
        crest_height: h_c, crest elevation above the SWL (m).
        base_width: B, width of the caisson's base (m): the uplift's triangle.
        angle: β, wave incidence from the normal to the breakwater (degrees).
        breaking_depth: h_b, depth at 5 H_1/3 seaward (m); None: h.
        factors: λ₁, λ₂, λ₃.
        density: Water density ρ (kg/m³).
        gravity: g (m/s²).
        berm_width: B_M, width of the berm in front of the upright section (m); given:
            Takahashi's impulsive coefficient α_I enters p₁ (the extended formula).

    """

    depth: float
    toe_depth: float
    berm_depth: float
    crest_height: float
    base_width: float
    angle: float = 0.0
    breaking_depth: float | None = None
    factors: tuple[float, float, float] = (1.0, 1.0, 1.0)
    density: float = 1025.0
    gravity: float = 9.81
    berm_width: float | None = None

    def __post_init__(self) -> None:
        # The types only (the ranges: the Goda formulas'; a case's storm reads its waves
        # with base_width NaN, which only the uplift's force takes).
        check_fields(self, ValueError, finite=False)


@dataclass(frozen=True)
class WaveLoad:
    """One wave's pressures on the caisson (module docstring).

    Attributes:
        wave: The wave.
        front: (z above the SWL (m), p/p₁) points of the front profile, increasing z.
        p1: τ ↦ p₁ (Pa), τ the time since the wave's force began (s).
        uplift: τ ↦ p_u (Pa) at the seaward edge of the base.
        duration: The force lasts 0 <= τ < duration (s).

    """

    wave: Wave
    front: tuple[tuple[float, float], ...]
    p1: Callable[[float], float]
    uplift: Callable[[float], float]
    duration: float
