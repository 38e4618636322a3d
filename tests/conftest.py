"""Test-suite set-up shared by every test file: MPI hygiene, quiet extra ranks, and the
guards of :mod:`mpi_harness` (a failure on one rank fails the test on every rank; a time
limit per test, ``@pytest.mark.timeout(seconds)``)."""

from __future__ import annotations

import gc
import pathlib
import signal

import pytest
from mpi4py import MPI
from mpi_harness import (  # noqa: F401  (the plugin's hooks, registered from here)
    pytest_configure,
    pytest_runtest_logreport,
    pytest_runtest_makereport,
    pytest_runtest_protocol,
)

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx when present)
from breakwater.common import petscfree

petscfree.install()  # the tests' own dolfinx objects too

# --- fixtures -------------------------------------------------------------------------

@pytest.fixture(scope="module", autouse=True)
def _collect_module():
    """Free everything the module's tests and fixtures left, then freeze what stays.

    A full collection examines every object of the process (the imported packages',
    200 000 once the suite is collected: 0.06-0.09 s a time, measured, 0.15 s on a busy
    machine); :func:`_collect_and_sync` examines only the objects created since the
    last freeze. Autouse and module-scoped, this is torn down after the module's other
    fixtures: what they held is collected here.
    """
    gc.unfreeze()
    petscfree.release()
    gc.freeze()
    yield
    gc.unfreeze()
    petscfree.release()
    gc.freeze()


@pytest.fixture(autouse=True)
def _collect_and_sync():
    """Free PETSc objects and line the ranks up after every test.

    The objects alive before the test were frozen (:func:`gc.freeze`): the collection
    examines the test's own, which is where its garbage is (0.06-0.15 s per test less
    than a full collection; a cycle reaching a frozen object is freed at the module's
    end).
    """
    yield
    petscfree.release()  # a collection, then what dolfinx's destructors put aside
    gc.freeze()
    MPI.COMM_WORLD.barrier()


STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@pytest.fixture(autouse=True)
def _signal_handlers_restored():
    """Fail a test that leaves the handler of SIGINT or SIGTERM changed (and put it back).

    A handler left behind changes every later test: a test that leaves SIGINT at the
    default action makes a later Ctrl-C test kill the process instead of stopping a run.
    """
    before = {sig: signal.getsignal(sig) for sig in STOP_SIGNALS}
    yield
    changed = {sig: signal.getsignal(sig) for sig in STOP_SIGNALS
               if signal.getsignal(sig) != before[sig]}
    for sig in changed:
        signal.signal(sig, before[sig])
    assert not changed, ("the test left the signal handlers changed: "
                         + ", ".join(f"{signal.Signals(sig).name} {h!r} (was "
                                     f"{before[sig]!r})" for sig, h in changed.items()))


@pytest.fixture
def shared_dir(tmp_path: pathlib.Path) -> pathlib.Path:
    """A temporary folder of rank 0, the same path on every rank (one per test)."""
    return pathlib.Path(MPI.COMM_WORLD.bcast(str(tmp_path), root=0))


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory,
           request: pytest.FixtureRequest) -> pathlib.Path:
    """A temporary folder of rank 0, the same path on every rank (one per test module)."""
    name = request.module.__name__.rsplit(".", 1)[-1]
    path = str(tmp_path_factory.mktemp(name)) if MPI.COMM_WORLD.rank == 0 else None
    return pathlib.Path(MPI.COMM_WORLD.bcast(path, root=0))
