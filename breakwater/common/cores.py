"""Ranks against cores: one warning line when the ranks of a case cannot each have a core.

The ranks of a case work in lock step: at every exchange (the Newton iterations'
reductions, the solver's) each waits for the slowest, spinning (MPICH busy-polls). With
more runnable processes than cores on a host, a rank that waits holds a core that the
rank it waits for needs, and a case of several ranks crawls. Measured on a 2-core host
(Goda case to t = 0.1 s, 1000 steps): 3.4 s on one rank, 7.5 s each for two serial runs
side by side, 24.5 to 35 s on two ranks, while other users' processes kept the load
average at 5 to 9 (``--ranks-per-case 2`` of a study: cases 5 to 10 times slower than
on one rank each).

:func:`core_warning` says so in one line, from what :func:`host_usage` measures on each
host (collective): the ranks there, the cores they may use (the union of their
affinities: a scheduler that binds each rank to a core gives each one core), and the
load average over the last minute (a study's cases of several ranks only: it moves with
other users' work).
"""

from __future__ import annotations

import os
import socket
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["HostUsage", "core_warning", "host_usage"]


@dataclass(frozen=True)
class HostUsage:
    """The busiest host of a run: its name, its ranks, their cores, its load average."""

    host: str
    ranks: int
    cores: int
    load: float


def _affinity() -> set[int]:
    if hasattr(os, "sched_getaffinity"):
        return set(os.sched_getaffinity(0))
    return set(range(os.cpu_count() or 1))


def host_usage(comm: MPI.Comm) -> HostUsage:
    """The host with the most ranks per core (collective; the same on every rank)."""
    from mpi4py import MPI

    node = comm.Split_type(MPI.COMM_TYPE_SHARED)
    try:
        cores = set().union(*node.allgather(sorted(_affinity())))
        ranks = node.size
    finally:
        node.Free()
    try:
        load = os.getloadavg()[0]
    except OSError:  # not available: taken as idle
        load = 0.0
    mine = (ranks / max(len(cores), 1), socket.gethostname(), ranks, len(cores), load)
    busiest = max(comm.allgather(mine))
    return HostUsage(busiest[1], busiest[2], busiest[3], busiest[4])


def core_warning(usage: HostUsage, ranks_per_case: int, fewer: str | None = None
                 ) -> str | None:
    """One line when a case's ranks will wait for each other on shared cores, else None.

    Args:
        usage: The busiest host (:func:`host_usage`).
        ranks_per_case: The ranks of each case (a run's: all of them).
        fewer: How to run a case on one rank (a study's ``--ranks-per-case 1``); None:
            the load average is not looked at.

    Returns:
        More ranks than cores on a host: always (a case of one rank shares its core
        too). With ``fewer`` given, a busy host too: its load average over the last
        minute at least one above its cores (one runnable process more than cores,
        though this run's own ranks count in it when they ran in that minute), for
        cases of several ranks, which wait for their slowest. A load average moves with
        other users' work: ``run`` does not give ``fewer`` (its messages stay the same
        from one run to the next).
    """
    h = usage
    if h.ranks > h.cores:
        return (f"{h.ranks} ranks on host {h.host}, which gives them {h.cores} cores: "
                "ranks share cores, and a case of several ranks waits for its slowest at "
                "every exchange (spinning): runs crawl (5-10x measured); start at most "
                f"{h.cores} ranks per host")
    if fewer is not None and ranks_per_case > 1 and h.load >= h.cores + 1:
        return (f"host {h.host} is busy (load average {h.load:.1f} over the last minute on "
                f"{h.cores} cores): a case of {ranks_per_case} ranks waits for its slowest "
                "at every exchange while others' processes hold the cores (5-10x slower "
                f"measured); one rank per case ({fewer}) is faster then")
    return None
