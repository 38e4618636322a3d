"""One run at a time in an output folder: an exclusive lock held while it runs.

``run`` refuses a folder whose ``summary.json`` names a live process
(:func:`breakwater.common.liveness.check_not_running`), but a run writes that summary
only once its case is meshed and calibrated: a second run started in those seconds (a
3D case: minutes) passed the check, and both ran to "finished" in one folder, each
clearing and writing the other's files (measured: two runs started one second apart).
:func:`holding` closes that window: rank 0 takes an exclusive ``flock`` on
``<folder>/.breakwater.lock`` (non-blocking) before the case is built and keeps it to
the end; a second run is refused in one line naming the process that holds it (written
in the file). The kernel releases the lock when the process ends, however it ends
(SIGKILL included), so a killed run leaves no stale lock. On a file system without
``flock`` (some network file systems) nothing is locked and the summary's check alone
remains.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import json
import os
import pathlib
from collections.abc import Iterator
from typing import TYPE_CHECKING

from breakwater.common.errors import CaseError
from breakwater.common.files import writing
from breakwater.common.liveness import describe, this_process
from breakwater.common.parallel import on_rank_zero

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["LOCK", "holding"]

LOCK = ".breakwater.lock"
"""The lock file's name in the output folder (removed when the run ends)."""

_HELD: dict[pathlib.Path, list[int]] = {}
"""The folders this process holds: the lock file's descriptor and the holders' count
(a run inside a command that holds the folder already takes it again)."""


def _holder(fd: int) -> str:
    """Who holds the lock, from the file (``pid 1234 on host node7, started ...``)."""
    try:
        data = json.loads(os.pread(fd, 4096, 0).decode("utf-8") or "{}")
    except (OSError, ValueError):
        data = None
    return describe(data) if isinstance(data, dict) and data else "another process"


def _acquire(directory: pathlib.Path, where: str) -> bool:
    """Take the folder's lock (rank 0); whether it was created here.

    Raises:
        CaseError: Another process holds it.
        OutputError: The folder or the lock file cannot be created.
    """
    if directory in _HELD:
        _HELD[directory][1] += 1
        return False
    created = not directory.is_dir()
    path = directory / LOCK
    with writing(directory):
        directory.mkdir(parents=True, exist_ok=True)
    while True:
        with writing(path):
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as e:
            held = e.errno in (errno.EWOULDBLOCK, errno.EAGAIN)
            who = _holder(fd) if held else ""
            os.close(fd)
            if held:
                raise CaseError(f"{where} {directory}: a run is going on in this folder "
                                f"({who}): wait for it, stop it, or choose another "
                                "folder") from None
            return created  # no flock here (ENOLCK, EOPNOTSUPP): not locked
        try:  # the file locked is still the folder's (not one its holder removed)
            same = os.stat(path).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    os.ftruncate(fd, 0)
    os.pwrite(fd, json.dumps(this_process()).encode("utf-8"), 0)
    _HELD[directory] = [fd, 1]
    return created


def _release(directory: pathlib.Path, created: bool) -> None:
    """Give the lock back (rank 0): the file removed, then the folder if left empty."""
    held = _HELD.get(directory)
    if held is None:
        return
    held[1] -= 1
    if held[1] > 0:
        return
    del _HELD[directory]
    with contextlib.suppress(OSError):
        (directory / LOCK).unlink()  # before unlocking: a waiter re-checks the inode
    os.close(held[0])
    if created:  # the case failed before writing anything: no empty folder left
        with contextlib.suppress(OSError):
            directory.rmdir()


@contextlib.contextmanager
def holding(directory: str | pathlib.Path, comm: MPI.Comm, where: str = "output.directory"
            ) -> Iterator[pathlib.Path]:
    """Hold the output folder's lock for the block (collective; rank 0 locks).

    Args:
        directory: The output folder (created when missing; removed again at the end
            when it was created here and is left empty).
        comm: The ranks of the run.
        where: How a refusal names the folder (``--out``, ``output.directory``).

    Yields:
        The folder's absolute path.

    Raises:
        CaseError: Another process runs in the folder (on every rank).
    """
    folder = pathlib.Path(directory).resolve()
    created = on_rank_zero(comm, lambda: _acquire(folder, where))
    try:
        yield folder
    finally:
        on_rank_zero(comm, lambda: _release(folder, created))
