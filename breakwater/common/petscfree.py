"""PETSc objects that Python frees: under MPI never destroyed at a moment a rank chose alone.

PETSc keeps an inner communicator for each MPI communicator that has live PETSc objects;
destroying the last of them frees it, and the next object made there duplicates the
communicator again (``MPI_Comm_dup``: collective). dolfinx's destructors call
``destroy()``: ``la.Vector.__del__`` (the PETSc view of a ``Function``'s values, made by
``x.petsc_vec``), ``fem.petsc.LinearProblem`` and ``NonlinearProblem``'s,
``nls.petsc.NewtonSolver``'s. A destructor runs when Python frees the object, which under
MPI is not the same moment on every rank (a cycle freed by the garbage collector, whose
collections follow each process's own allocations). A rank that destroyed the last
object on a communicator duplicated it at its next vector while the other went on into
the vector's own collectives: the 2-rank suite hung (rank 0 in ``MPI_Allgather`` of
``PetscLayoutSetUp``, rank 1 in ``MPI_Comm_dup`` of ``PetscCommDuplicate``) or crashed
with a segmentation fault where the mismatched collectives met, about one run in two on
an empty numba cache (measured on ``tests/test_release.py``). Two lines of petsc4py show
it: a vector destroyed on rank 1 only, then a new one on the same communicator, hangs
(``tests/test_petscfree.py``).

:func:`install` gives those classes a destructor that, on a communicator of more than
one process, only puts the object aside; :func:`release` destroys what was put aside, on
every rank at once, after a full collection (so that every rank has put aside the
same objects): at the end of a run and after each test. On one process the object is
destroyed at once, as dolfinx does.

The same mismatch follows from any object freed at a moment that differs by rank, not
only dolfinx's: a petsc4py wrapper collected on one rank before its parent's
``destroy()`` (which then destroys the object at once there) and after it on the other
(where petsc4py puts it in PETSc's garbage, which keeps the communicator). So each
model also anchors (:func:`anchor`) the communicators of its meshes and spaces: PETSc's inner
communicator then lives as long as the communicator, whatever is freed when.
"""

from __future__ import annotations

import gc
from collections.abc import Callable

from mpi4py import MPI
from petsc4py import PETSc

__all__ = ["anchor", "install", "put_aside", "release"]

#: The PETSc objects of dolfinx's classes that destroy them in ``__del__``.
_OWNED: dict[tuple[str, str], tuple[str, ...]] = {
    ("dolfinx.la", "Vector"): ("_petsc_x",),
    ("dolfinx.fem.petsc", "LinearProblem"): ("_solver", "_A", "_b", "_x", "_P_mat"),
    ("dolfinx.fem.petsc", "NonlinearProblem"): ("_snes", "_A", "_b", "_x", "_P_mat"),
    ("dolfinx.nls.petsc", "NewtonSolver"): ("_A", "_b"),
}

_aside: list[PETSc.Object] = []
_installed = False
_keyval: int | None = None


def put_aside(obj: PETSc.Object | None, aside: list[PETSc.Object] | None = None) -> None:
    """Destroy ``obj`` now on one process; on more, keep it for :func:`release`.

    Args:
        obj: A PETSc object, or None (nothing to do; as one destroyed already, or one
            that PETSc, finalized at the interpreter's exit, has freed).
        aside: Where to keep it (the module's list: a destructor binds it, which the
            interpreter's exit may have cleared from the module).
    """
    if obj is None or not obj.handle or PETSc.Sys.isFinalized():
        return
    if obj.comm.size == 1:
        obj.destroy()
    else:
        (_aside if aside is None else aside).append(obj)


def _destructor(names: tuple[str, ...]) -> Callable[[object], None]:
    """A ``__del__`` that puts aside the PETSc objects held in ``names``.

    ``getattr`` with a default: a constructor interrupted (a notebook's interrupt
    button while the forms compile) leaves some of them unset.
    """
    aside, keep = _aside, put_aside

    def __del__(self: object) -> None:
        for name in names:
            keep(getattr(self, name, None), aside)
    return __del__


def install() -> None:
    """Give dolfinx's PETSc-owning classes the destructor of :func:`put_aside` (once)."""
    global _installed
    if _installed:
        return
    import importlib

    for (module, name), held in _OWNED.items():
        cls = getattr(importlib.import_module(module), name)
        cls.__del__ = _destructor(held)
    _installed = True


def release(comm: MPI.Comm | None = None) -> int:
    """Destroy the objects put aside (collective: every rank at the same point).

    A full collection first, on every rank, frees the cycles one rank's collector had
    not reached yet, so that the ranks destroy the same objects.

    Args:
        comm: Only the objects on communicators of this one's group (those of a run's
            mesh); default: all.

    Returns:
        How many objects were destroyed.
    """
    gc.collect()
    pending = _aside[:]
    del _aside[:]  # (what a collection puts aside from here waits for the next release)
    done = 0
    for obj in pending:
        if not obj.handle:  # destroyed since, through another reference
            continue
        if comm is not None and MPI.Comm.Compare(obj.comm.tompi4py(), comm) not in (
                MPI.IDENT, MPI.CONGRUENT):
            _aside.append(obj)
            continue
        obj.destroy()
        done += 1
    return done


def _freed(comm: MPI.Comm, keyval: int, anchor: PETSc.Object) -> None:
    """MPI's call as a communicator with an anchor is freed: the anchor goes aside.

    Not destroyed here: the last reference to PETSc's inner communicator would make
    PETSc edit the attributes of the communicator being freed.
    """
    _aside.append(anchor)


def anchor(comm: MPI.Comm) -> None:
    """Keep PETSc's inner communicator of ``comm`` for as long as ``comm`` lives (collective).

    An empty PETSc vector on ``comm``, held by an attribute of ``comm`` that MPI lets go
    of when ``comm`` is freed (then destroyed at the next :func:`release`). However the
    other PETSc objects on ``comm`` are freed (destroyed, put aside, or left to a
    collection that reached them on one rank first, while a parent object's ``destroy()``
    freed them at once on the other), PETSc's inner communicator stays: a new object on
    ``comm`` never duplicates it on one rank alone.
    """
    global _keyval
    if comm.size == 1:
        return
    if _keyval is None:
        _keyval = MPI.Comm.Create_keyval(delete_fn=_freed)
    if comm.Get_attr(_keyval) is None:
        comm.Set_attr(_keyval, PETSc.Vec().create(comm=comm))  # type: ignore[arg-type]
