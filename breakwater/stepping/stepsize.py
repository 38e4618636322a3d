"""Step-size control of the time loop: halve on failure, grow back, land on the end.

The loop asks :meth:`StepSize.propose` for the next step, tries it, and reports
:meth:`~StepSize.reject` (the step did not converge: retry with half of it, up to
``max_cutbacks`` halvings of the nominal Δt in effect) or :meth:`~StepSize.accept`.
After :data:`GROW_AFTER` accepted steps in a row the step doubles again, never above
the nominal Δt. The time is the exactly rounded sum of the accepted steps
(:func:`math.fsum`, no drift), and the step that reaches ``end_time`` lands on it
exactly: when what remains is at most the current step (within 1e-6 of it), the
step is what remains.

The controller is plain data (a dataclass of numbers and a list), so a checkpoint
saves and restores it as it is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

__all__ = ["GROW_AFTER", "StepSize"]

GROW_AFTER = 4
"""Accepted steps after a cut-back before the step size doubles again."""


@dataclass
class StepSize:
    """The step size of the time loop and its history.

    Args:
        dt: The nominal step (s).
        end_time: The time to reach (s).
        max_cutbacks: Halvings of ``dt`` allowed at once.
        floor: No cut-back makes the step smaller than this (s; 0: no floor).
        t: The time reached: the exactly rounded sum of ``accepted``.
        h: The current step size.
        halvings: Halvings of ``dt`` in effect (``h = dt / 2**halvings``, or what
            remained before the end when that was halved).
        streak: Accepted steps since the last change of ``h``.
        accepted: The accepted step sizes, after a leading 0.
        min_dt: The smallest step size tried after a cut-back (``dt`` without one).
        cutbacks: Cut-backs so far.

    """

    dt: float
    end_time: float
    max_cutbacks: int
    floor: float = 0.0
    t: float = 0.0
    h: float = math.nan
    halvings: int = 0
    streak: int = 0
    accepted: list[float] = field(default_factory=lambda: [0.0])
    min_dt: float = math.nan
    cutbacks: int = 0

    def __post_init__(self) -> None:
        if not (self.dt > 0 and self.end_time >= 0 and self.max_cutbacks >= 0):
            raise ValueError(f"invalid time settings: dt = {self.dt}, end_time = "
                             f"{self.end_time}, max_cutbacks = {self.max_cutbacks}")
        if math.isnan(self.h):
            self.h = self.dt
        if math.isnan(self.min_dt):
            self.min_dt = self.dt

    @property
    def finished(self) -> bool:
        """Whether ``end_time`` is reached (to 1e-9 of the nominal step)."""
        return self.end_time - self.t <= 1e-9 * self.dt

    def _next(self) -> tuple[float, bool]:
        """The step to try, and whether it is the last one (it lands on the end)."""
        remaining = self.end_time - self.t
        last = remaining <= self.h * (1.0 + 1e-6)
        return (remaining if last and abs(remaining - self.h) > 1e-9 * self.h
                else self.h), last

    def propose(self) -> float:
        """The step to try from ``t``: ``h``, or what remains before the end."""
        return self._next()[0]

    def reject(self) -> bool:
        """The proposed step failed: halve it, unless no cut-back is left.

        Returns:
            True when the step is to be retried with ``h`` halved; False when
            ``max_cutbacks`` halvings are in effect already, or half the step would be
            below ``floor`` (nothing changes).
        """
        trial = self.propose()
        if self.halvings >= self.max_cutbacks or 0.5 * trial < self.floor * (1 - 1e-9):
            return False
        self.halvings += 1
        self.cutbacks += 1
        self.h = 0.5 * trial
        self.min_dt = min(self.min_dt, self.h)
        self.streak = 0
        return True

    def accept(self) -> bool:
        """The proposed step succeeded: advance ``t`` by it (exactly onto the end).

        Returns:
            Whether the step size grew back (doubled) after this step.
        """
        trial, last = self._next()
        self.accepted.append(trial)
        self.t = self.end_time if last else math.fsum(self.accepted)
        self.streak += 1
        if self.halvings > 0 and self.streak >= GROW_AFTER:
            self.halvings -= 1
            self.h = min(2.0 * self.h, self.dt)
            self.streak = 0
            return True
        return False
