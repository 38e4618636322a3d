"""Step-size control of the time loop: halve on failure, grow back, land on the end.

The loop asks :meth:`StepSize.propose` for the next step, tries it, and reports
:meth:`~StepSize.reject` (the step did not converge: retry with half of it, up to
``max_cutbacks`` halvings of the nominal Δt in effect) or :meth:`~StepSize.accept`.
After :data:`GROW_AFTER` accepted steps in a row the step doubles again, never above
the nominal Δt. The time is the exactly rounded sum of the accepted steps
(:func:`math.fsum` of their exact partial sums, kept step by step: no drift), and
the step that reaches ``end_time`` lands on it
exactly: when what remains is at most the current step (within 1e-6 of it), the
step is what remains.

**Adaptive steps** (``levels > 0``): the step sizes are ``dt / 2**k``, k = 0 … ``levels``
(a factorisation each, kept: :mod:`breakwater.stepping.factorisations`), chosen by

- the **local error** of the step just solved (:meth:`StepSize.judge`): GN22's local
  truncation error, estimated from the step's acceleration increment (Zienkiewicz &
  Xie 1991, "A simple error estimator and adaptive time stepping procedure for dynamic
  analysis", Earthquake Eng. Struct. Dyn. 20, 871–887; :func:`local_error`), against
  ``tolerance`` times the step's displacement increment plus a floor, a fraction
  :data:`FLOOR` of the largest displacement of the run so far (``scale``)::

      r = ‖e‖∞ / (tolerance (‖Δu‖∞ + FLOOR · scale))

  (a body at rest, or sticking, has Δu ≈ 0 but alternating accelerations, GN22's
  signature of a stiff stick: the floor keeps them from driving the step to its
  smallest);

  r > 1: the step is rejected and retried with half of it (unless it is the smallest);
  r <= 1: accepted; after :data:`CALM_STEPS` accepted steps in a row with
  r < :data:`GROW_BELOW` the step doubles (e ∝ Δt² Δa ∝ Δt³ and Δu ∝ Δt: doubling
  multiplies r by about 4), never above ``dt``;
- the **loads' breakpoints** (:meth:`StepSize.propose`): the times where a load's
  history jumps or turns (a pulse's start, peak and end; a table's points; a ramp's
  ends; each wave of a storm), so that no step jumps over a short load: the step is
  halved until it is at most 1/``resolve`` of every load segment it overlaps. The error
  alone would not see a pulse that begins and ends inside one step. A step that would
  pass a breakpoint is shortened to end on it (as the last step ends on ``end_time``):
  the steps sample each peak and corner of the loads exactly. Before, a breakpoint off
  the grid of the steps dt/2^k fell inside a step: a storm's impulsive peak (Takahashi's
  469.2 N/m) was applied as 468.7 N/m, found by a user. Each landing is a step size of
  its own (one more factorisation of the fast solver's step matrix).

A step that does not converge is halved as with fixed steps (a cut-back), down to the
smallest step.

The controller is plain data (a dataclass of numbers and lists), so a checkpoint
saves and restores it as it is.
"""

from __future__ import annotations

import bisect
import itertools
import math
from dataclasses import dataclass, field

__all__ = ["CALM_STEPS", "FLOOR", "GROW_AFTER", "GROW_BELOW", "LOAD_STEPS", "StepSize",
           "error_constant", "resolved_step"]

GROW_AFTER = 4
"""Accepted steps after a cut-back before the step size doubles again."""

GROW_BELOW = 0.15
"""Adaptive steps: the error ratio below which a step counts as calm (doubling the step
multiplies the ratio by about 4: 0.6 after it)."""

CALM_STEPS = 2
"""Adaptive steps: calm steps in a row before the step doubles."""


FLOOR = 1e-2
"""Adaptive steps: the error floor, as a fraction of the largest displacement so far."""

LOAD_STEPS = 5
"""Adaptive steps: the least number of steps per load segment (a triangular pulse, two
segments: 10 steps, as fixed steps resolve a pulse, ``casefile.loads.RESOLVED_STEPS``)."""


def resolved_step(dt: float, levels: int, breakpoints: tuple[float, ...] | list[float]
                  ) -> float:
    """The adaptive step inside a load of these ``breakpoints``.

    The largest ``dt / 2**k`` (k <= ``levels``) at most 1/:data:`LOAD_STEPS` of every
    segment between consecutive breakpoints.
    """
    bp = sorted(breakpoints)
    shortest = min((b - a for a, b in itertools.pairwise(bp) if b > a),
                   default=math.inf)
    k = 0
    while k < levels and dt / 2**k * LOAD_STEPS > shortest * (1 + 1e-9):
        k += 1
    return dt / 2**k


def _add_exactly(partials: list[float], x: float) -> None:
    """Add ``x`` to the exact sum held by ``partials`` (Shewchuk 1997; math.fsum's loop).

    ``math.fsum(partials)`` is then the correctly rounded sum of every value added.
    """
    i = 0
    for y in partials:
        if abs(x) < abs(y):
            x, y = y, x
        hi = x + y
        lo = y - (hi - x)
        if lo:
            partials[i] = lo
            i += 1
        x = hi
    partials[i:] = [x]


def error_constant(beta1: float, beta2: float) -> float:
    """The constant c in GN22's local error estimate ``e = c Δt² Δa`` (a bound, in displacement).

    The displacement's local truncation error of Newmark's scheme is
    (β − 1/6) Δt³ ȧ ≈ (β − 1/6) Δt² Δa with β = β₂/2 (Zienkiewicz & Xie 1991); with
    β₁ ≠ ½ the velocity's is (β₁ − ½) Δt Δa, which the next step carries into the
    displacement times Δt. The sum of both magnitudes: c = |β₂/2 − 1/6| + |β₁ − ½|
    (0.236 for the default β₁ = 0.6, β₂ = 0.605).
    """
    return abs(0.5 * beta2 - 1.0 / 6.0) + abs(beta1 - 0.5)


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
        levels: Adaptive steps: the halvings of ``dt`` allowed (0: fixed steps).
        tolerance: Adaptive steps: the local error allowed, relative to the step's
            displacement increment.
        scale: Adaptive steps: the largest ‖u‖∞ of the run so far (m).
        resolve: Adaptive steps: the least number of steps per load segment.
        breakpoints: Adaptive steps: the loads' breakpoints (s, sorted).
        rejected: Adaptive steps: steps rejected by the error estimate.
        calm: Adaptive steps: accepted steps in a row with a small error.
        ratio: Adaptive steps: the error ratio r of the last step judged.
        partials: ``accepted``'s exact sum as non-overlapping floats (Shewchuk's
            expansion, as :func:`math.fsum` keeps it): ``t`` in O(1) per step, not
            O(steps) (a storm of 280 000 steps spent most of its time summing).

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
    levels: int = 0
    tolerance: float = 0.0
    scale: float = 0.0
    resolve: int = LOAD_STEPS
    breakpoints: list[float] = field(default_factory=list)
    rejected: int = 0
    calm: int = 0
    ratio: float = 0.0
    partials: list[float] = field(default_factory=list)

    def __post_init__(self) -> None:
        if not (self.dt > 0 and self.end_time >= 0 and self.max_cutbacks >= 0):
            raise ValueError(f"invalid time settings: dt = {self.dt}, end_time = "
                             f"{self.end_time}, max_cutbacks = {self.max_cutbacks}")
        if self.levels < 0 or (self.levels and not self.tolerance > 0):
            raise ValueError(f"invalid adaptive settings: levels = {self.levels}, "
                             f"tolerance = {self.tolerance}")
        if not self.partials and len(self.accepted) > 1:  # a checkpoint saved without them
            for x in self.accepted:
                _add_exactly(self.partials, x)
        if math.isnan(self.h):
            self.h = self.dt
        if math.isnan(self.min_dt):
            self.min_dt = self.dt

    @property
    def finished(self) -> bool:
        """Whether ``end_time`` is reached (to 1e-9 of the nominal step)."""
        return self.end_time - self.t <= 1e-9 * self.dt

    def _next(self) -> tuple[float, bool]:
        """The step to try, and whether it is the last one (it lands on the end).

        Adaptive steps land on the loads' breakpoints as on the end: a step that would
        pass one (by more than 1e-6 of it) is what remains before it (module docstring).
        """
        remaining = self.end_time - self.t
        last = remaining <= self.h * (1.0 + 1e-6)
        step = remaining if last and abs(remaining - self.h) > 1e-9 * self.h else self.h
        if self.adaptive:
            bp = self.breakpoints
            i = bisect.bisect_right(bp, self.t + 1e-9 * self.h)  # the next one ahead
            if i < len(bp) and bp[i] - self.t < step * (1.0 - 1e-6):
                return bp[i] - self.t, False
        return step, last

    @property
    def adaptive(self) -> bool:
        """Whether the step size follows the error estimate and the loads."""
        return self.levels > 0

    def propose(self) -> float:
        """The step to try from ``t``: ``h``, or what remains before the end.

        Adaptive steps: ``h`` is first halved until it resolves the loads (module
        docstring).
        """
        if self.adaptive:
            while self.halvings < self.levels and self._coarse(self.t, self._next()[0]):
                self.halvings += 1
                self.h = self.dt / 2**self.halvings
                self.calm = 0
        return self._next()[0]

    def landing(self) -> float:
        """Where the proposed step ends, the ``t`` :meth:`accept` sets (not t + h rounded)."""
        trial, last = self._next()
        partials = list(self.partials)
        _add_exactly(partials, trial)
        return self.end_time if last else math.fsum(partials)

    def _coarse(self, t: float, h: float) -> bool:
        """Whether a step (t, t + h) is longer than 1/resolve of a load segment it meets."""
        bp = self.breakpoints
        i = bisect.bisect_right(bp, t)  # the segment holding t: bp[i-1] <= t < bp[i]
        j = bisect.bisect_left(bp, t + h)  # ... and t + h: bp[j-1] < t + h <= bp[j]
        for k in range(max(i, 1), min(j, len(bp) - 1) + 1):
            if h * self.resolve > (bp[k] - bp[k - 1]) * (1 + 1e-9):
                return True
        return False

    def judge(self, error: float, increment: float, size: float = 0.0) -> bool:
        """Adaptive steps: accept the step just solved, or retry it with half of it.

        Args:
            error: ‖e‖∞ of the step's local error estimate (m).
            increment: ‖Δu‖∞ of the step's displacement increment (m).
            size: ‖u‖∞ at the end of the step (m): the ``scale`` of the floor.

        Returns:
            True to accept (then :meth:`accept`); False when ``h`` was halved for a
            retry (the error ratio above 1 and a smaller step left).
        """
        scale = max(self.scale, size)
        allowed = self.tolerance * (increment + FLOOR * scale)
        self.ratio = 0.0 if error <= 0 else error / allowed if allowed > 0 else math.inf
        if self.ratio <= 1.0 or self.halvings >= self.levels:
            self.scale = scale
            return True
        self.rejected += 1
        self.h = 0.5 * self.propose()
        self.halvings += 1
        self.min_dt = min(self.min_dt, self.h)
        self.calm = 0
        return False

    def reject(self) -> bool:
        """The proposed step failed: halve it, unless no cut-back is left.

        Returns:
            True when the step is to be retried with ``h`` halved; False when
            ``max_cutbacks`` halvings are in effect already, or half the step would be
            below ``floor`` (nothing changes).
        """
        trial = self.propose()
        allowed = self.levels if self.adaptive else self.max_cutbacks
        if self.halvings >= allowed or 0.5 * trial < self.floor * (1 - 1e-9):
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
        self.min_dt = min(self.min_dt, trial)  # the last step, shortened onto the end
        _add_exactly(self.partials, trial)
        self.t = self.end_time if last else math.fsum(self.partials)
        if self.adaptive:
            return self._adapt()
        self.streak += 1
        if self.halvings > 0 and self.streak >= GROW_AFTER:
            self.halvings -= 1
            self.h = min(2.0 * self.h, self.dt)
            self.streak = 0
            return True
        return False

    def _adapt(self) -> bool:
        """Adaptive steps: double ``h`` after calm steps (never above ``dt``)."""
        self.calm = self.calm + 1 if self.ratio < GROW_BELOW else 0
        if self.halvings > 0 and self.calm >= CALM_STEPS:
            self.halvings -= 1
            self.h = self.dt / 2**self.halvings
            self.calm = 0
            return True
        return False
