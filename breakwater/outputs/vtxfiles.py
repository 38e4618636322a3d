"""The VTX (ADIOS2) writers of a run's ParaView files, failing in one line.

ADIOS2 reports a failed write (a full disk, a file-size limit, a quota) as a C++
exception that dolfinx passes on as a ``RuntimeError`` with a coloured, multi-line
text. Worse, a writer whose write or close failed throws again from its C++
destructor, where nothing can catch it: the process aborted (``terminate called after
throwing an instance of 'std::ios_base::failure'``, exit status 134) after the
traceback, leaving ``summary.json`` saying ``running``. :class:`VTXFiles` turns the
failure into :class:`~breakwater.common.errors.OutputError` (``cannot write
<file>: No space left on device``) on every rank and keeps a failed writer alive to the
end of the process (:func:`abandon`), so that its destructor never runs. What the
file holds stays readable up to its last whole time (ADIOS2 indexes a step once it
is written; measured after a full disk and after SIGKILL).
"""

from __future__ import annotations

import ctypes
import logging
import pathlib
import re
import shutil
from collections.abc import Sequence
from typing import Any

import dolfinx
from dolfinx import fem
from mpi4py import MPI

from breakwater.common.errors import OutputError
from breakwater.common.parallel import on_every_rank, on_rank_zero

__all__ = ["VTXFiles", "abandon", "adios_reason"]

log = logging.getLogger("breakwater.run.simulation")  # the run's: rank 0 only

MARGIN = 4e6
"""Bytes left free beside two field writes: the summary, a checkpoint's rows (B)."""

_ABANDONED: list[Any] = []
"""Writers whose C++ object must never be destroyed (see :func:`abandon`)."""


def adios_reason(error: BaseException) -> str:
    """The reason of an ADIOS2 error in a few words (``No space left on device``).

    The operating system's message where the text has one (``errno = 28: ...``), else
    the text without its colour codes, timestamp and tags, on one line.
    """
    text = re.sub(r"\x1b\[[0-9;]*m", "", str(error))
    said = re.search(r"errno = \d+: ([^\n]+)", text)
    if said:
        return said.group(1).strip()
    text = re.sub(r"\[[^\]]*\]|<[^>]*>", " ", text)  # [date] [ADIOS2 EXCEPTION] <Tag>
    return " ".join(text.replace(": iostream error", "").split()).strip(" :") or \
        type(error).__name__


def _size(size: float) -> str:
    """Bytes for a message: ``631 kB``, ``1.27 GB``."""
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if size >= scale:
            return f"{size / scale:.3g} {unit}"
    return f"{size:.0f} bytes"


def abandon(writer: Any) -> None:
    """Keep ``writer``'s C++ object alive until the process ends.

    Its destructor would close the files again and throw from C++ (aborting the
    process); with one more reference than Python will ever release, it is never
    run, not even when the interpreter shuts down. The operating system closes the
    files at exit.
    """
    cpp = getattr(writer, "_cpp_object", writer)
    _ABANDONED.append(cpp)
    ctypes.pythonapi.Py_IncRef(ctypes.py_object(cpp))


class VTXFiles:
    """One VTX writer per file, whose failures are one :class:`OutputError` on every rank.

    Args:
        comm: The communicator of the meshes.
        paths: The files (``.bp`` folders).
        functions: The Functions of each file (one mesh per file).

    Attributes:
        failed: The first failure (``cannot write ...``), or None: once a write
            failed, nothing more is written (the files keep their whole times).
    """

    def __init__(self, comm: MPI.Comm, paths: Sequence[pathlib.Path],
                 functions: Sequence[Sequence[fem.Function]], expected: int = 0) -> None:
        self.comm, self.paths, self.expected = comm, list(paths), expected
        # The mesh is the reference configuration: written once (warp by displacement).
        self.writers = [dolfinx.io.VTXWriter(comm, p, list(f),
                                             mesh_policy=dolfinx.io.VTXMeshPolicy.reuse)
                        for p, f in zip(self.paths, functions, strict=True)]
        self.failed: OutputError | None = None
        self._bad: set[int] = set()  # writers abandoned on this rank
        self._writes = 0  # times written
        self._first = 0  # bytes after the first (rank 0)

    def _each(self, call: str, *args: float) -> None:
        """Call ``write``/``close`` on every writer of this rank; raise the first failure.

        Every writer is called even after one failed (their collectives stay matched
        across the ranks); a writer that failed is abandoned.
        """
        first: OutputError | None = None
        for k, (path, w) in enumerate(zip(self.paths, self.writers, strict=True)):
            if k in self._bad:
                continue
            try:
                getattr(w, call)(*args)
            except RuntimeError as e:
                self._bad.add(k)
                abandon(w)
                first = first or OutputError(f"cannot write {path}: {adios_reason(e)}")
        if first is not None:
            raise first

    def write(self, t: float) -> None:
        """Write every file's Functions at time ``t`` (collective).

        Raises:
            OutputError: A file cannot be written, on every rank (then and after: no
                more writes are tried).
        """
        if self.failed is not None:
            return
        try:
            on_rank_zero(self.comm, self._check_room)
            on_every_rank(self.comm, lambda: self._each("write", t))
        except OutputError as e:
            self.failed = e
            if self.comm.size > 1:  # a file failed on one rank is closed on none
                for k in set().union(*self.comm.allgather(self._bad)) - self._bad:
                    self._bad.add(k)
                    abandon(self.writers[k])
            raise
        self._writes += 1

    def _check_room(self) -> None:
        """Refuse a write that the file system has no room for (rank 0).

        Under MPI, ADIOS2 hangs when a write fails (its ranks wait in ``MPI_Win_free``
        for good: measured on 2 ranks); the run stops before, in one line, with room
        left for its summary. A write takes about the files' mean bytes per write so
        far (the first, with the mesh, is counted as one): twice that and
        :data:`MARGIN` must be free.
        """
        if not self._writes:
            return
        used = sum(f.stat().st_size for p in self.paths if p.is_dir() for f in p.iterdir())
        free = shutil.disk_usage(self.paths[0].parent).free
        if self._writes == 1:
            self._first = used
        elif self._writes == 2:
            self._foresee(used - self._first, free)
        need = 2 * used / self._writes + MARGIN
        if free < need:
            raise OutputError(
                f"cannot write {self.paths[0].parent}: No space left on device "
                f"({_size(free)} free; the ParaView fields take about "
                f"{_size(used / self._writes)} a write: raise output.field_interval "
                "or free space)")

    def _foresee(self, per_write: int, free: int) -> None:
        """Warn (rank 0) when the writes still planned will not fit on the disk.

        Said after the second write (the first holds the mesh): before, a long run
        learned it only when the disk was full, hours in.
        """
        left = self.expected - 2
        if left > 0 and per_write * left > free:
            log.warning("the ParaView fields will take about %s more (%d writes of %s) "
                        "and %s has %s free: the run will stop when it is full (raise "
                        "output.field_interval)", _size(per_write * left), left,
                        _size(per_write), self.paths[0].parent, _size(free))

    def close(self) -> None:
        """Close the files (collective); a failure to close is raised on every rank.

        Raises:
            OutputError: After a failed write, the first failure again, unless it was
                raised then (``failed``): closing does not say it twice.
        """
        if not self.writers:
            return
        try:
            on_every_rank(self.comm, lambda: self._each("close"))
        except OutputError:
            if self.failed is None:
                raise
        finally:
            self.writers = []
