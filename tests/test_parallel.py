"""The rank-0 helpers (breakwater.common.parallel), serially and on several ranks."""

from __future__ import annotations

import pathlib

import pytest
from mpi4py import MPI

from breakwater.common.errors import ConvergenceError
from breakwater.common.parallel import on_every_rank, on_rank_zero, shared_tempdir
from breakwater.outputs.checkpoint import CheckpointError

COMM = MPI.COMM_WORLD


def test_result_of_rank_zero_on_every_rank():
    ranks = []

    def action() -> tuple[int, str]:
        ranks.append(COMM.rank)
        return COMM.rank, "done"

    assert on_rank_zero(COMM, action) == (0, "done")
    assert ranks == ([0] if COMM.rank == 0 else [])


@pytest.mark.parametrize("error", [CheckpointError("no checkpoint in x"),
                                   ValueError("bad value"), Exception("gmsh: no file")])
def test_error_of_rank_zero_on_every_rank(error):
    def action() -> None:
        raise error

    with pytest.raises(type(error)) as info:
        on_rank_zero(COMM, action)
    assert type(info.value) is type(error) and str(info.value) == str(error)
    assert (info.value is error) == (COMM.rank == 0)  # rank 0: the original


def test_error_that_does_not_pickle():
    # ConvergenceError needs three arguments: a copy cannot be made from its args.
    def action() -> None:
        raise ConvergenceError("Newton diverged", -3, 12)

    expected = ConvergenceError if COMM.rank == 0 else RuntimeError
    with pytest.raises(expected, match="Newton diverged"):
        on_rank_zero(COMM, action)


def test_every_rank_does_its_own_work():
    assert on_every_rank(COMM, lambda: COMM.rank) == COMM.rank


@pytest.mark.timeout(60)
def test_an_error_on_one_rank_is_raised_on_every_rank():
    # The last rank fails alone (on 1 rank: rank 0 itself); every rank raises its error
    # and the ranks still line up after it (a collective that follows matches).
    last = COMM.size - 1

    def action() -> int:
        if COMM.rank == last:
            raise CheckpointError("cannot read the checkpoint x: injected")
        return COMM.rank

    with pytest.raises(CheckpointError, match="injected") as info:
        on_every_rank(COMM, action)
    assert str(info.value) == "cannot read the checkpoint x: injected"
    assert COMM.allreduce(1) == COMM.size


@pytest.mark.timeout(120)
def test_a_mesh_file_that_one_rank_does_not_see(shared_dir: pathlib.Path,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    # Whether the mesh file exists is rank 0's answer (rank 0 reads it): a rank that did
    # not see it (a network file system's cached answer) raised "mesh file not found"
    # alone, and rank 0 waited in the mesh's distribution until the time limit.
    from blocks import two_rectangles

    from breakwater.model.mesh import read_mesh

    path = two_rectangles(shared_dir / "blocks.msh", COMM, (1.0, 0.5), (2.0, 0.5), 0.25)
    is_file = pathlib.Path.is_file
    if COMM.rank > 0:
        monkeypatch.setattr(pathlib.Path, "is_file",
                            lambda p: False if p == path else is_file(p))
    data = read_mesh(path, COMM)
    cells = data.mesh.topology.index_map(data.mesh.topology.dim).size_global
    assert cells > 0 and COMM.allreduce(cells, op=MPI.MAX) == cells


def test_shared_tempdir():
    with shared_tempdir(COMM, "breakwater-test-") as folder:
        assert COMM.allgather(str(folder)) == [str(folder)] * COMM.size
        assert folder.is_dir() and folder.name.startswith("breakwater-test-")
        if COMM.rank == 0:
            (folder / "f.txt").write_text("x")
        COMM.barrier()
        assert (folder / "f.txt").read_text() == "x"
    assert not pathlib.Path(folder).exists()


def _free_communicators() -> int:
    """How many more communicators this process can create (MPICH: about 2048 in all)."""
    comms = []
    try:
        while True:
            comms.append(COMM.Dup())
    except MPI.Exception:
        pass
    for c in comms:
        c.Free()
    return len(comms)


def test_a_run_leaves_no_communicator_behind(tmp_path: pathlib.Path) -> None:
    # Every PETSc solver holds MPI communicators, a finite resource of the process
    # (MPICH: 2048 context ids): a study that runs many cases in one process fails
    # once they are used up. The calibration's solver was not destroyed (30 per run,
    # measured); a whole run (calibration, static state, time steps, outputs) must
    # leave the count where it was.
    import gc

    from breakwater.cli import main

    out = COMM.bcast(str(tmp_path), root=0)
    argv = ["run", "--quiet", "--out", out, "--set", "time.end_time=0.0003",
            "--set", "output.figures=false"]
    assert main([*argv, "--set", "time.solver=\"reference\""]) == 0  # the first: caches
    gc.collect()
    before = _free_communicators()
    for solver in ("fast", "reference"):
        assert main([*argv, "--set", f"time.solver=\"{solver}\""]) == 0
    gc.collect()
    assert _free_communicators() == before
