"""A run and its process: a progress bar, rank-0 logging, SIGTERM and SIGINT.

:func:`rank_zero_logging` lets only rank 0 log on a logger while a run goes (set up by
the run itself, not on import, so that importing breakwater changes no logging);
:class:`Progress` draws a tqdm bar in simulated seconds on rank 0; :class:`SlowPhase`
reports a long phase of work (statics, X's solves) as it goes; :class:`StopSignal`
turns SIGTERM and SIGINT into a request to stop at the next step boundary.
"""

from __future__ import annotations

import contextlib
import logging
import math
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

from mpi4py import MPI

__all__ = ["Progress", "SlowPhase", "StopSignal", "rank_zero_logging", "second_sigint_raises",
           "stop_requested"]


class _RankZero(logging.Filter):
    """Let only rank 0 of a communicator log."""

    def __init__(self, comm: MPI.Comm) -> None:
        super().__init__()
        self.rank = comm.rank

    def filter(self, record: logging.LogRecord) -> bool:
        return self.rank == 0


@contextlib.contextmanager
def rank_zero_logging(logger: logging.Logger, comm: MPI.Comm) -> Iterator[None]:
    """Only rank 0 of ``comm`` logs on ``logger`` inside the block.

    The filter is removed on exit; nothing is logged once per rank under MPI.
    """
    rank_zero = _RankZero(comm)
    logger.addFilter(rank_zero)
    try:
        yield
    finally:
        logger.removeFilter(rank_zero)


class Progress:
    """A tqdm bar in simulated seconds on rank 0 (no-op elsewhere or when disabled).

    In a Jupyter notebook (``notebook``), one line of text updated in place instead
    (:class:`~breakwater.common.notebookprogress.NotebookLine`): a tqdm bar there left a
    line per refresh in the saved notebook.

    The bar is drawn on entering the context, not before: log lines written before it
    stay whole. While the bar is shown, log records of the console handlers (of the
    root and ``breakwater`` loggers) are routed through ``tqdm.write``, so that they do
    not break the bar.

    Args:
        end_time: The end of the bar (s).
        enabled: Draw the bar (rank 0 only).
        name: The bar's label.
        start: The time it starts from (s).
        notebook: Draw a notebook's line instead of the bar.

    """

    def __init__(self, end_time: float, enabled: bool, name: str, start: float = 0.0,
                 notebook: bool = False) -> None:
        self.end_time, self.enabled, self.name = end_time, enabled, name
        self.notebook = notebook
        self.bar: Any = None
        self.line: Any = None
        self._redirect: contextlib.AbstractContextManager[None] = contextlib.nullcontext()
        self._t = start

    def __enter__(self) -> Progress:
        if self.enabled and self.notebook:
            from breakwater.common.notebookprogress import NotebookLine

            self.line = NotebookLine(self.name, self.end_time, self._t)
        elif self.enabled:
            from tqdm import tqdm
            from tqdm.contrib.logging import logging_redirect_tqdm

            self._redirect = logging_redirect_tqdm(
                loggers=[logging.getLogger(), logging.getLogger("breakwater")])
            self._redirect.__enter__()
            self.bar = tqdm(total=self.end_time, initial=self._t, desc=self.name, unit="s",
                            file=sys.stderr,
                            bar_format="{desc}: {percentage:3.0f}%|{bar}| t={n:.4g}/"
                                       "{total:.4g} s [{elapsed}<{remaining}{postfix}]")
        return self

    def __exit__(self, *exc: object) -> None:
        if self.line is not None:
            self.line.close()
            self.line = None
        if self.bar is not None:
            self.bar.close()
            self.bar = None
        self._redirect.__exit__(None, None, None)
        self._redirect = contextlib.nullcontext()

    def update(self, t: float, **postfix: Any) -> None:
        """Move the bar to simulated time ``t``."""
        if self.line is not None:
            self.line.update(t, **postfix)
        if self.bar is not None:
            self.bar.update(t - self._t)
            self.bar.set_postfix(postfix, refresh=False)
            self._t = t


class StopSignal:
    """Catches SIGTERM and SIGINT (Ctrl-C): the run stops at the next step boundary.

    The handler only sets a flag (the time loop polls it collectively, so that every
    rank stops at the same step) and restores the default action of both signals, so a
    second SIGTERM or SIGINT kills the process at once (for SIGINT the operating
    system's default, not Python's KeyboardInterrupt). Installed only from the main
    thread. In an interactive serial session (a Jupyter kernel, IPython, ``python -i``)
    whose SIGINT raised KeyboardInterrupt, a second SIGINT raises it again instead
    (:func:`second_sigint_raises`): Jupyter's interrupt button is SIGINT, and a second
    press, while the run reached its next step, killed the kernel and the notebook's
    state with it.

    StopSignals nest (a study's around each of its runs): a signal sets the flag of
    every StopSignal in effect, and one entered after a signal starts with the flag set
    (and installs nothing, so that a second signal still kills). Before, a run entered
    after the study had caught a signal (while its case was being built) started with
    a clear flag and ran to its end.

    Args:
        poll: Also asked by :attr:`received` (at most once a second): a signal number
            when a stop was requested elsewhere (another group of a study), else 0.
        post: Called once with the signal number when this StopSignal, or one nested
            in it, is found to have received one (to tell the others, e.g. the other
            groups of a study).
    """

    SIGNALS = (signal.SIGTERM, signal.SIGINT)
    _active: list[StopSignal] = []  # noqa: RUF012 (the StopSignals in effect, outermost first)
    POLL_SECONDS = 1.0

    def __init__(self, poll: Callable[[], int] | None = None,
                 post: Callable[[int], None] | None = None) -> None:
        self._received = 0
        self._previous: dict[int, Any] = {}
        self._poll, self._post, self._posted = poll, post, False
        self._polled = -math.inf
        self._outer: StopSignal | None = None

    @property
    def received(self) -> int:
        """The signal received (0: none), here or (``poll``) elsewhere."""
        if not self._received and self._poll is not None:
            now = time.monotonic()
            if now - self._polled >= self.POLL_SECONDS:
                self._polled = now
                self._received = self._poll()
        if not self._received and self._outer is not None:
            self._received = self._outer.received
        if self._received:
            outer: StopSignal | None = self
            while outer is not None:
                if outer._post is not None and not outer._posted:
                    outer._posted = True
                    outer._post(self._received)
                outer = outer._outer
        return self._received

    @received.setter
    def received(self, signum: int) -> None:
        self._received = signum

    def _handle(self, signum: int, frame: object) -> None:
        for active in self._active:
            active._received = active._received or signum
        for sig in self.SIGNALS:
            signal.signal(sig, self._second(sig))

    def _second(self, sig: int) -> Any:
        """The action of a second ``sig``: the default one, or KeyboardInterrupt."""
        first = next((s._previous[sig] for s in self._active if sig in s._previous),
                     self._previous.get(sig))
        if sig == signal.SIGINT and first is signal.default_int_handler \
                and second_sigint_raises():
            return signal.default_int_handler
        return signal.SIG_DFL

    def __enter__(self) -> StopSignal:
        self._outer = self._active[-1] if self._active else None
        if self._outer is not None:
            self._received = self._outer.received
        self._active.append(self)
        if not self._received and threading.current_thread() is threading.main_thread():
            for sig in self.SIGNALS:
                self._previous[sig] = signal.signal(sig, self._handle)
        return self

    def __exit__(self, *exc: object) -> None:
        if self in self._active:
            self._active.remove(self)
        outer = self._active[-1] if self._active else None
        for sig, previous in self._previous.items():
            # After a signal, the outer StopSignal's handler stays off: a second kills.
            signal.signal(sig, self._second(sig) if self._received and outer is not None
                          else previous)
        self._previous.clear()
        if outer is not None and self._received:
            outer._received = outer._received or self._received


def stop_requested() -> int:
    """The signal the innermost :class:`StopSignal` in effect received (0: none, or none in effect).

    Local (no poll of other groups): a caller that stops on it asks every rank.
    """
    return StopSignal._active[-1]._received if StopSignal._active else 0


def second_sigint_raises() -> bool:
    """Whether a second SIGINT during a run raises KeyboardInterrupt rather than kill.

    In an interactive session of one process: an IPython shell or Jupyter kernel, or
    Python's own prompt (``python -i``). The run then ends where it is, writing its
    outputs as interrupted, and the session lives on. Under MPI a second SIGINT still
    kills (a KeyboardInterrupt on one rank would leave the others in a collective), as
    it does for the command line.
    """
    ipython = sys.modules.get("IPython")
    shell = getattr(ipython, "get_ipython", lambda: None)() if ipython is not None else None
    interactive = shell is not None or hasattr(sys, "ps1") or bool(sys.flags.interactive)
    return interactive and MPI.COMM_WORLD.size == 1


class SlowPhase:
    """Progress lines of a phase of work that turns out long (statics, X's solves).

    The phase calls itself after each unit of work (a Newton iteration, a calibration
    solve, a chunk of back-solves) with what it did. Nothing is shown while the phase
    is younger than :attr:`AFTER` seconds, so that a phase of a few seconds (every 2D
    case, every step of the reference solver) prints nothing more than before; then a
    line goes to ``info`` at most every :attr:`EVERY` seconds, with the time elapsed: a
    3D case's calibration and static state, minutes of silence otherwise, report how
    far they are.

    Args:
        logger: Where the lines go (under a run: rank 0 only,
            :func:`rank_zero_logging`).
        name: The phase, the start of each line.
        clock: Seconds (monotonic).
        every: Seconds before the first line and between two (default :attr:`AFTER`
            and :attr:`EVERY`).
    """

    #: Seconds of a phase before its lines are shown, and between two of them.
    AFTER = 10.0
    EVERY = 10.0

    def __init__(self, logger: logging.Logger, name: str,
                 clock: Callable[[], float] = time.monotonic,
                 every: float | None = None) -> None:
        self.logger, self.name, self.clock = logger, name, clock
        self.after = self.AFTER if every is None else every
        self.every = self.EVERY if every is None else every
        self.start = clock()
        self._shown: float | None = None  # when the last line was shown

    def due(self) -> bool:
        """Whether a line is shown now (then counted as shown)."""
        now = self.clock()
        if now - self.start < self.after or (
                self._shown is not None and now - self._shown < self.every):
            return False
        self._shown = now
        return True

    @property
    def elapsed(self) -> float:
        """Seconds since the phase started."""
        return self.clock() - self.start

    def __call__(self, message: str, *args: object) -> None:
        """A unit of work done: ``message % args``."""
        if self.due():
            self.logger.info("%s: %s (%.0f s)", self.name, message % args, self.elapsed)
