"""The time loop's progress in a Jupyter notebook: one line, updated in place.

A Jupyter kernel's stderr is not a terminal, so the command line's tqdm bar was off
there, and the batch job's heartbeat goes to ``logging``, which a kernel does not show:
a notebook cell running for minutes showed nothing until the final report. A tqdm bar
forced on (``progress=True``) wrote a carriage-return update into the cell's stream
at each refresh, which a saved notebook (nbclient, the documentation build) keeps, one
line per refresh.

:class:`NotebookLine` is one display output (IPython's ``display(..., display_id=True)``)
replaced at most every :attr:`NotebookLine.EVERY` seconds and at the end: the cell, and
the notebook saved, hold one line (``t``, percentage, steps, Newton iterations,
elapsed, time left). :func:`in_kernel` tells a Jupyter kernel from a terminal.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from typing import Any

__all__ = ["NotebookLine", "duration", "in_kernel", "progress_line", "time_left"]


def in_kernel() -> bool:
    """Whether this process is a Jupyter kernel (an IPython shell with a kernel).

    IPython is not imported here: a process that has not imported it is no kernel.
    """
    ipython = sys.modules.get("IPython")
    get = getattr(ipython, "get_ipython", None) if ipython is not None else None
    shell = get() if get is not None else None
    return shell is not None and getattr(shell, "kernel", None) is not None


def duration(seconds: float) -> str:
    """``1 h 02 min``, ``3 min 05 s`` or ``42 s`` (``?`` when unknown)."""
    if not math.isfinite(seconds):
        return "?"
    s = round(seconds)
    if s >= 3600:
        return f"{s // 3600} h {s % 3600 // 60:02d} min"
    if s >= 60:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s} s"


def time_left(elapsed: float, t: float, start: float, end: float) -> float:
    """Seconds left at the rate since ``start`` (simulated seconds per second; inf: none)."""
    return elapsed * (end - t) / (t - start) if t > start else math.inf


def progress_line(name: str, t: float, start: float, end: float, steps: int,
                  iterations: int, elapsed: float, done: bool = False) -> str:
    """The progress line: ``name: 40% |████      | t = 0.02/0.05 s, 200 steps, ...``.

    The time left is the rate in simulated seconds since ``start`` (where the run
    started or resumed) over what remains.
    """
    fraction = min(max(t / end, 0.0), 1.0) if end > 0 else 1.0
    width = 20
    filled = round(width * fraction)
    bar = "█" * filled + " " * (width - filled)
    mean = f"{iterations / steps:.2f}" if steps else "-"
    if done:
        tail = f"{duration(elapsed)} elapsed"
    else:
        left = time_left(elapsed, t, start, end)
        tail = f"{duration(elapsed)} elapsed, about {duration(left)} left"
    return (f"{name}: {100 * fraction:3.0f}% |{bar}| t = {t:.4g}/{end:.4g} s, {steps} steps, "
            f"{mean} Newton iterations per step, {tail}")


class NotebookLine:
    """One progress line in a notebook cell, replaced in place (rank 0 only).

    Args:
        name: The run's name, the start of the line.
        end_time: The run's end time (s).
        start: The time it starts from (s).
        clock: Seconds (monotonic).
        display: IPython's ``display`` (a test may pass its own).
    """

    #: Seconds between two updates of the line.
    EVERY = 1.0

    def __init__(self, name: str, end_time: float, start: float = 0.0,
                 clock: Callable[[], float] = time.monotonic,
                 display: Callable[..., Any] | None = None) -> None:
        if display is None:
            from IPython.display import display as ipython_display

            display = ipython_display
        self.name, self.end, self.start, self.clock = name, end_time, start, clock
        self.t, self.steps, self.iterations = start, 0, 0
        self.began = self._shown = clock()
        self.handle = display({"text/plain": self._text()}, raw=True, display_id=True)

    def _text(self, done: bool = False) -> str:
        return progress_line(self.name, self.t, self.start, self.end, self.steps,
                             self.iterations, self.clock() - self.began, done)

    def update(self, t: float, its: int = 0, **_: Any) -> None:
        """A step reached ``t`` in ``its`` Newton iterations; shown every :attr:`EVERY` s."""
        self.t, self.steps, self.iterations = t, self.steps + 1, self.iterations + its
        now = self.clock()
        if now - self._shown >= self.EVERY:
            self._shown = now
            self.handle.update({"text/plain": self._text()}, raw=True)

    def close(self) -> None:
        """Show the last state, with the time taken."""
        self.handle.update({"text/plain": self._text(done=True)}, raw=True)
