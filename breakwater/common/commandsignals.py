"""SIGTERM and SIGINT outside a run's time steps: one line and exit status 1, every rank.

A run catches SIGTERM and SIGINT from the start of its case's build to its end
(:class:`~breakwater.common.console.StopSignal`: it stops at the next step boundary,
with a checkpoint). Before that (the case read, the output folder checked) and in the
commands that have no time steps (``calibrate``, ``mesh``), the signals met whatever
handler was in place: PETSc's own, installed when petsc4py is first imported, caught
SIGTERM and ended the process with seven lines of ``PETSC ERROR: Caught signal number 15
Terminate`` and ``MPI_Abort`` (exit status 15; measured 1.5 and 2.5 s after a ``run``
started, a batch system's ``scancel`` or time limit), and before that import the
process died without a word (exit status 143).

:func:`signals_end_the_command` puts one handler in their place for the whole command:
serially it raises :class:`~breakwater.common.errors.Interrupted` (the command line
prints ``breakwater: error: interrupted by SIGTERM`` and exits with status 1, the
``finally`` blocks run: temporary folders, folder locks; a second signal kills the
process at once); on several ranks rank 0 prints that line and every rank aborts the
job (``MPI_Abort``), as PETSc's handler did, since a rank raising where another waits
in a collective would leave that one waiting for good. A run's StopSignal nests
inside it and gives it back on exit.
"""

from __future__ import annotations

import contextlib
import importlib.util
import signal
import sys
import threading
import time
from collections.abc import Iterator
from types import FrameType

from mpi4py import MPI

from breakwater.common.errors import Interrupted

__all__ = ["ABORT_DELAY", "EXIT_STATUS", "SIGNALS", "signals_end_the_command"]

SIGNALS = (signal.SIGTERM, signal.SIGINT)
"""The signals that end a command."""

ABORT_DELAY = 0.5
"""Seconds the other ranks give rank 0 to print its line before they abort (s)."""

EXIT_STATUS = 1
"""The exit status of a command a signal ended (the command line's for a failed run)."""


def _handler(comm: MPI.Comm) -> signal.Handlers | object:
    def handle(signum: int, frame: FrameType | None) -> None:
        line = f"interrupted by {signal.Signals(signum).name}"
        # A second signal: killed at once serially; ignored while the ranks abort (the
        # job's launcher passes it to every rank, and an abort may send it again).
        for sig in SIGNALS:
            signal.signal(sig, signal.SIG_IGN if comm.size > 1 else signal.SIG_DFL)
        if comm.size > 1:
            if comm.rank == 0:
                print(f"breakwater: error: {line}", file=sys.stderr, flush=True)
            else:  # rank 0's line first (the abort of any rank ends every rank)
                time.sleep(ABORT_DELAY)
            comm.Abort(EXIT_STATUS)
        raise Interrupted(line)

    return handle


@contextlib.contextmanager
def signals_end_the_command(comm: MPI.Comm) -> Iterator[None]:
    """SIGTERM and SIGINT end the command in one line (the module doc); collective-free.

    PETSc is initialised first (its import installs its own handler of SIGTERM, which
    would replace this one). SIGINT is taken only where Python's default handler has it
    (a background job's ignored SIGINT stays ignored); a handler set by the caller is
    left in place. Outside the main thread nothing is installed.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    if importlib.util.find_spec("petsc4py") is not None:
        import petsc4py.PETSc  # noqa: F401  (PetscInitialize: its signal handlers now)
    handle = _handler(comm)
    previous = {}
    for sig, default in ((signal.SIGTERM, signal.SIG_DFL),
                         (signal.SIGINT, signal.default_int_handler)):
        if signal.getsignal(sig) is default:
            previous[sig] = signal.signal(sig, handle)  # type: ignore[arg-type]
    try:
        yield
    finally:
        for sig, before in previous.items():
            signal.signal(sig, before)
