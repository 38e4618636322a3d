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

The lock file also keeps :data:`RESERVE` bytes allocated while the run holds the folder:
room for its last ``summary.json`` on a full disk (:func:`write_final_summary` frees it
when that write meets ENOSPC and writes again). Before, a disk with no byte left kept
the summary at ``"status": "running"`` after the run had failed, and a study's table
reported the failed case as running.
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

from breakwater.common import files
from breakwater.common.errors import CaseError, OutputError
from breakwater.common.files import writing
from breakwater.common.liveness import describe, this_process
from breakwater.common.parallel import on_rank_zero

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["LOCK", "RESERVE", "holding", "spend_reserve", "write_final_summary"]

LOCK = ".breakwater.lock"
"""The lock file's name in the output folder (removed when the run ends)."""

RESERVE = 1 << 20
"""Bytes the lock file keeps allocated for the last ``summary.json`` (1 MiB; a summary
takes 5-50 kB, written beside the one it replaces)."""

_HELD: dict[pathlib.Path, list[int]] = {}
"""The folders this process holds: the lock file's descriptor, the holders' count (a
run inside a command that holds the folder already takes it again) and the bytes of the
file's text, or -1 once no room is kept (spent, or none could be allocated)."""


def _holder(fd: int) -> str:
    """Who holds the lock, from the file (``pid 1234 on host node7, started ...``)."""
    try:
        data = json.loads(os.pread(fd, 4096, 0).rstrip(b"\0").decode("utf-8") or "{}")
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
    text = json.dumps(this_process()).encode("utf-8")
    os.pwrite(fd, text, 0)
    try:  # zeros after the text: read back without them (_holder)
        os.posix_fallocate(fd, 0, len(text) + RESERVE)
        kept = len(text)
    except OSError:  # a disk (nearly) full already, or no fallocate: no room kept
        os.ftruncate(fd, len(text))
        kept = -1
    _HELD[directory] = [fd, 1, kept]
    return created


def spend_reserve(directory: str | pathlib.Path) -> bool:
    """Free the room kept in the folder's lock file (rank 0); whether there was any."""
    held = _HELD.get(pathlib.Path(directory).resolve())
    if held is None or held[2] < 0:
        return False
    try:
        os.ftruncate(held[0], held[2])
    except OSError:
        return False
    held[2] = -1
    return True


def write_final_summary(path: pathlib.Path, summary: dict[str, object]) -> None:
    """Write a run's ``summary.json`` that ends it (rank 0), on a full disk as well.

    When the write meets a full disk (ENOSPC, EDQUOT), the room kept in the folder's
    lock file is freed and the summary written again: its status then says how the run
    ended, not ``running``.

    Raises:
        OutputError: The summary cannot be written (no room kept, or another reason).
    """
    try:
        files.atomic_write_json(path, summary)
    except OutputError as e:
        cause = e.__cause__
        if not (isinstance(cause, OSError) and cause.errno in (errno.ENOSPC, errno.EDQUOT)
                and spend_reserve(path.parent)):
            raise
        files.atomic_write_json(path, summary)


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
