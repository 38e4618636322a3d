"""Whether the process that wrote an output folder is still running.

A run's ``summary.json`` says ``"status": "running"`` from its start; a run killed by
SIGKILL (or the out-of-memory killer, a node lost) cannot change it, so the word stays
there, false, for good. The summary (and a study case's ``sweep_case.json``) therefore
records the writing process, :func:`this_process`: its host, its PID (rank 0's) and
the start time of that PID (Linux ``/proc/<pid>/stat``, so that a PID reused by
another process does not count). :func:`process_state` then tells, on the same host,
whether that process is still there: ``run`` refuses a folder whose run is going on,
and a killed run reads as ``stopped``.
"""

from __future__ import annotations

import datetime
import os
import pathlib
import socket
from collections.abc import Mapping
from typing import Any, Literal

from breakwater.common.errors import CaseError
from breakwater.common.files import SUMMARY, read_json

__all__ = ["STOPPED", "check_not_running", "describe", "process_state", "this_process"]

STOPPED = "stopped"
"""The status a ``running`` folder reads as when its process is gone (killed, crashed)."""


def _start_ticks(pid: int) -> int | None:
    """The start time of process ``pid`` (clock ticks after boot; Linux), or None."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as f:
            stat = f.read()
        return int(stat.rsplit(")", 1)[1].split()[19])  # field 22 (after pid, comm)
    except (OSError, ValueError, IndexError):
        return None


def this_process() -> dict[str, Any]:
    """The running process, as a summary records it: host, PID, start (ticks, UTC)."""
    pid = os.getpid()
    return {"host": socket.gethostname(), "pid": pid, "start_ticks": _start_ticks(pid),
            "started": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")}


def process_state(process: Any) -> Literal["alive", "gone"] | None:
    """Whether the recorded process still runs: ``alive``, ``gone``, or None (unknown).

    Unknown: nothing recorded, or recorded on another host (a cluster's node: it cannot
    be asked from here).
    """
    if not isinstance(process, Mapping) or process.get("host") != socket.gethostname():
        return None
    pid, ticks = process.get("pid"), process.get("start_ticks")
    if not isinstance(pid, int) or isinstance(pid, bool) or pid <= 0:
        return None
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return "gone"
    except PermissionError:  # another user's process of that PID: not ours
        pass
    except OSError:
        return None
    if isinstance(ticks, int) and _start_ticks(pid) not in (None, ticks):
        return "gone"  # the PID is another process's now
    return "alive"


def describe(process: Mapping[str, Any]) -> str:
    """``pid 1234 on host node7, started 2026-11-27T17:30:00+00:00`` for messages."""
    return (f"pid {process.get('pid')} on host {process.get('host')}, started "
            f"{process.get('started')}")


def check_not_running(directory: str | pathlib.Path, where: str) -> None:
    """Refuse an output folder whose run is going on (its process alive on this host).

    A second run (or ``--resume``) would write the same files at the same time. The
    calling process's own run is not refused (it cannot be going on beside this one).

    Raises:
        CaseError: One line naming the folder and the process.
    """
    summary = read_json(pathlib.Path(directory) / SUMMARY)
    if summary is None or summary.get("status") != "running":
        return
    process = summary.get("process")
    # This very process: its run ended by an exception that run() let through (an API
    # caller's; a run's own stop writes its status), not a run going on beside.
    if isinstance(process, Mapping) and process_state(process) == "alive" \
            and process.get("pid") != os.getpid():
        raise CaseError(f"{where} {directory}: a run is going on in this folder "
                        f"({describe(process)}): wait for it, stop it, or choose another "
                        "folder")
