"""Work that one rank does for all: rank 0 acts, every rank gets its result or its error.

Files (meshes, temporary folders, checks of an output folder) are written or read
by rank 0 alone; the other ranks must then go on with the same result, or stop with
the same error, or an MPI run hangs or prints a different message per rank.
:func:`on_rank_zero` is that pattern, once; :func:`shared_tempdir` is a scratch folder
made by rank 0 and seen by every rank.
"""

from __future__ import annotations

import ctypes
import pathlib
import pickle
import shutil
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["on_every_rank", "on_rank_zero", "shared_tempdir"]


def on_rank_zero[T](comm: MPI.Comm, action: Callable[[], T]) -> T:
    """Run ``action`` on rank 0 of ``comm``; every rank returns its result or raises its error.

    Collective: every rank calls it, and the others return only once rank 0 has
    finished. It is not a barrier: rank 0 may return before the others have received
    its result (a file it rewrites next may still be read by them). ``action`` itself
    must not be collective.

    Args:
        comm: MPI communicator.
        action: The work of rank 0 (e.g. writing a file); its result must pickle.

    Returns:
        The result of ``action``, on every rank.

    Raises:
        BaseException: What ``action`` raised, on every rank: rank 0 re-raises the
            original (with its traceback), the others a copy of the same type and
            message (a ``RuntimeError`` naming the type, when the exception does not
            pickle).

    """
    if comm.size == 1:  # nothing to share
        return action()
    if comm.rank == 0:
        try:
            result = action()
        except BaseException as exc:
            comm.bcast((False, _portable(exc)), root=0)
            raise
        comm.bcast((True, result), root=0)
        return result
    ok, payload = comm.bcast(None, root=0)
    if ok:
        return payload  # type: ignore[no-any-return]
    raise _restore(payload)


def on_every_rank[T](comm: MPI.Comm, action: Callable[[], T]) -> T:
    """Run ``action`` on every rank; when it fails on any rank, every rank raises.

    For work each rank must do itself (reading the part of a file it needs, reading a
    case's files) but whose failure one rank could meet alone (a file system that
    answers ranks differently under load, or a file changed between two ranks' reads):
    that rank would raise while the others go on into the next collective and wait
    there for good. Collective (an allgather of the outcome).

    Returns:
        This rank's result of ``action``.

    Raises:
        Exception: The error of the lowest rank that failed, on every rank (a rank that
            failed itself raises it with its own error as the cause).
    """
    try:
        result, failure = action(), None
    except Exception as exc:
        result, failure = None, exc
    if comm.size == 1:
        if failure is not None:
            raise failure
        return result  # type: ignore[return-value]
    outcomes = comm.allgather(None if failure is None else _portable(failure))
    first = next((r for r, o in enumerate(outcomes) if o is not None), None)
    if first is None:
        return result  # type: ignore[return-value]
    if first == comm.rank:
        assert failure is not None
        raise failure
    raise _restore(outcomes[first], first) from failure


def _portable(exc: BaseException) -> tuple[bytes | None, str]:
    """The exception pickled (when it survives a round trip) and its one-line text."""
    text = f"{type(exc).__name__}: {exc}"
    try:
        data = pickle.dumps(exc)
        pickle.loads(data)
    except Exception:  # e.g. an __init__ with more arguments than args holds
        return None, text
    return data, text


def _restore(payload: tuple[bytes | None, str], rank: int = 0) -> BaseException:
    data, text = payload
    if data is None:
        return RuntimeError(f"failed on rank {rank}: {text}")
    exc: BaseException = pickle.loads(data)
    return exc


@contextmanager
def shared_tempdir(comm: MPI.Comm, prefix: str = "breakwater-") -> Iterator[pathlib.Path]:
    """A temporary folder made by rank 0, the same path on every rank; removed on exit.

    Collective on entry and exit: the folder is removed once every rank is done, and
    it is gone on every rank when the block is left.
    """
    folder = pathlib.Path(on_rank_zero(comm, lambda: tempfile.mkdtemp(prefix=prefix)))
    try:
        yield folder
    finally:
        comm.barrier()
        if comm.rank == 0:
            shutil.rmtree(folder, ignore_errors=True)
        comm.barrier()


#: The thread-count setters of the OpenBLAS builds a process may load (PETSc's and
#: basix's plain OpenBLAS, NumPy's scipy-openblas64).
_BLAS_SETTERS = ("openblas_set_num_threads", "scipy_openblas_set_num_threads64_")


def single_threaded_blas(comm: MPI.Comm) -> list[str]:
    """One BLAS thread per rank in every OpenBLAS loaded, when ``comm`` has 2+ ranks.

    Under MPI each rank's multithreaded BLAS (MUMPS' dense kernels, NumPy's products of
    the fast solver's interface matrices) starts as many threads as there are cores,
    and the ranks' threads contend for the same cores. Found through the libraries
    mapped into this process (``/proc/self/maps``, Linux); nothing is done elsewhere.

    Returns:
        The libraries set to one thread.
    """
    if comm.size < 2:
        return []
    done = []
    try:
        with open("/proc/self/maps") as f:
            libs = {line.split()[-1] for line in f if "openblas" in line.lower()}
    except OSError:
        return []
    for lib in sorted(libs):
        try:
            handle = ctypes.CDLL(lib)
        except OSError:
            continue
        for name in _BLAS_SETTERS:
            setter = getattr(handle, name, None)
            if setter is not None:
                setter(ctypes.c_int(1))
                done.append(lib)
                break
    return done
