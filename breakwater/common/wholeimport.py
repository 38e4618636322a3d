"""Imports that an interrupt cannot cut in half (a notebook's kernel goes on after it).

A KeyboardInterrupt while a package is imported leaves the submodules it had loaded in
``sys.modules`` and the package itself out: each later import of the package in the
process meets submodules that its new module object lacks. Measured: a second
interrupt while a study was wrapping up (it imports matplotlib to draw its figures)
left ``AttributeError: module 'matplotlib' has no attribute '_docstring'`` for every
later figure of the kernel, the user's own too, until a restart.
:func:`import_whole` holds SIGINT back until the import is done, then delivers it.
"""

from __future__ import annotations

import importlib
import signal
import sys
import threading
from types import FrameType, ModuleType

__all__ = ["import_whole"]


def import_whole(name: str) -> ModuleType:
    """``importlib.import_module(name)``, with a SIGINT during it delivered after it.

    The signal goes, once the module is whole, to the handler it was meant for: a
    KeyboardInterrupt (Python's default handler), or a run's or a study's stop.
    Outside the main thread, or where SIGINT's handler is not Python's, a plain import.
    """
    if name in sys.modules or threading.current_thread() is not threading.main_thread():
        return importlib.import_module(name)
    caught: list[int] = []

    def hold(signum: int, frame: FrameType | None) -> None:
        caught.append(signum)

    previous = signal.getsignal(signal.SIGINT)
    if previous is None:  # set outside Python: it could not be put back
        return importlib.import_module(name)
    signal.signal(signal.SIGINT, hold)
    try:
        return importlib.import_module(name)
    finally:
        signal.signal(signal.SIGINT, previous)
        if caught:
            signal.raise_signal(signal.SIGINT)
