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


def _killed_run(out: pathlib.Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A run of rank 0 alone into ``out``, killed after its checkpoint of step 20."""
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


def _no_calibration(*args, **kwargs):  # type: ignore[no-untyped-def]
    raise AssertionError("the resumed run calibrated again")


def test_calibrated_case_resumes_on_another_number_of_ranks(
        shared_dir: pathlib.Path, monkeypatch: pytest.MonkeyPatch) -> None:
    out = shared_dir / "run"
    _killed_run(out, monkeypatch)
    saved = tomllib.loads((out / "case.toml").read_text())["bodies"]["mound"]["shear_modulus"]

    monkeypatch.setattr(casebuild, "calibrate", _no_calibration)
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


@pytest.mark.parametrize("option", ["--resume", "--auto-resume"])
def test_an_edited_case_is_refused_before_calibrating(
        shared_dir: pathlib.Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str], option: str) -> None:
    """The case edited after the kill (μ 0.65 -> 0.5): refused in one line naming the key
    changed, not the calibrated modulus (before: calibrated again, then refused naming
    ``bodies.mound.shear_modulus`` too on another number of ranks, after the
    calibration's solves: minutes in 3D), and nothing in the folder changed."""
    out = shared_dir / "run"
    _killed_run(out, monkeypatch)
    before = (out / "checkpoint.npz").read_bytes(), (out / "case.toml").read_text()
    monkeypatch.setattr(casebuild, "calibrate", _no_calibration)
    args = ["run", "--out", str(out), option, "--quiet",
            "--set", "contact.interface.friction=0.5"]
    for s in SETTINGS:
        args += ["--set", s]
    assert cli.main(args) == 2
    err = capsys.readouterr().err
    if COMM.rank == 0:
        assert err.count("\n") == 1, err
        assert "cannot resume: the case differs" in err
        assert err.rstrip().endswith("in contact.interface.friction (run it without "
                                     "--resume, or into another --out folder)"), err
    assert ((out / "checkpoint.npz").read_bytes(), (out / "case.toml").read_text()) == before
