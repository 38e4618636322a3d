"""The loads of a step are evaluated at the step's recorded end, the exact sum of the steps.

The run's time is the exactly rounded sum of the steps
(:class:`breakwater.stepping.stepsize.StepSize`); GN22 evaluated a step's loads at
``t + Δt`` rounded instead, which drifts from it by an ulp: ten steps of 0.5 ms end at
0.005 s, but 0.0045000000000000005 + 0.0005 = 0.005000000000000001, after the end of a
rectangular pulse of 5 ms, whose amplitude there is 0. The run then lost
(1 − β₁) Δt F + β₁ Δt F of the pulse, 10 % of its impulse (measured), which the
prediction before the run (the steps k Δt, ``sampled``) did not know of.
"""

from __future__ import annotations

import pathlib

import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater.casefile.case import load_case
from breakwater.run import simulation
from breakwater.stepping.stepsize import StepSize

COMM = MPI.COMM_WORLD


def test_landing_is_where_accept_puts_the_time() -> None:
    step = StepSize(dt=5e-4, end_time=0.006, max_cutbacks=3)
    while not step.finished:
        step.propose()
        landing = step.landing()
        step.accept()
        assert landing == step.t
    assert step.t == 0.006


@pytest.mark.timeout(300)
def test_rectangular_pulse_ending_on_a_step_end_is_applied_whole(folder: pathlib.Path
                                                                 ) -> None:
    # The Goda case on its coarse mesh, the pendulum's pulse made rectangular over
    # 5 ms, left out of the initial state (its F(0) is then 0), 10 steps of 0.5 ms
    # across it. GN22's momentum rule Σ Δt ((1 − β₁) F(t_n) + β₁ F(t_{n+1})) with
    # F = I/T on (0, T] (closed at T: breakwater.loads.signals.Pulse) gives
    # Δt F (β₁ + 9 + (1 − β₁)) = I exactly, as the summary's prediction
    # (sampled.impulse_ratio = 1); before, 0.9.
    case = load_case(None, ["mesh.refinement=0.7", 'loads.impact.shape="rectangular"',
                            "loads.impact.duration=0.005", "time.dt=5e-4",
                            "time.end_time=0.006", "initial.loads=[]", "output.figures=false",
                            "output.field_interval=0", "output.checkpoint_interval=0",
                            f"output.directory=\"{(folder / 'goda').as_posix()}\""])
    built = case.build(COMM)
    summary = simulation.run(built.model, built.time, built.output,
                             extra_summary=built.extra, report=False)
    impact = summary["loads"]["impact"]
    assert impact["sampled"]["impulse_ratio"] == pytest.approx(1.0, abs=1e-12)
    assert impact["applied"]["impulse_ratio"] == pytest.approx(1.0, abs=1e-12)
