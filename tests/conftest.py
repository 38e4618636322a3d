"""Test-suite set-up shared by every test file: MPI hygiene and quiet extra ranks."""

from __future__ import annotations

import gc

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


@pytest.fixture(autouse=True)
def _collect_and_sync():
    """Free PETSc objects and line the ranks up after every test."""
    yield
    gc.collect()
    MPI.COMM_WORLD.barrier()
