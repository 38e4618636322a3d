"""A 3-D general pair's search cannot hang on a diverging iterate (issue 25).

A half cylinder on a block, run through the command line, had its static Newton
diverge (master nodes 8.78 m away in a 0.3 m block); the mortar segmentation of that
iterate made 3.1e5 integration points and 6.1e7 projection candidates, 30–50 s per
search inside compiled code, and SIGTERM waited for it: the run hung. Checked here on
the 3-D patch model (two boxes meshed apart, :func:`tests.test_pair3d._patch`'s):

- an iterate that stretches the master's faces (its nodes moved at random by up to
  8.78 m) is refused before the search, as a ConvergenceError (the step is cut back or
  the relaxation fails in one line), in well under a second;
- non-finite positions likewise;
- a rigid move of 8.78 m (no strain) is a state, not a divergence: searched (nothing
  in contact);
- a stop signal received before a search stops the run there (:class:`Interrupted`),
  not at the next step.
"""

from __future__ import annotations

import pathlib
import signal
import time

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater.common.console import StopSignal
from breakwater.common.errors import ConvergenceError, Interrupted
from breakwater.contact.surfacesearch3d import STRETCH
from breakwater.stepping.gn22 import GN22
from tests.test_pair3d import _patch

COMM = MPI.COMM_WORLD
WILD = 8.78  # m: the diverged iterate's master nodes (in a 0.3 m block)


@pytest.fixture(scope="module")
def pair(folder: pathlib.Path):  # type: ignore[no-untyped-def]
    model = _patch(folder, "upper")
    s = GN22(model, 1e-3)
    yield s.surfaces[0]
    s.destroy()


def test_stretched_iterate_is_refused_fast(pair) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(0)
    u1 = np.zeros(pair.n + 1)  # the interface unknowns and a trailing 0 (Dirichlet)
    free = pair._pm[pair._pm >= 0]
    u1[free] = rng.uniform(-WILD, WILD, free.shape)
    t0 = time.perf_counter()
    with pytest.raises(ConvergenceError, match=r"a diverging iterate \(a master face at .* "
                       rf"stretched ×[0-9.e+]+, beyond ×{STRETCH:g}"):
        pair._normal(u1)
    assert time.perf_counter() - t0 < 1.0  # the check is O(faces); the search was 30-50 s


def test_non_finite_iterate_is_refused(pair) -> None:  # type: ignore[no-untyped-def]
    u1 = np.zeros(pair.n + 1)
    u1[pair._ps[0, 0, 0]] = np.nan
    with pytest.raises(ConvergenceError, match="non-finite positions"):
        pair._normal(u1)


def test_rigid_move_is_searched(pair) -> None:  # type: ignore[no-untyped-def]
    u1 = np.zeros(pair.n + 1)
    y = pair._pm[..., 1]
    u1[y[y >= 0]] = -WILD  # the lower box's top 8.78 m down, undeformed
    p = pair._normal(u1)
    assert len(p["index"]) == 0  # nothing within the search radius


def test_stop_signal_stops_between_searches(pair) -> None:  # type: ignore[no-untyped-def]
    u1 = np.zeros(pair.n + 1)
    u1[:-1] = 1e-7  # a state not cached
    with StopSignal() as stop:
        stop.received = signal.SIGTERM
        with pytest.raises(Interrupted, match="interrupted by SIGTERM during the contact "
                           "search of 'c'"):
            pair._normal(u1)
