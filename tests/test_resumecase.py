"""A calibrated case resumed on another number of ranks (breakwater.run.resumecase).

The calibrated shear modulus of the Goda mound differs in its last digits with the
partition (measured: 2277894.708936863 Pa serially, 2277894.7089616703 Pa on 2 ranks,
1.1e-11 apart, beyond the fingerprint's 12 digits): a serial run resumed on 2 ranks
calibrated again and was refused as another case ("the case differs ... in
bodies.mound.shear_modulus", exit 2). Now the resumed run takes the killed run's
modulus from its folder: here a run of rank 0 alone, killed after its checkpoint, is
resumed by every rank through the command line. On 2 ranks the resume fails without the
fix; on one rank the test checks what holds on any: the modulus is the killed run's
exactly, no calibration solve runs again, the summary keeps the calibration.
"""

from __future__ import annotations

import json
import pathlib
import tomllib

import pytest
from mpi4py import MPI

from breakwater import cli
from breakwater.casefile import build as casebuild
from breakwater.casefile.case import load_case
from breakwater.run import simulation

COMM = MPI.COMM_WORLD
SETTINGS = ["mesh.refinement=0.5", "time.end_time=0.003", "output.checkpoint_interval=10",
            "output.field_interval=0", "output.figures=false"]
KILL_AFTER = 25  # steps: the checkpoint of step 20 is the one resumed


class _Killed(Exception):
    """Stands for a kill: not a BreakwaterError, so run() leaves the checkpoint."""


def test_calibrated_case_resumes_on_another_number_of_ranks(
        shared_dir: pathlib.Path, monkeypatch: pytest.MonkeyPatch) -> None:
    out = shared_dir / "run"
    overrides = [*SETTINGS, f'output.directory="{out}"']
    check = simulation._check_stop

    def killing(r, stop):  # type: ignore[no-untyped-def]
        if r.state.steps >= KILL_AFTER:
            raise _Killed(f"killed at step {r.state.steps}")
        check(r, stop)

    error = None
    if COMM.rank == 0:  # the killed run: rank 0 alone
        try:
            built = load_case(None, overrides).build(MPI.COMM_SELF)
            with monkeypatch.context() as mp:
                mp.setattr(simulation, "_check_stop", killing)
                with pytest.raises(_Killed):
                    simulation.run(built.model, built.time, built.output,
                                   resolved_case=built.case.resolved(),
                                   extra_summary=built.extra, report=False)
        except BaseException as e:  # reported on every rank: none waits forever
            error = repr(e)
    error = COMM.bcast(error, root=0)
    assert error is None, error
    saved = tomllib.loads((out / "case.toml").read_text())["bodies"]["mound"]["shear_modulus"]

    def no_calibration(*args, **kwargs):  # type: ignore[no-untyped-def]
        raise AssertionError("the resumed run calibrated again")

    monkeypatch.setattr(casebuild, "calibrate", no_calibration)
    args = ["run", "--out", str(out), "--resume", "--quiet"]
    for s in SETTINGS:
        args += ["--set", s]
    assert cli.main(args) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "finished"
    assert summary["resumed_from"][0]["mpi_size"] == COMM.size  # the resuming run
    assert summary["resumed_from"][0]["steps"] == 20
    assert summary["calibration"]["shear_modulus"] == saved
    ran = tomllib.loads((out / "case.toml").read_text())["bodies"]["mound"]["shear_modulus"]
    assert ran == saved
