"""Bad inputs that only a run can find, one file each in ``tests/bad_cases/run/``.

A case file there starts with comment lines that say what ``python -m breakwater run``
(or another command) must do with it (the file is run in-process through
:func:`breakwater.cli.main`, serially and under ``mpiexec``):

- ``# expect: PHRASE`` (first line): the phrase the one line on stderr must contain;
- ``# exit: N`` (optional, default 2): 2, refused as an input error, before any step;
  1, a run that fails, with ``summary.json`` saying ``"status": "failed"`` and the same
  one-line reason; 0, a run that finishes with a one-line warning naming the input;
- ``# args: ...`` (optional): more command-line arguments (``--set key=value`` ...);
- ``# command: NAME`` (optional, default ``run``): the command run instead, e.g.
  ``calibrate`` (which writes no output folder: only exit status 2 then).

Files a case reads (meshes, tables) sit beside it; a case names them relative to itself.
"""

from __future__ import annotations

import json
import pathlib
import shlex

import pytest
from mpi4py import MPI

from breakwater import cli

COMM = MPI.COMM_WORLD
RUNS = pathlib.Path(__file__).parent / "bad_cases" / "run"
RUN_FILES = sorted(RUNS.glob("*.toml"))


def header(path: pathlib.Path) -> tuple[str, int, list[str], str]:
    """The expected phrase, exit status, extra arguments and command of a bad run file."""
    lines = path.read_text(encoding="utf-8").splitlines()
    assert lines[0].startswith("# expect: "), path
    phrase, status, args, command = lines[0].removeprefix("# expect: "), 2, [], "run"
    for line in lines[1:]:
        if not line.startswith("#"):
            break
        if line.startswith("# exit: "):
            status = int(line.removeprefix("# exit: "))
        elif line.startswith("# args: "):
            args = shlex.split(line.removeprefix("# args: "))
        elif line.startswith("# command: "):
            command = line.removeprefix("# command: ").strip()
    return phrase, status, args, command


@pytest.mark.parametrize("path", RUN_FILES, ids=lambda p: p.stem)
def test_bad_run(path: pathlib.Path, shared_dir: pathlib.Path,
                 capsys: pytest.CaptureFixture[str]) -> None:
    phrase, status, args, command = header(path)
    out = shared_dir / "out"
    if command == "run":
        args = ["--out", str(out), "--no-progress", *args]
    else:  # no output folder, no summary: refused as an input
        assert status == 2, path
    code = cli.main([command, str(path), "--quiet", *args])
    err = capsys.readouterr().err
    assert code == status, err
    if COMM.rank == 0:
        assert "Traceback" not in err, err
        lines = [line for line in err.splitlines() if phrase in line]
        assert len(lines) == 1, err
        if status == 2:
            assert err.count("\n") == 1, err
            assert lines[0].startswith("breakwater: error: "), err
        if status == 1:
            summary = json.loads((out / "summary.json").read_text())
            assert summary["status"] == "failed", summary
            assert phrase in summary["error"] and "\n" not in summary["error"]
