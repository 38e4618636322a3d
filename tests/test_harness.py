"""The test suite's MPI guards (tests/mpi_harness.py), on small generated test files run
by a real ``mpiexec -n 2 python -m pytest -p mpi_harness`` (and serially).

Without the guards, the first file below passes on rank 0 and fails on rank 1 only, and
the second hangs for ever: rank 1 fails before a collective that rank 0 waits in.
"""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys
import time

import pytest
from mpi4py import MPI

COMM = MPI.COMM_WORLD
TESTS = pathlib.Path(__file__).parent
MPIEXEC = pathlib.Path(sys.executable).parent / "mpiexec"

ONE_RANK_FAILS = '''
from mpi4py import MPI
COMM = MPI.COMM_WORLD

def test_fails_on_rank_one():
    COMM.barrier()
    assert COMM.rank == 0, "rank 1 disagrees"

def test_then_every_rank_goes_on():
    assert COMM.allreduce(1) == COMM.size

def test_passes_everywhere():
    COMM.barrier()
'''

STUCK = '''
import time
import pytest
from mpi4py import MPI
COMM = MPI.COMM_WORLD

@pytest.mark.timeout(5)
def test_rank_one_fails_while_rank_zero_waits():
    if COMM.rank == 1:
        assert False, "rank 1 gives up before the barrier"
    while True:  # rank 0 waits for a message that never comes
        time.sleep(0.01)

def test_never_reached():
    pass
'''

HANG = '''
import time
import pytest

@pytest.mark.timeout(3)
def test_hangs():
    time.sleep(1000)

def test_never_reached():
    pass
'''


def _pytest(folder: pathlib.Path, name: str, text: str, ranks: int,
            timeout: float) -> tuple[subprocess.CompletedProcess, float]:
    (folder / f"test_{name}.py").write_text(text)
    command = [sys.executable, "-m", "pytest", "-p", "mpi_harness", "-p", "no:cacheprovider",
               "-q", str(folder / f"test_{name}.py")]
    if ranks > 1:
        command = [str(MPIEXEC), "-n", str(ranks), *command]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(TESTS), *filter(None, [os.environ.get("PYTHONPATH")])])}
    start = time.perf_counter()
    result = subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                            cwd=folder, env=env)
    return result, time.perf_counter() - start


@pytest.mark.serial
def test_a_failure_on_one_rank_fails_on_every_rank(tmp_path: pathlib.Path) -> None:
    if COMM.size > 1:
        pytest.skip("runs mpiexec itself")
    result, _ = _pytest(tmp_path, "one_rank", ONE_RANK_FAILS, 2, timeout=120)
    out = result.stdout
    assert result.returncode == 1, out + result.stderr
    # rank 0 passed the first test itself, and reports it failed on rank 1
    assert "1 failed, 2 passed" in out, out
    assert "failed on rank(s) 1" in out, out
    # rank 1's own report names its assertion
    assert "[rank 1] FAILED" in result.stderr and "rank 1 disagrees" in result.stderr


@pytest.mark.serial
def test_a_rank_left_waiting_stops_the_suite(tmp_path: pathlib.Path) -> None:
    if COMM.size > 1:
        pytest.skip("runs mpiexec itself")
    # The limit is 5 s: the whole run (two interpreters starting) ends well within 60 s,
    # where the unguarded suite waits forever.
    result, seconds = _pytest(tmp_path, "stuck", STUCK, 2, timeout=60)
    assert result.returncode != 0
    assert "time limit of 5 s exceeded" in result.stderr, result.stderr
    assert "test_rank_one_fails_while_rank_zero_waits" in result.stderr
    # the failure that left rank 0 waiting is shown (rank 1's report came only after
    # the agreement, which never ended: a hang of the suite named no cause)
    assert "[rank 1] FAILED" in result.stderr, result.stderr
    assert "rank 1 gives up before the barrier" in result.stderr, result.stderr
    assert "passed" not in result.stdout  # test_never_reached did not run
    assert seconds < 60


@pytest.mark.serial
def test_a_hang_is_stopped_serially(tmp_path: pathlib.Path) -> None:
    if COMM.size > 1:
        pytest.skip("runs a pytest subprocess")
    result, seconds = _pytest(tmp_path, "hang", HANG, 1, timeout=60)
    assert result.returncode != 0
    assert "test_hangs: time limit of 3 s exceeded" in result.stderr, result.stderr
    assert 'test_hang.py", line 7 in test_hangs' in result.stderr  # where it hung
    assert "passed" not in result.stdout
    assert seconds < 60
