"""Load time functions: pulses of given impulse, constant, ramp-and-hold, tabulated.

Every load is a time function t ↦ factor times a fixed spatial traction field (see
:mod:`breakwater.loads.fields`); the time functions here are plain callables (frozen
dataclasses, so that a checkpoint can fingerprint them):

- :class:`Pulse`: an impact pulse of given impulse (below), with the pendulum impulse
  of eq. 29 (:func:`pendulum_impulse`);
- :class:`Constant`: ``value`` from ``start`` on (zero before);
- :class:`Ramp`: zero until ``start``, linear rise to ``value`` over ``rise``, then held;
- :class:`Table`: linear interpolation of (t, value) points (a measured record), the
  first value before the first point; after the last point an error unless
  ``hold_last``.

A pulse is an amplitude ``t ↦ f(t)`` that is zero outside ``[start, start + duration]``
and whose time integral is exactly the impulse it was built for, so the
momentum given to the structure does not depend on the chosen shape or duration
(only on the impulse). The shapes:

- ``"triangular"``: linear rise to the peak at ``start + peak·duration``, linear
  decay (the paper's Fig. 15); peak value ``2I/duration``.
- ``"rectangular"``: constant ``I/duration``.
- ``"half-sine"``: ``(πI / 2 duration) sin(π (t − start)/duration)``.

The time stepper samples the amplitude at the step ends. The trapezoidal sum of a
triangular pulse is exact when its start, peak and end fall on step ends; the
other shapes are integrated to O(Δt²) (or O(Δt) at the jumps of the rectangle).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Literal

PulseShape = Literal["triangular", "rectangular", "half-sine"]
PULSE_SHAPES: tuple[str, ...] = ("triangular", "rectangular", "half-sine")

STANDARD_GRAVITY = 9.81
"""g (m/s²) used by the paper in eq. 29 and for the caisson weight (4586 N/m²)."""


def impact_velocity(cord_length: float, release_distance: float,
                    gravity: float = STANDARD_GRAVITY) -> float:
    """Velocity of the pendulum at impact, ω = s₀ sqrt(g / l₀) (m/s, eq. 29).

    The small-angle pendulum released at rest a horizontal distance ``s₀`` from the
    face moves harmonically with circular frequency sqrt(g/l₀); its speed at the
    face (the bottom of the swing) is amplitude × frequency.

    Args:
        cord_length: Cord length l₀ (m).
        release_distance: Release distance s₀ from the struck face (m).
        gravity: Acceleration of gravity g (m/s²).

    """
    if not (cord_length > 0 and release_distance > 0 and gravity > 0):
        raise ValueError("cord length, release distance and gravity must be > 0")
    return release_distance * math.sqrt(gravity / cord_length)


def pendulum_impulse(mass: float, cord_length: float, release_distance: float,
                     restitution: float, gravity: float = STANDARD_GRAVITY) -> float:
    """Impulse of a pendulum bouncing off the structure, I = M ω (1 + e₀) (N s, eq. 29).

    The pendulum arrives with velocity ω and leaves with −e₀ ω; the change of its
    momentum is the impulse given to the structure (a rigid, fixed target: the
    paper's assumption).

    Args:
        mass: Pendulum mass M (kg).
        cord_length: Cord length l₀ (m).
        release_distance: Release distance s₀ (m).
        restitution: Coefficient of restitution e₀ (-), in [0, 1].
        gravity: Acceleration of gravity g (m/s²).

    """
    if not mass > 0:
        raise ValueError(f"pendulum mass must be > 0 (got {mass})")
    if not 0.0 <= restitution <= 1.0:
        raise ValueError(f"restitution must be in [0, 1] (got {restitution})")
    return mass * impact_velocity(cord_length, release_distance, gravity) * (1.0 + restitution)


@dataclass(frozen=True)
class Pulse:
    """A force-time pulse of given impulse (callable: t ↦ amplitude).

    Attributes:
        impulse: Time integral of the amplitude (amplitude unit × s).
        duration: Pulse length (s), > 0.
        shape: ``"triangular"``, ``"rectangular"`` or ``"half-sine"``.
        start: Time the pulse starts (s).
        peak: Triangular pulses: time of the peak as a fraction of the duration,
            in [0, 1] (0.5: symmetric).

    """

    impulse: float
    duration: float
    shape: PulseShape = "triangular"
    start: float = 0.0
    peak: float = 0.5

    def __post_init__(self) -> None:
        if self.shape not in PULSE_SHAPES:
            raise ValueError(f"unknown pulse shape {self.shape!r} (known: "
                             f"{', '.join(PULSE_SHAPES)})")
        if not (self.duration > 0 and math.isfinite(self.duration)):
            raise ValueError(f"pulse duration must be > 0 (got {self.duration})")
        if not 0.0 <= self.peak <= 1.0:
            raise ValueError(f"pulse peak fraction must be in [0, 1] (got {self.peak})")

    @property
    def end(self) -> float:
        """Time the pulse ends (s)."""
        return self.start + self.duration

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """Times where the amplitude jumps or its slope changes (s): start, peak, end."""
        if self.shape == "triangular":
            return (self.start, self.start + self.peak * self.duration, self.end)
        return (self.start, self.end)

    @property
    def maximum(self) -> float:
        """Largest amplitude of the pulse."""
        return {"triangular": 2.0, "rectangular": 1.0,
                "half-sine": 0.5 * math.pi}[self.shape] * self.impulse / self.duration

    def __call__(self, t: float) -> float:
        """Amplitude at time ``t``."""
        s = (t - self.start) / self.duration  # position in the pulse, 0..1
        if s < 0.0 or s > 1.0:
            return 0.0
        if self.shape == "rectangular":
            return self.impulse / self.duration
        if self.shape == "half-sine":
            return self.maximum * math.sin(math.pi * s)
        p = self.peak
        if s < p:
            rise = s / p
        elif s > p:
            rise = (1.0 - s) / (1.0 - p)
        else:
            rise = 1.0
        return self.maximum * rise


@dataclass(frozen=True)
class Constant:
    """A constant factor ``value`` from ``start`` on, zero before (callable: t ↦ factor).

    With ``start = 0`` the load is present at t = 0 (and enters the initial static
    state); with ``start > 0`` it is applied suddenly at the first step end ≥ start.
    """

    value: float = 1.0
    start: float = 0.0

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """Where the factor jumps (s): ``start`` when it is after t = 0."""
        return (self.start,) if self.start > 0 else ()

    def __call__(self, t: float) -> float:
        """Factor at time ``t``."""
        return self.value if t >= self.start else 0.0


@dataclass(frozen=True)
class Ramp:
    """Zero until ``start``, linear rise to ``value`` at ``start + rise``, then held."""

    value: float = 1.0
    start: float = 0.0
    rise: float = 1.0

    def __post_init__(self) -> None:
        if not (self.rise > 0 and math.isfinite(self.rise)):
            raise ValueError(f"ramp rise time must be > 0 (got {self.rise})")

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """Where the slope changes (s): the start and the end of the rise."""
        return (self.start, self.start + self.rise)

    def __call__(self, t: float) -> float:
        """Factor at time ``t``."""
        s = (t - self.start) / self.rise
        return self.value * min(max(s, 0.0), 1.0)


class TableEnded(ValueError):
    """A :class:`Table` was evaluated after its last point without ``hold_last``."""


@dataclass(frozen=True)
class Table:
    """Linear interpolation of a tabulated history (callable: t ↦ factor).

    Attributes:
        times: Increasing times (s), at least two.
        values: The factor at each time.
        hold_last: After the last time keep the last value (else :class:`TableEnded`).
        start: The table's time 0 is at ``start`` (s): factor(t) = table(t − start).

    Before the first point the factor is the first value.
    """

    times: tuple[float, ...]
    values: tuple[float, ...]
    hold_last: bool = False
    start: float = 0.0

    def __post_init__(self) -> None:
        if len(self.times) != len(self.values):
            raise ValueError("times and values must have the same length")
        if len(self.times) < 2:
            raise ValueError("a table needs at least two points")
        if not all(math.isfinite(v) for v in (*self.times, *self.values)):
            raise ValueError("table values must be finite")
        for k in range(1, len(self.times)):
            if not self.times[k] > self.times[k - 1]:
                raise ValueError(f"times must increase (point {k}: t = {self.times[k]:g} after "
                                 f"t = {self.times[k - 1]:g})")

    @property
    def end(self) -> float:
        """The time of the last point (s), on the run's clock."""
        return self.start + self.times[-1]

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """The table's points on the run's clock (s): where the slope changes."""
        return tuple(self.start + t for t in self.times)

    def __call__(self, t: float) -> float:
        """Factor at time ``t``."""
        τ = t - self.start
        times, values = self.times, self.values
        if τ <= times[0]:
            return values[0]
        if τ >= times[-1]:
            if τ > times[-1] and not self.hold_last:
                raise TableEnded(f"the table ends at t = {self.end:g} s (asked at t = {t:g} s)")
            return values[-1]
        k = bisect.bisect_right(times, τ)  # times[k - 1] <= τ < times[k]
        t0, t1 = times[k - 1], times[k]
        return values[k - 1] + (values[k] - values[k - 1]) * (τ - t0) / (t1 - t0)
