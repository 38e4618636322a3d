"""SIGTERM and SIGINT outside a run's time steps end a command in one line (exit status 1).

Before, PETSc's own handler (installed when petsc4py is imported) caught a SIGTERM that
came while a case was read or a modulus calibrated: seven lines of ``PETSC ERROR`` and
an ``MPI_Abort``, exit status 15 or 59.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest
from mpi4py import MPI

from breakwater.common.commandsignals import signals_end_the_command
from breakwater.common.errors import Interrupted

COMM = MPI.COMM_WORLD


def test_a_signal_raises_interrupted_and_the_handlers_come_back():
    """On one rank: SIGTERM raises Interrupted, the handlers are the caller's again after."""
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(Interrupted, match=r"^interrupted by SIGTERM$"):
        with signals_end_the_command(MPI.COMM_SELF):
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)  # (the handler raises before this ends)
    assert signal.getsignal(signal.SIGTERM) == before


def test_a_handler_of_the_callers_is_left_in_place():
    """A SIGINT the caller handles itself (or ignores, as a background job) is not taken."""
    caught: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda s, f: caught.append(s))
    try:
        with signals_end_the_command(MPI.COMM_SELF):
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.1)
        assert caught == [signal.SIGINT]
    finally:
        signal.signal(signal.SIGINT, previous)


def _loaded(pid: int, library: str) -> bool:
    try:
        with open(f"/proc/{pid}/maps") as f:
            return library in f.read()
    except OSError:
        return False


@pytest.mark.serial
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/<pid>/maps")
def test_sigterm_while_calibrating_is_one_line():
    """``calibrate`` (no time steps) killed by a batch system: one line, exit status 1.

    The signal is sent once the process has loaded gmsh, which the command imports to
    mesh the case, after PETSc's import (``import breakwater.cli`` loads neither).
    """
    if COMM.size > 1:
        pytest.skip("a subprocess of its own")
    p = subprocess.Popen([sys.executable, "-m", "breakwater", "calibrate", "--set",
                          "mesh.refinement=3"], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    try:
        start = time.monotonic()
        while not _loaded(p.pid, "gmsh") and p.poll() is None:
            assert time.monotonic() - start < 120, "gmsh never loaded"
            time.sleep(0.01)
        p.send_signal(signal.SIGTERM)
        _, err = p.communicate(timeout=120)
    finally:
        p.kill()
    assert p.returncode == 1, (p.returncode, err[-2000:])
    assert err.strip().splitlines()[-1] == "breakwater: error: interrupted by SIGTERM", err
    assert "PETSC ERROR" not in err and "Traceback" not in err
