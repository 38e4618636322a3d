"""PETSc objects freed by Python under MPI (:mod:`breakwater.common.petscfree`).

dolfinx's destructors call ``destroy()`` when Python frees the object: under MPI, at a
moment each rank's garbage collector chooses. When that destroyed the last PETSc object
on a communicator on one rank only, PETSc freed its inner communicator there, and the
next PETSc object on the same communicator made that rank duplicate it
(``MPI_Comm_dup``, collective) while the other went on without: the ranks hung.
"""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys

import pytest
from mpi4py import MPI
from petsc4py import PETSc

from breakwater.common import petscfree

COMM = MPI.COMM_WORLD
MPIEXEC = pathlib.Path(sys.executable).parent / "mpiexec"

# A Function's PETSc view (``x.petsc_vec``) is the only PETSc object on its space's index
# map's communicator; rank 1 frees the Function (its collector got there first), rank 0
# still holds it; then both make a vector on the same space.
ONE_RANK_FREES = '''
import sys
import breakwater
from mpi4py import MPI
import dolfinx
import dolfinx.fem.petsc
from breakwater.common import petscfree
if sys.argv[1] == "installed":
    petscfree.install()
mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 2, 2)
V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1))
if sys.argv[1] == "anchored":
    petscfree.anchor(V.dofmap.index_map.comm)
u = dolfinx.fem.Function(V)
u.x.petsc_vec
if MPI.COMM_WORLD.rank == 1:
    if sys.argv[1] == "anchored":  # destroyed at once on rank 1 only
        u.x.petsc_vec.destroy()
    else:
        del u
b = dolfinx.fem.petsc.create_vector(V)
MPI.COMM_WORLD.barrier()
print("made", flush=True)
'''


@pytest.mark.serial
@pytest.mark.parametrize("guard", ["installed", "anchored"])
def test_a_function_freed_on_one_rank_leaves_the_ranks_in_step(guard: str,
                                                               tmp_path: pathlib.Path) -> None:
    """Without a guard both scripts hang (measured: still waiting after 60 s, rank 0 in
    the vector's layout, rank 1 duplicating the communicator): ``installed``, with
    dolfinx's own destructor; ``anchored``, with the view destroyed on rank 1 only. With
    :func:`petscfree.install` or :func:`petscfree.anchor` they end at once. The time
    limit is far above the two interpreters' start (~5 s)."""
    if COMM.size > 1:
        pytest.skip("runs mpiexec itself")
    script = tmp_path / "one_rank_frees.py"
    script.write_text(ONE_RANK_FREES)
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    result = subprocess.run([str(MPIEXEC), "-n", "2", sys.executable, str(script), guard],
                            capture_output=True, text=True, timeout=120, env=env)
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.count("made") == 2, result.stdout + result.stderr


def test_an_object_is_put_aside_on_more_than_one_process() -> None:
    """On one process the object is destroyed at once; on more, at the release only."""
    alone = PETSc.Vec().createSeq(3, comm=PETSc.COMM_SELF)
    petscfree.put_aside(alone)
    assert not alone.handle
    shared = PETSc.Vec().createMPI((None, 3 * COMM.size), comm=COMM)
    petscfree.put_aside(shared)
    if COMM.size == 1:
        assert not shared.handle
        return
    assert shared.handle  # still alive: other ranks may not have freed theirs
    assert petscfree.release(COMM) >= 1
    assert not shared.handle


def test_dolfinx_destructors_put_aside() -> None:
    """The installed destructor of a Function's values keeps its PETSc view under MPI."""
    import dolfinx

    petscfree.install()
    mesh = dolfinx.mesh.create_unit_square(COMM, 2, 2)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1))
    u = dolfinx.fem.Function(V)
    view = u.x.petsc_vec
    del u
    assert bool(view.handle) == (COMM.size > 1)
    petscfree.release(COMM)
    assert not view.handle


def test_an_anchor_goes_with_its_communicator() -> None:
    """The anchor lives as long as its communicator, and is destroyed at the release
    after the communicator is freed."""
    comm = COMM.Dup()
    petscfree.anchor(comm)
    petscfree.anchor(comm)  # once per communicator
    petscfree.release()
    comm.Free()
    assert petscfree.release() == (1 if COMM.size > 1 else 0)
