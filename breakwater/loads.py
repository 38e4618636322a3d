"""Impact loads: the pendulum impulse (eq. 29) and force-time pulse shapes.

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
