"""A pytest plugin that cannot leave the ranks of an MPI test run in different places
(imported by conftest.py; ``-p mpi_harness`` for another test folder).

Under ``mpiexec`` every rank runs every test, and a test's collectives (barriers,
reductions, PETSc solves) match only while every rank goes through the same ones. A
failure on one rank used to let that rank go on to the next test while the others waited
inside the failed test's next collective: the suite hung until the Makefile's timeout.
Two guards make that impossible:

1. **Agreement.** After each phase of each test (setup, call, teardown) the ranks
   exchange their outcomes on a communicator of the suite's own (:data:`HARNESS`, a
   duplicate of ``COMM_WORLD``: it can never match a collective of the test). A test
   that failed on any rank fails on every rank, with the failing ranks named; every
   rank then goes on to the same next test.
2. **A time limit per test** (:data:`DEFAULT_LIMIT` seconds, or
   ``@pytest.mark.timeout(seconds)``). A rank whose test failed while another rank is
   still inside one of the test's collectives waits for it in the agreement; the limit
   then stops the whole suite on every rank together (``MPI_Abort``), with the test's
   name and every thread's traceback on stderr. A test that hangs on all ranks (a
   deadlock in the code under test) is stopped the same way, serially too.
"""

from __future__ import annotations

import faulthandler
import os
import sys
import threading
import time
from collections.abc import Iterator

import numpy as np
import pytest
from mpi4py import MPI

HARNESS = MPI.COMM_WORLD.Dup()
"""The suite's own communicator, for the ranks' agreement on each test's outcome."""

DEFAULT_LIMIT = 600.0
"""Seconds a test may take, set-up and tear-down included, unless marked otherwise.

The slowest tests take about 60 s serially on an idle machine and up to three times
that under ``mpiexec -n 2`` beside another CPU-heavy process: 600 s stops only a hang.
"""

ABORT_GRACE = 2.0
"""Seconds between a rank's time limit and its abort of the suite."""

PASSED, SKIPPED, FAILED = 0, 1, 2

_CONFIG: list[pytest.Config] = []
"""The session's configuration (its capture manager holds the real stderr)."""

_WAITING: list[pytest.TestReport] = []
"""The report of the phase this rank waits to agree on (its failure, the cause of a hang,
is printed by the time limit: its report would come only after the agreement)."""


@pytest.hookimpl(trylast=True)
def pytest_configure(config: pytest.Config) -> None:
    """Only rank 0 reports, so nothing is printed twice under mpiexec."""
    _CONFIG[:] = [config]
    config.addinivalue_line("markers", "timeout(seconds): the test's time limit "
                            f"(default {DEFAULT_LIMIT:g} s, set-up and tear-down included)")
    if MPI.COMM_WORLD.rank > 0:
        reporter = config.pluginmanager.getplugin("terminalreporter")
        if reporter is not None:
            config.pluginmanager.unregister(reporter)


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    """A failure on a rank other than 0 (whose report is silenced) is shown all the same."""
    if MPI.COMM_WORLD.rank > 0 and report.failed and not getattr(report, "elsewhere", False):
        sys.stderr.write(f"\n[rank {MPI.COMM_WORLD.rank}] FAILED {report.nodeid} "
                         f"({report.when})\n{report.longreprtext}\n")
        sys.stderr.flush()


# --- the time limit -------------------------------------------------------------------

def _limit(item: pytest.Item) -> float:
    marker = item.get_closest_marker("timeout")
    return float(marker.args[0]) if marker is not None else DEFAULT_LIMIT


def _stop(nodeid: str, limit: float) -> None:
    """The time limit is over: say so, show where every thread is, stop every rank."""
    rank = MPI.COMM_WORLD.rank
    captured = ""
    capture = _CONFIG[0].pluginmanager.getplugin("capturemanager") if _CONFIG else None
    if capture is not None:  # write to the real stderr, with what the test printed
        capture.suspend_global_capture(in_=False)
        captured = capture.read_global_capture()[1]
    sys.stderr.write(captured)
    for report in _WAITING:
        if report.failed:  # this rank failed and waited for the others in the agreement
            sys.stderr.write(f"\n[rank {rank}] FAILED {report.nodeid} ({report.when}), "
                             f"then waited for the other ranks:\n{report.longreprtext}\n")
    sys.stderr.write(f"\n[rank {rank}] {nodeid}: time limit of {limit:g} s exceeded "
                     "(a hang, or a rank left waiting in a collective after a failure "
                     "on another rank); stopping the test suite on every rank\n")
    sys.stderr.flush()
    faulthandler.dump_traceback(file=sys.stderr, all_threads=True)
    sys.stderr.flush()
    if MPI.COMM_WORLD.size > 1:
        # The other ranks' limits end at about the same moment: a pause lets them print
        # theirs (a rank waiting in the agreement, its failure) before the abort.
        time.sleep(ABORT_GRACE)
        MPI.COMM_WORLD.Abort(1)
    os._exit(1)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None) -> Iterator[None]:
    """Run each test under its time limit.

    A Python timer stops the suite (:func:`_stop`); faulthandler's own thread, which
    needs no interpreter lock, is the backstop 60 s later for code that never releases
    it.
    """
    limit = _limit(item)
    timer = threading.Timer(limit, _stop, (item.nodeid, limit))
    timer.daemon = True
    timer.start()
    faulthandler.dump_traceback_later(limit + 60.0, exit=True)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()
        timer.cancel()


# --- agreement of the ranks -----------------------------------------------------------

def _state(report: pytest.TestReport) -> int:
    return FAILED if report.failed else SKIPPED if report.skipped else PASSED


POLL = 1e-3
"""The longest pause, in seconds, between two looks at the ranks' exchange.

The rank that came first sleeps, and while it sleeps the exchange does not finish on
the others either (MPI moves it on inside its calls only): a pause is every rank's wait.
With pauses growing to 20 ms, 100 tests where rank 0 takes 30 ms longer than rank 1 ran
in 10.2-10.9 s on 2 ranks, in 7.7-8.1 s at 1 ms (7.8 s at 0.2 ms; measured 2026-11-29, a
loaded machine); a rank waiting for one still inside its test looks 1000 times a second,
a few microseconds each."""


def _allgather(state: int) -> np.ndarray:
    """Every rank's state, without blocking the interpreter: the time limit's timer
    must be able to run while a rank waits here for another still inside the test."""
    send = np.array([state], dtype=np.int32)
    states = np.empty(HARNESS.size, dtype=np.int32)
    request = HARNESS.Iallgather(send, states)
    pause = 1e-4
    while not request.Test():
        time.sleep(pause)
        pause = min(2 * pause, POLL)
    return states


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item,
                              call: pytest.CallInfo[None]) -> Iterator[None]:
    """Under MPI: a phase that failed on any rank fails on every rank.

    A phase skipped on some ranks only (a set-up that skips on one rank) is a failure
    too: the ranks would otherwise run different tests.
    """
    outcome = yield
    if HARNESS.size == 1:
        return
    report: pytest.TestReport = outcome.get_result()
    _WAITING[:] = [report]  # shown by the time limit if the other ranks never come
    states = _allgather(_state(report))
    _WAITING.clear()
    failed = [r for r, s in enumerate(states) if s == FAILED]
    if failed and not report.failed:
        report.outcome = "failed"
        report.longrepr = (f"{item.nodeid} ({report.when}) failed on rank(s) "
                           f"{', '.join(map(str, failed))}: see that rank's report")
        report.elsewhere = True  # type: ignore[attr-defined]
    elif not failed and len(set(states.tolist())) > 1:
        skipped = [r for r, s in enumerate(states) if s == SKIPPED]
        report.outcome = "failed"
        report.longrepr = (f"{item.nodeid} ({report.when}) skipped on rank(s) "
                           f"{', '.join(map(str, skipped))} only: the ranks must run the "
                           "same tests")
