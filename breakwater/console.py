"""A run and its process: a progress bar, rank-0 logging, SIGTERM and SIGINT.

:func:`rank_zero_logging` lets only rank 0 log on a logger while a run goes (set up by
the run itself, not on import, so that importing breakwater changes no logging);
:class:`Progress` draws a tqdm bar in simulated seconds on rank 0; :class:`StopSignal`
turns SIGTERM and SIGINT into a request to stop at the next step boundary.
"""

from __future__ import annotations

import contextlib
import logging
import signal
import sys
import threading
from collections.abc import Iterator
from typing import Any

from mpi4py import MPI

__all__ = ["Progress", "StopSignal", "rank_zero_logging"]


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

    The bar is drawn on entering the context, not before: log lines written before it
    stay whole. While the bar is shown, log records of the console handlers (of the
    root and ``breakwater`` loggers) are routed through ``tqdm.write``, so that they do
    not break the bar.

    Args:
        end_time: The end of the bar (s).
        enabled: Draw the bar (rank 0 only).
        name: The bar's label.
        start: The time it starts from (s).

    """

    def __init__(self, end_time: float, enabled: bool, name: str, start: float = 0.0
                 ) -> None:
        self.end_time, self.enabled, self.name = end_time, enabled, name
        self.bar: Any = None
        self._redirect: contextlib.AbstractContextManager[None] = contextlib.nullcontext()
        self._t = start

    def __enter__(self) -> Progress:
        if self.enabled:
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
        if self.bar is not None:
            self.bar.close()
            self.bar = None
        self._redirect.__exit__(None, None, None)
        self._redirect = contextlib.nullcontext()

    def update(self, t: float, **postfix: Any) -> None:
        """Move the bar to simulated time ``t``."""
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
    thread.
    """

    SIGNALS = (signal.SIGTERM, signal.SIGINT)

    def __init__(self) -> None:
        self.received = 0
        self._previous: dict[int, Any] = {}

    def _handle(self, signum: int, frame: object) -> None:
        self.received = signum
        for sig in self.SIGNALS:
            signal.signal(sig, signal.SIG_DFL)

    def __enter__(self) -> StopSignal:
        if threading.current_thread() is threading.main_thread():
            for sig in self.SIGNALS:
                self._previous[sig] = signal.signal(sig, self._handle)
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, previous in self._previous.items():
            signal.signal(sig, previous)
        self._previous.clear()
