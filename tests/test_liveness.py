"""A folder's run after SIGKILL: ``running`` is checked against its process.

A run killed by SIGKILL leaves ``summary.json`` saying ``"status": "running"`` for good;
the summary records the process (host, PID, the PID's start time), so that a reader
can tell a run going on from one whose process is gone.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys

import pytest
from mpi4py import MPI

from breakwater import cli
from breakwater.common import liveness
from breakwater.common.errors import CaseError

COMM = MPI.COMM_WORLD


def _gone_pid() -> int:
    """The PID of a process that has ended (and been reaped)."""
    child = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                           capture_output=True, text=True, check=True)
    return int(child.stdout)


def test_process_state():
    me = liveness.this_process()
    assert me["host"] == socket.gethostname() and me["start_ticks"] is not None
    assert liveness.process_state(me) == "alive"
    assert liveness.process_state({**me, "pid": _gone_pid()}) == "gone"
    # The same PID started at another time: another process (a PID reused).
    assert liveness.process_state({**me, "start_ticks": me["start_ticks"] + 1}) == "gone"
    assert liveness.process_state({**me, "host": me["host"] + "-other-node"}) is None
    assert liveness.process_state(None) is None and liveness.process_state({}) is None


def _running(folder, process) -> None:
    if COMM.rank == 0:
        (folder / "summary.json").write_text(json.dumps({"status": "running",
                                                         "process": process}))
    COMM.barrier()


def test_run_refuses_a_folder_whose_run_goes_on(shared_dir, capsys):
    """Before, a second run cleared the folder of a run going on (two runs writing it).

    The run going on is another process (a sleeping child here); the calling process's
    own (an in-process run that an exception ended) is not refused.
    """
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"]) \
        if COMM.rank == 0 else None
    try:
        other = COMM.bcast({**liveness.this_process(), "pid": child.pid,
                            "start_ticks": liveness._start_ticks(child.pid)}
                           if child is not None else None, root=0)
        _running(shared_dir, other)
        assert cli.main(["run", "--out", str(shared_dir), "--quiet"]) == 2
        err = capsys.readouterr().err
        if COMM.rank == 0:
            assert err == (f"breakwater: error: --out {shared_dir}: a run is going on in "
                           f"this folder (pid {other['pid']} on host {other['host']}, "
                           f"started {other['started']}): wait for it, stop it, or choose "
                           "another folder\n")
        assert json.loads((shared_dir / "summary.json").read_text())["process"] == other
    finally:
        if child is not None:
            child.kill()
            child.wait()


def test_a_folder_whose_process_is_gone_is_not_refused(tmp_path):
    gone = {**liveness.this_process(), "pid": _gone_pid()}
    (tmp_path / "summary.json").write_text(json.dumps({"status": "running",
                                                       "process": gone}))
    liveness.check_not_running(tmp_path, "--out")  # no CaseError: resumable, replaceable
    (tmp_path / "summary.json").write_text(json.dumps({"status": "running"}))  # older
    liveness.check_not_running(tmp_path, "--out")
    (tmp_path / "summary.json").write_text(json.dumps(
        {"status": "finished", "process": liveness.this_process()}))
    liveness.check_not_running(tmp_path, "--out")
    (tmp_path / "summary.json").write_text(json.dumps(  # this process's own run
        {"status": "running", "process": liveness.this_process()}))
    liveness.check_not_running(tmp_path, "--out")
    parent = {**liveness.this_process(), "pid": os.getppid(),
              "start_ticks": liveness._start_ticks(os.getppid())}
    (tmp_path / "summary.json").write_text(json.dumps({"status": "running",
                                                       "process": parent}))
    with pytest.raises(CaseError, match="a run is going on in this folder"):
        liveness.check_not_running(tmp_path, "--out")
