"""The figures' matplotlib settings: matplotlib's defaults, whatever the session set.

The figures are drawn with matplotlib's object API (no pyplot), but the settings they
are drawn with (``matplotlib.rcParams``) are the process's: in a notebook that had
called ``plt.style.use("dark_background")`` a run's ``figures/`` had the style's black
background with the figures' own black lines on it (invisible), its font sizes and
colour cycle; ``rcParams["text.usetex"] = True`` without LaTeX ended a finished run in a
``RuntimeError``. :func:`default_style` draws them with matplotlib's defaults, as the
command line does, and leaves the session's settings as they were.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

__all__ = ["default_style"]


def default_style[**P, R](draw: Callable[P, R]) -> Callable[P, R]:
    """Run ``draw`` with matplotlib's default settings (the session's restored after)."""

    @functools.wraps(draw)
    def drawn(*args: P.args, **kwargs: P.kwargs) -> R:
        from breakwater.common.wholeimport import whole_imports

        with whole_imports():  # when drawing: importing the callers loads no matplotlib
            import matplotlib.style

        with matplotlib.style.context("default"):
            return draw(*args, **kwargs)

    return drawn
