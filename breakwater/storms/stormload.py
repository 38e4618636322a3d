"""A storm as loads of the FE model: the front pressure and the uplift, wave by wave.

One wave's load (:class:`~breakwater.storms.waves.WaveLoad`) is ``p₁(τ) · shape(z)`` on
the seaward face and ``p_u(τ)`` × the uplift triangle under the base. A storm drives the
model with them one after the other, in one run:

- the front: a :class:`~breakwater.loads.fields.StagedProfile` whose stage k is wave k's
  ``shape`` (placed at the still water level), from its start on, times
  :class:`WaveHistory` of p₁ (the model sets the shape's points at each wave's start);
- the uplift: the fixed triangle (1 at the seaward edge, 0 at the heel) times
  :class:`WaveHistory` of p_u.

Between the end of a wave's force and the next wave's start both are 0.
"""

from __future__ import annotations

import bisect
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

from breakwater.loads.fields import StagedProfile
from breakwater.storms.waves import WaveLoad

__all__ = ["WaveHistory", "check_wave_loads", "front_field"]


def check_wave_loads(loads: Sequence[WaveLoad]) -> None:
    """Refuse wave loads that do not follow one another.

    Raises:
        ValueError: No load; a wave starting before the one before it; a wave's force
            lasting past the next wave's start (its tail would be lost); a front shape
            of fewer than two points.
    """
    if not loads:
        raise ValueError("a storm needs at least one wave")
    for k, w in enumerate(loads):
        if len(w.front) < 2:
            raise ValueError(f"wave {k + 1}: its front shape needs at least two points")
        if not w.duration > 0:
            raise ValueError(f"wave {k + 1}: its force must last > 0 s (got {w.duration!r})")
        if k + 1 < len(loads):
            gap = loads[k + 1].wave.start - w.wave.start
            if not gap > 0:
                raise ValueError(f"wave {k + 2} starts at {loads[k + 1].wave.start:g} s, not "
                                 f"after wave {k + 1} ({w.wave.start:g} s)")
            if w.duration > gap * (1 + 1e-12):
                raise ValueError(f"wave {k + 1}'s force lasts {w.duration:g} s, past the "
                                 f"start of wave {k + 2} {gap:g} s later")


@dataclass(frozen=True)
class WaveHistory:
    """t ↦ the pressure of the wave whose force acts at t: p₁ or p_u (Pa), else 0.

    Attributes:
        loads: The waves' loads in order of their start (:func:`check_wave_loads`).
        part: ``"p1"`` (the front's pressure at the still water level) or ``"uplift"``.

    """

    loads: tuple[WaveLoad, ...]
    part: Literal["p1", "uplift"]
    starts: tuple[float, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "starts", tuple(w.wave.start for w in self.loads))

    def wave(self, t: float) -> int | None:
        """The last wave started at ``t`` (None before the first)."""
        k = bisect.bisect_right(self.starts, t) - 1
        return k if k >= 0 else None

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """Where the history jumps or its slope changes, on the run's clock (s).

        Each wave's start and end of force, and its history's own breakpoints (τ from
        the wave's start: :class:`breakwater.storms.waveforce.PulseHistory`'s, a
        :class:`~breakwater.loads.signals.Table`'s points). Adaptive steps keep a few
        steps between them.

        Raises:
            AttributeError: A wave's history does not give its breakpoints (a plain
                function): then there are none to give (adaptive steps refuse it).
        """
        times: set[float] = set()
        for w in self.loads:
            history = w.p1 if self.part == "p1" else w.uplift
            own = getattr(history, "breakpoints", None)
            if own is None:
                raise AttributeError(f"the {self.part} history of the wave at t = "
                                     f"{w.wave.start:g} s gives no breakpoints")
            t0 = w.wave.start
            times.update(t0 + float(τ) for τ in own if 0.0 <= τ <= w.duration)
            times.update((t0, t0 + w.duration))
        return tuple(sorted(times))

    def __call__(self, t: float) -> float:
        """p₁ or p_u (Pa) at time ``t``."""
        k = self.wave(t)
        if k is None:
            return 0.0
        w = self.loads[k]
        τ = t - w.wave.start
        if not τ < w.duration:
            return 0.0
        return float(w.p1(τ) if self.part == "p1" else w.uplift(τ))


def front_field(loads: Sequence[WaveLoad], still_water_level: float) -> StagedProfile:
    """The front pressure per unit p₁: wave k's shape from its start on (y = SWL + z)."""
    check_wave_loads(loads)
    return StagedProfile(tuple(tuple(w.front) for w in loads),
                         tuple(w.wave.start for w in loads), (0.0, 1.0),
                         (0.0, still_water_level))
