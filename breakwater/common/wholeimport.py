"""Imports that an interrupt cannot cut in half (a notebook's kernel goes on after it).

A KeyboardInterrupt while a package is imported leaves the submodules it had loaded in
``sys.modules`` and the package itself out: each later import of the package in the
process meets submodules that its new module object lacks. Measured: a second
interrupt while a study was wrapping up (it imports matplotlib to draw its figures)
left ``AttributeError: module 'matplotlib' has no attribute '_docstring'`` for every
later figure of the kernel, the user's own too, until a restart.
:func:`whole_imports` holds SIGINT back while its block imports, then delivers it.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from types import FrameType

__all__ = ["whole_imports"]


@contextlib.contextmanager
def whole_imports() -> Iterator[None]:
    """Hold SIGINT back inside the block (its lazy imports); deliver it after the block.

    The signal goes, once the modules are whole, to the handler it was meant for: a
    KeyboardInterrupt (Python's default handler), or a run's or a study's stop.
    Outside the main thread, or where SIGINT's handler is not Python's, nothing is held.
    """
    previous = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or previous is None:
        yield  # (a handler set outside Python could not be put back)
        return
    caught: list[int] = []

    def hold(signum: int, frame: FrameType | None) -> None:
        caught.append(signum)

    signal.signal(signal.SIGINT, hold)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if caught:
            signal.raise_signal(signal.SIGINT)
