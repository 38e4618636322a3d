"""The arguments of :func:`breakwater.studies.sweep.run_study` given from Python, checked.

A notebook's natural first call, ``run_study("study.toml")``, failed inside the study
with ``AttributeError: 'str' object has no attribute 'points'``; ``ranks_per_case="2"``
with ``TypeError: '<' not supported between instances of 'str' and 'int'``, a ``comm``
that is not a communicator with an ``AttributeError``. Each is refused here in one line
naming the argument, before the study's folder is made (every rank refuses alike: the
arguments are the same on every rank).
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
from mpi4py import MPI

from breakwater.config.fields import printable, shown
from breakwater.studies.studyfile import Study

__all__ = ["checked_study_arguments"]


def checked_study_arguments(study: Any, out: Any, comm: Any, ranks_per_case: Any,
                            quiet: Any) -> int:
    """``run_study``'s arguments checked; ``ranks_per_case`` as an ``int``.

    Raises:
        TypeError: An argument of another type (one line naming it).
    """
    if isinstance(study, str | os.PathLike):
        raise TypeError("run_study: study: expected a Study, got a path: read it first, "
                        f"run_study(load_study({printable(repr(os.fspath(study)))}), ...)")
    if not isinstance(study, Study):
        raise TypeError("run_study: study: expected a Study (run_study(load_study("
                        f"'study.toml'), ...)), got {shown(study)}")
    if out is not None and not isinstance(out, str | os.PathLike):
        raise TypeError(f"run_study: out: expected a folder as a str or a pathlib.Path "
                        f"(or None: results/<study name>), got {shown(out)}")
    if comm is not None and not isinstance(comm, MPI.Intracomm):
        raise TypeError(f"run_study: comm: expected an MPI communicator (e.g. "
                        f"MPI.COMM_WORLD, or None: every rank), got {shown(comm)}")
    if isinstance(ranks_per_case, bool) or not isinstance(ranks_per_case, int | np.integer):
        raise TypeError(f"run_study: ranks_per_case: expected an integer, "
                        f"got {shown(ranks_per_case)}")
    if not isinstance(quiet, bool | np.bool_):
        raise TypeError(f"run_study: quiet: expected True or False, got {shown(quiet)}")
    return int(ranks_per_case)
