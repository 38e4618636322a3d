"""SIGTERM and SIGINT: a run and a study stop cleanly, whatever they are doing.

- gmsh replaces the C-level handlers of SIGTERM and SIGINT when it initialises (even
  with ``interruptible=False``) and leaves them on finalising: a SIGTERM while a case
  was meshed or read, or in the second after, killed the process outright. The gmsh
  session of breakwater gives the signals back to Python.
- A study's :class:`~breakwater.common.console.StopSignal` and the one of each run nest: a
  signal caught while a case was being built reached only the study's, and the run
  started afterwards went on to its end.
- Under ``mpiexec``, a group that stops tells the others through the study's shared
  counter: no new case starts.

The process tests run the command line in a subprocess (serially, marked ``serial``),
one of them under a real ``mpiexec -n 2``.
"""

from __future__ import annotations

import csv
import json
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import textwrap
import time

import pytest
from mpi4py import MPI

from breakwater.common.console import StopSignal

COMM = MPI.COMM_WORLD
ROOT = pathlib.Path(__file__).parents[1]

STUDY = '''base = "goda"
[set]
"time.end_time" = {end}
"output.field_interval" = 0
"output.figures" = false
"output.checkpoint_interval" = 1
[grid]
"contact.interface.friction" = {values}
'''


def test_nested_stop_signals_share_the_signal():
    """A StopSignal entered after a signal (a run after its case was built) stops too."""
    # What SIGINT's handler was (Python's default_int_handler, or SIG_IGN in a job
    # started in the background by a non-interactive shell): the StopSignals put it back.
    before = signal.getsignal(signal.SIGINT)
    with StopSignal() as outer:
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(0.05)  # the handler runs between bytecodes of the main thread
        assert outer.received == signal.SIGTERM
        # The second signal would kill: the handler is the default one again, and the
        # inner StopSignal installs none.
        assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL
        with StopSignal() as inner:
            assert inner.received == signal.SIGTERM
            assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL
    with StopSignal() as outer, StopSignal() as inner:  # a signal during the run:
        os.kill(os.getpid(), signal.SIGINT)  # the study sees it too
        time.sleep(0.05)
        assert inner.received == outer.received == signal.SIGINT
    assert signal.getsignal(signal.SIGINT) == before


def test_a_second_sigint_in_an_interactive_session_raises(monkeypatch: pytest.MonkeyPatch):
    """Jupyter's interrupt button is SIGINT: a second press killed the kernel.

    Measured in a Jupyter kernel: interrupts 0.2 s and 0.5 s into a run of the Goda case
    (its static state) killed the kernel, and the notebook's state with it. In an
    interactive serial session the second SIGINT now raises KeyboardInterrupt (the run
    writes its outputs as interrupted); elsewhere (the command line, MPI) it still kills.
    """
    # An interactive session's handler (pytest's main thread has it unless a test before
    # left another: on 2 ranks in the whole suite, SIG_DFL), put back after the test.
    monkeypatch.setattr(sys, "ps1", ">>> ", raising=False)  # python -i, IPython alike
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        _second_sigint(monkeypatch)
    finally:
        signal.signal(signal.SIGINT, previous)


def _second_sigint(monkeypatch: pytest.MonkeyPatch) -> None:
    """The body of :func:`test_a_second_sigint_in_an_interactive_session_raises`."""
    before = signal.getsignal(signal.SIGINT)
    assert before is signal.default_int_handler
    serial = COMM.size == 1
    with StopSignal() as outer, StopSignal() as inner:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)
        assert inner.received == outer.received == signal.SIGINT
        second = signal.getsignal(signal.SIGINT)
        assert second is (signal.default_int_handler if serial else signal.SIG_DFL)
        if serial:
            with pytest.raises(KeyboardInterrupt):
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(0.05)
    assert signal.getsignal(signal.SIGINT) is before
    monkeypatch.delattr(sys, "ps1")
    with StopSignal():  # not interactive: a second SIGINT kills, as it did
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)
        assert signal.getsignal(signal.SIGINT) == signal.SIG_DFL
    assert signal.getsignal(signal.SIGINT) is before


def test_stop_signal_polls_the_other_groups():
    """``poll`` (the study's shared counter) stops a StopSignal and the runs inside it."""
    asked = []

    def poll() -> int:
        asked.append(1)
        return int(signal.SIGTERM) if len(asked) > 1 else 0

    with StopSignal(poll=poll) as outer:
        assert outer.received == 0
        outer._polled -= StopSignal.POLL_SECONDS  # a second later
        with StopSignal() as inner:
            assert inner.received == signal.SIGTERM


@pytest.mark.serial
def test_gmsh_leaves_the_signals_to_python():
    """SIGTERM inside and after a gmsh session reaches Python's handler (no kill)."""
    if COMM.size > 1:
        pytest.skip("subprocess test")
    script = textwrap.dedent('''
        import os, signal, time
        import gmsh
        from breakwater.common.gmshtools import gmsh_session
        got = []
        signal.signal(signal.SIGTERM, lambda s, f: got.append(s))
        with gmsh_session():
            gmsh.model.geo.addPoint(0, 0, 0)
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.05)
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(0.05)
        print(len(got))
    ''')
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=60, cwd=ROOT)
    # Without the fix: killed by the first SIGTERM (-15), nothing printed.
    assert done.returncode == 0, done
    assert done.stdout.strip() == "2"


def _statuses(out: pathlib.Path) -> dict[str, str]:
    with open(out / "sweep.csv", newline="") as f:
        return {row["case"]: row["status"] for row in csv.DictReader(f)}


def _sigterm_when_built(command: list[str], out: pathlib.Path, cases: int,
                        timeout: float = 120.0) -> subprocess.CompletedProcess[str]:
    """Start the study; SIGTERM as soon as ``cases`` case folders exist (being built)."""
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, cwd=ROOT)
    start = time.monotonic()
    while time.monotonic() - start < timeout:
        if len(list(out.glob("case-*/sweep_case.json"))) >= cases:
            break
        if proc.poll() is not None:
            break
        time.sleep(0.01)
    proc.send_signal(signal.SIGTERM)
    stdout, stderr = proc.communicate(timeout=timeout)
    return subprocess.CompletedProcess(command, proc.returncode, stdout, stderr)


@pytest.mark.serial
def test_study_stops_on_sigterm_while_a_case_is_built(tmp_path):
    """SIGTERM while the first case is meshed: it stops with its checkpoint, exit 1.

    Before: gmsh's handler killed the study (exit -15, the case left ``running``), or
    the run started after the signal went on to its end and the study went on.
    """
    if COMM.size > 1:
        pytest.skip("subprocess test")
    study = tmp_path / "study.toml"
    study.write_text(STUDY.format(end=0.003, values="[0.5, 0.6, 0.7]"))
    out = tmp_path / "out"
    done = _sigterm_when_built([sys.executable, "-m", "breakwater", "sweep", str(study),
                                "--out", str(out), "--quiet"], out, 1)
    assert done.returncode == 1, done
    assert "interrupted by SIGTERM" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr
    statuses = _statuses(out)
    assert statuses == {"0": "interrupted", "1": "pending", "2": "pending"}, statuses
    first = next(out.glob("case-0000*"))
    record = json.loads((first / "sweep_case.json").read_text())
    assert record["status"] == "interrupted"
    assert json.loads((first / "summary.json").read_text())["status"] == "interrupted"
    assert (first / "checkpoint").exists() or any(first.glob("checkpoint*")), \
        sorted(p.name for p in first.iterdir())
    assert not any(out.glob("case-0001*"))  # no new case started


@pytest.mark.serial
def test_study_stops_every_group_under_mpiexec(tmp_path):
    """``mpiexec -n 2`` with groups of one rank: SIGTERM to the job stops both groups,
    the cases they run are interrupted and no further case starts.

    The signal is sent when two case folders exist. On a busy machine one group may
    already have finished its case and started the next by then (measured beside a
    CPU-heavy process: cases 0 finished, 1 and 2 interrupted, 3 pending), so the test
    checks what must hold whatever the timing: no case is left running or failed, the
    cases running at the signal are interrupted, and at least one case never starts.
    The cases are long (0.03 s, 300 steps) so that finishing one first is unlikely."""
    if COMM.size > 1:
        pytest.skip("subprocess test")
    mpiexec = shutil.which("mpiexec", path=str(pathlib.Path(sys.executable).parent)) \
        or shutil.which("mpiexec")
    if mpiexec is None:
        pytest.skip("no mpiexec")
    study = tmp_path / "study.toml"
    study.write_text(STUDY.format(end=0.03, values="[0.5, 0.6, 0.7, 0.8]"))
    out = tmp_path / "out"
    done = _sigterm_when_built([mpiexec, "-n", "2", sys.executable, "-m", "breakwater",
                                "sweep", str(study), "--out", str(out), "--quiet"], out, 2)
    assert done.returncode != 0, done
    assert "Traceback" not in done.stderr, done.stderr
    statuses = _statuses(out)
    assert set(statuses.values()) <= {"finished", "interrupted", "pending"}, statuses
    interrupted = [k for k, v in statuses.items() if v == "interrupted"]
    pending = [k for k, v in statuses.items() if v == "pending"]
    assert 1 <= len(interrupted) <= 2 and pending, (statuses, done)
    for case in pending:  # never started
        assert not any(out.glob(f"case-{int(case):04d}*")), statuses


@pytest.mark.serial
def test_run_stops_on_sigterm_while_its_case_is_built(tmp_path):
    """``run``: SIGTERM while the case is meshed or calibrated stops it after its static
    state, with a checkpoint (exit 1, ``interrupted``), as a study's case does.

    Before: nothing caught the signal before the time loop; the process died (exit
    -15 here, 143 in a shell), leaving a folder with its mesh only, nothing to resume.
    """
    if COMM.size > 1:
        pytest.skip("subprocess test")
    out = tmp_path / "out"
    command = [sys.executable, "-m", "breakwater", "run", "--out", str(out), "--quiet",
               "--set", "time.end_time=0.003", "--set", "output.field_interval=0",
               "--set", "output.figures=false", "--set", "output.checkpoint_interval=1"]
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, cwd=ROOT)
    start = time.monotonic()
    while not (out / "mesh").exists() and proc.poll() is None:  # meshing has begun
        assert time.monotonic() - start < 120
        time.sleep(0.005)
    proc.send_signal(signal.SIGTERM)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 1, (proc.returncode, stderr)
    assert "interrupted by SIGTERM at t = 0 s" in stderr and "Traceback" not in stderr
    assert json.loads((out / "summary.json").read_text())["status"] == "interrupted"
    assert (out / "checkpoint.npz").exists()


def _package(root: pathlib.Path, name: str) -> None:
    """A package whose import is interrupted half-way (SIGINT sent by its __init__),
    after loading a submodule that a later submodule reads as an attribute (as
    ``matplotlib._docstring`` is read by ``matplotlib.colorizer``)."""
    (root / name).mkdir()
    (root / name / "first.py").write_text("VALUE = 1\n")
    (root / name / "second.py").write_text(f"import {name}\nVALUE = {name}.first.VALUE + 1\n")
    (root / name / "__init__.py").write_text(textwrap.dedent(f'''
        import os, signal, time
        import {name}.first
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)  # the handler runs here, between bytecodes
        import {name}.second
    '''))


def test_an_interrupted_import_is_completed_first(tmp_path: pathlib.Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    """SIGINT during a lazy import (matplotlib's, when a run or a study draws its
    figures) is delivered once the module is whole.

    Measured in one process: a second interrupt while a study wrapped up left
    ``AttributeError: module 'matplotlib' has no attribute '_docstring'`` in every later
    figure, the user's own too: the interrupted import had left ``matplotlib``'s
    submodules in ``sys.modules`` and ``matplotlib`` out.
    """
    import importlib

    from breakwater.common.wholeimport import whole_imports

    name = f"interrupted_{COMM.rank}"
    modules = (name, f"{name}.first", f"{name}.second")
    _package(tmp_path, name)
    monkeypatch.syspath_prepend(str(tmp_path))
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)  # a kernel's
    try:
        with pytest.raises(KeyboardInterrupt), whole_imports():  # the interrupt comes,
            importlib.import_module(name)
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
        assert sys.modules[name].second.VALUE == 2  # once the package is whole
        with StopSignal() as stop:  # a run's handler gets it (no KeyboardInterrupt)
            for module in modules:
                del sys.modules[module]
            with whole_imports():
                assert importlib.import_module(name).second.VALUE == 2
            time.sleep(0.05)
            assert stop.received == signal.SIGINT
    finally:
        signal.signal(signal.SIGINT, previous)
        for module in modules:
            sys.modules.pop(module, None)
