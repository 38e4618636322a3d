"""Test-suite set-up shared by every test file: MPI hygiene and quiet extra ranks."""

from __future__ import annotations

import gc
import pathlib
import sys

import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx when present)


@pytest.hookimpl(trylast=True)
def pytest_configure(config: pytest.Config) -> None:
    """Only rank 0 reports, so nothing is printed twice under mpiexec."""
    if MPI.COMM_WORLD.rank > 0:
        reporter = config.pluginmanager.getplugin("terminalreporter")
        if reporter is not None:
            config.pluginmanager.unregister(reporter)


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    """A failure on a rank other than 0 (whose report is silenced) is shown all the same."""
    if MPI.COMM_WORLD.rank > 0 and report.failed:
        sys.stderr.write(f"\n[rank {MPI.COMM_WORLD.rank}] FAILED {report.nodeid} "
                         f"({report.when})\n{report.longreprtext}\n")


@pytest.fixture(autouse=True)
def _collect_and_sync():
    """Free PETSc objects and line the ranks up after every test."""
    yield
    gc.collect()
    MPI.COMM_WORLD.barrier()


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
