"""The step-size controller of the time loop (breakwater.stepping.stepsize.StepSize).

Sequences of propose / reject / accept with the expected step sizes written out:
halving on a failed step (of the step tried, also when it was the short last one),
doubling back after GROW_AFTER accepted steps (never above the nominal Δt), the
time as the exactly rounded sum of the accepted steps, and the last step landing
exactly on the end time. Plain numbers: exact comparisons.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math

import pytest

from breakwater.common.errors import CaseError
from breakwater.config.runspec import TimeSpec
from breakwater.outputs.quality import PairInputs
from breakwater.run.runstate import RunState
from breakwater.stepping.stepsize import (
    CALM_STEPS,
    GROW_AFTER,
    LOAD_STEPS,
    StepSize,
    error_constant,
    resolved_step,
)

pytestmark = pytest.mark.serial  # arithmetic alone (no MPI): once is enough


def _steps(step: StepSize) -> list[float]:
    """Accept proposals to the end; the steps taken."""
    taken = []
    while not step.finished:
        taken.append(step.propose())
        step.accept()
    return taken


def test_lands_exactly_on_the_end() -> None:
    # 0.35 = 3 × 0.1 + what remains: the last step is the remainder, t the end time.
    step = StepSize(dt=0.1, end_time=0.35, max_cutbacks=3)
    taken = _steps(step)
    assert taken[:3] == [0.1, 0.1, 0.1]
    assert taken[3] == 0.35 - math.fsum([0.1, 0.1, 0.1])
    assert step.t == 0.35 and step.accepted == [0.0, *taken]
    # The summary's smallest step is that last one (it reported Δt: found by a user).
    assert step.min_dt == taken[3]
    # 0.3 - fsum(0.1, 0.1) is 0.1 less 2 ulp: within 1e-9 Δt of Δt, so the last step is
    # Δt itself (no sliver step), and t is the end time, not the sum 0.30000000000000004.
    step = StepSize(dt=0.1, end_time=0.3, max_cutbacks=3)
    assert _steps(step) == [0.1, 0.1, 0.1]
    assert step.t == 0.3 and math.fsum(step.accepted) != 0.3
    # Zero duration: nothing to do.
    assert StepSize(dt=0.1, end_time=0.0, max_cutbacks=0).finished


def test_time_is_the_rounded_sum_of_the_steps() -> None:
    step = StepSize(dt=0.1, end_time=100.0, max_cutbacks=0)
    running = 0.0
    for k in range(1, 500):
        step.accept()
        running += 0.1
        assert step.t == math.fsum([0.1] * k)
    assert running != step.t  # adding the steps one by one drifts


def test_reject_halves_until_no_cutback_is_left() -> None:
    step = StepSize(dt=1.0, end_time=100.0, max_cutbacks=2)
    assert step.propose() == 1.0
    assert step.reject() is True
    assert (step.h, step.halvings, step.cutbacks, step.min_dt, step.streak) == (0.5, 1, 1, 0.5, 0)
    assert step.reject() is True
    assert (step.h, step.halvings, step.cutbacks, step.min_dt) == (0.25, 2, 2, 0.25)
    before = dataclasses.asdict(step)
    assert step.reject() is False  # max_cutbacks halvings in effect: nothing changes
    assert dataclasses.asdict(step) == before
    assert step.t == 0.0 and step.accepted == [0.0]


def test_floor_stops_the_cutbacks() -> None:
    # time.min_dt: no cut-back below the floor, whatever max_cutbacks allows.
    step = StepSize(dt=1.0, end_time=100.0, max_cutbacks=20, floor=0.25)
    assert step.reject() is True and step.h == 0.5
    assert step.reject() is True and step.h == 0.25
    before = dataclasses.asdict(step)
    assert step.reject() is False  # 0.125 < floor: nothing changes
    assert dataclasses.asdict(step) == before
    time = TimeSpec(dt=1e-4, end_time=0.1, max_cutbacks=20, min_dt=2.5e-5)
    assert RunState.start(time).step.floor == 2.5e-5
    assert TimeSpec(dt=1e-4, end_time=0.1).dt_floor == 0.0  # max_cutbacks halvings only


def test_limits_of_the_time_settings() -> None:
    """Refused: more steps than time.max_steps, more than 20 cut-backs, min_dt > dt."""
    assert TimeSpec(dt=1e-4, end_time=100.0).planned_steps == 1_000_000  # at the limit
    assert TimeSpec(dt=0.1, end_time=0.35).planned_steps == 4  # a short last step
    assert TimeSpec(dt=0.1, end_time=0.3).planned_steps == 3  # 0.3 / 0.1 = 2.9999999999999996
    with pytest.raises(CaseError, match=r"end_time: .* = 1\.5e\+10 steps, above the limit "
                       r"time\.max_steps = 1000000"):
        TimeSpec(dt=1e-11, end_time=0.15)
    assert TimeSpec(dt=1e-11, end_time=0.15, max_steps=2 * 10**10).planned_steps > 1e10
    with pytest.raises(CaseError, match=r"max_cutbacks: must be <= 20 \(got 2000\)"):
        TimeSpec(dt=1e-4, end_time=0.1, max_cutbacks=2000)
    with pytest.raises(CaseError, match=r"min_dt: must be <= dt"):
        TimeSpec(dt=1e-4, end_time=0.1, min_dt=1e-3)


def test_grows_back_after_grow_after_steps() -> None:
    step = StepSize(dt=1.0, end_time=100.0, max_cutbacks=3)
    step.reject()
    step.reject()  # h = 1/4
    grown = [step.accept() for _ in range(2 * GROW_AFTER + 3)]
    # GROW_AFTER steps of 1/4, GROW_AFTER of 1/2, then Δt, never more.
    expected = [0.25] * GROW_AFTER + [0.5] * GROW_AFTER + [1.0] * 3
    assert step.accepted[1:] == expected
    assert grown == ([False] * (GROW_AFTER - 1) + [True]) * 2 + [False] * 3
    assert (step.h, step.halvings, step.cutbacks, step.min_dt) == (1.0, 0, 2, 0.25)
    assert step.t == math.fsum(expected)
    # A failure during the regrowth restarts the count.
    step.reject()
    step.accept()
    step.reject()  # h = 1/4: 2 halvings
    assert [step.accept() for _ in range(GROW_AFTER)] == [False] * (GROW_AFTER - 1) + [True]
    assert (step.h, step.halvings, step.streak) == (0.5, 1, 0)


def test_cutback_of_the_last_step() -> None:
    # The short last step (0.5 of Δt = 1) fails: the retry halves the step tried, not
    # Δt, and the run still ends exactly on the end time.
    step = StepSize(dt=1.0, end_time=2.5, max_cutbacks=1)
    step.accept()
    step.accept()
    assert step.propose() == 0.5
    assert step.reject() is True and step.h == 0.25
    assert _steps(step) == [0.25, 0.25]
    assert step.t == 2.5 and step.min_dt == 0.25


def test_saved_and_restored() -> None:
    # The controller is plain data: through JSON (as a checkpoint holds it) it goes on
    # with the same steps, bit for bit.
    step = StepSize(dt=0.1, end_time=1.234, max_cutbacks=4)
    step.accept()
    step.reject()
    step.accept()
    copy = StepSize(**json.loads(json.dumps(dataclasses.asdict(step))))
    assert copy == step
    assert _steps(copy) == _steps(step) and copy == step and copy.t == 1.234

    # The run state round-trips as a whole; the time settings are the run's own.
    state = RunState.start(TimeSpec(dt=0.1, end_time=1.234, max_cutbacks=4))
    state.step = step
    state.iterations = [3, 4]
    state.contact = [PairInputs("interface", 1e10, 0.25, (1e8, 2e8), 1e-6, 1e-5)]
    data = json.loads(json.dumps(state.as_dict()))
    assert RunState.from_dict(data, TimeSpec(dt=0.1, end_time=1.234, max_cutbacks=4)) == state


def test_invalid_settings() -> None:
    for dt, end, cutbacks in [(0.0, 1.0, 1), (-1.0, 1.0, 1), (0.1, -1.0, 1), (0.1, 1.0, -1)]:
        with pytest.raises(ValueError, match="invalid time settings"):
            StepSize(dt=dt, end_time=end, max_cutbacks=cutbacks)


# --- adaptive steps -----------------------------------------------------------------------


def test_adaptive_error_rejects_and_grows_back() -> None:
    # r = e / (tolerance ‖Δu‖ + floor_u): above 1 the step is retried with half of it;
    # after CALM_STEPS steps in a row with r < GROW_BELOW it doubles, never above dt.
    step = StepSize(dt=1.0, end_time=100.0, max_cutbacks=0, levels=3, tolerance=1e-2)
    assert step.propose() == 1.0
    assert step.judge(error=2e-2, increment=1.0) is False  # r = 2: retry with 1/2
    assert (step.h, step.halvings, step.rejected) == (0.5, 1, 1)
    assert step.judge(error=0.9e-2, increment=1.0) is True  # r = 0.9: accepted
    assert step.accept() is False and step.t == 0.5
    for _ in range(CALM_STEPS - 1):
        assert step.judge(error=1e-4, increment=1.0) and step.accept() is False
    assert step.judge(error=1e-4, increment=1.0) and step.accept() is True
    assert (step.h, step.halvings) == (1.0, 0)
    # Calm steps at dt: no growth beyond it.
    for _ in range(2 * CALM_STEPS):
        assert step.judge(error=0.0, increment=1.0) and step.accept() is False
    assert step.h == 1.0
    # At the smallest step (levels halvings) a large error is accepted.
    for _ in range(3):
        assert step.judge(error=1.0, increment=1.0) is False
    assert step.halvings == 3 and step.judge(error=1.0, increment=1.0) is True
    # A step that does not converge halves too, down to the same smallest step.
    assert step.reject() is False


def test_adaptive_steps_resolve_the_loads() -> None:
    # A pulse of 0.1 s starting at t = 2 inside steps of 1: the step shrinks to at most
    # 1/LOAD_STEPS of each segment it meets before the step that would cross the pulse
    # is taken (the error alone would not see a pulse inside one step).
    step = StepSize(dt=1.0, end_time=6.0, max_cutbacks=0, levels=8, tolerance=1e-2,
                    breakpoints=[2.0, 2.05, 2.1])
    taken = []
    while not step.finished:
        taken.append(step.propose())
        step.judge(error=0.0, increment=1.0)
        step.accept()
    assert step.t == 6.0
    inside = [h for h, t in zip(taken, itertools.accumulate(taken), strict=True)
              if 2.0 < t <= 2.1 + 1e-12]
    assert max(inside) * LOAD_STEPS <= 0.05  # the segments are 0.05 s long
    assert len(inside) >= 2 * LOAD_STEPS
    assert taken[0] == 1.0 and 1.0 in taken[-2:]  # large steps away from the pulse
    # The same rule, alone: the step of a triangular pulse of 0.02 s from dt = 1e-2.
    assert resolved_step(1e-2, 10, (0.0, 0.01, 0.02)) == 1e-2 / 8  # 1.25e-3 <= 0.01/5
    assert resolved_step(1e-2, 2, (0.0, 0.01, 0.02)) == 1e-2 / 4  # no more than levels


def test_adaptive_settings_are_checked() -> None:
    assert TimeSpec(dt=1e-3, end_time=1.0).levels == 0
    spec = TimeSpec(dt=1e-3, end_time=1.0, adaptive=True)
    assert spec.levels == 6 and spec.smallest_dt == 1e-3 / 64
    assert TimeSpec(dt=1e-3, end_time=1.0, adaptive=True, min_dt=1e-4).levels == 3
    with pytest.raises(CaseError, match="tolerance: must be > 0"):
        TimeSpec(dt=1e-3, end_time=1.0, adaptive=True, tolerance=0.0)
    with pytest.raises(CaseError, match="min_dt: adaptive steps: at most 20 halvings"):
        TimeSpec(dt=1e-3, end_time=1.0, adaptive=True, min_dt=1e-12)
    # GN22's error constant: |β₂/2 − 1/6| + |β₁ − ½| (trapezoidal rule: 1/12).
    assert error_constant(0.5, 0.5) == pytest.approx(1 / 12, rel=1e-15)
    assert error_constant(0.6, 0.605) == pytest.approx(0.3025 - 1 / 6 + 0.1, rel=1e-15)


def test_time_is_the_exact_sum_in_constant_time() -> None:
    # t is math.fsum of every accepted step, kept as exact partial sums (not a sum over
    # the list at every step: quadratic in a storm of 10⁵ steps); steps of 0.1, 1e-17 and
    # 1e16 make a naive running sum drift.
    step = StepSize(dt=1.0, end_time=1e30, max_cutbacks=0)
    values = [0.1, 1e-17, 0.3, 1e16, 0.7, -1e16 + 1.0, 1e-17] * 50
    for v in values:
        step.h = v
        step.accept()
    assert step.t == math.fsum(values) and len(step.partials) <= 4
    # A checkpoint written without the partials rebuilds them from the accepted steps.
    data = dataclasses.asdict(step)
    del data["partials"]
    assert StepSize(**data).partials == step.partials


def test_adaptive_steps_land_on_the_breakpoints() -> None:
    # Breakpoints off the grid of the steps dt/2^k (a storm's impulsive peak at
    # t_k + τ₀/2 of a drawn period): each is a step end, to round-off, as the end time
    # is; the steps then go on from it. Without the landing, steps of 1/2^k from 0
    # never meet 2.0123 (measured: the nearest step ends 2.0117 and 2.0156).
    bp = [2.0, 2.0123, 2.0577, 2.1]
    step = StepSize(dt=1.0, end_time=3.0, max_cutbacks=0, levels=8, tolerance=1e-2,
                    breakpoints=bp)
    times = []
    while not step.finished:
        step.propose()
        step.judge(error=0.0, increment=1.0)
        step.accept()
        times.append(step.t)
    for b in bp:
        assert min(abs(t - b) for t in times) <= 1e-15 * b, b
    assert step.t == 3.0
    assert max(h for h in step.accepted) == 1.0  # large steps away from the loads
