"""Ranks against cores: the one-line warning of a case whose ranks share cores.

Measured on this 2-core host (Goda case to t = 0.1 s): 3.4 s on one rank, 24.5 to 35 s
on two while other users' processes kept the load average at 5 to 9; four ranks on two
cores are oversubscribed by the run itself. Before, a study or a run said nothing.
"""

from __future__ import annotations

import os
import socket

from mpi4py import MPI

from breakwater.common.cores import HostUsage, core_warning, host_usage

COMM = MPI.COMM_WORLD


def test_core_warning():
    idle = HostUsage("node", ranks=2, cores=2, load=0.5)
    assert core_warning(idle, 2) is None and core_warning(idle, 1) is None
    over = HostUsage("node", ranks=4, cores=2, load=0.5)
    for k in (1, 2):
        assert core_warning(over, k) == (
            "4 ranks on host node, which gives them 2 cores: ranks share cores, and a case "
            "of several ranks waits for its slowest at every exchange (spinning): runs "
            "crawl (5-10x measured); start at most 2 ranks per host")
    busy = HostUsage("node", ranks=2, cores=2, load=5.4)
    fewer = "--ranks-per-case 1"
    assert core_warning(busy, 1, fewer) is None  # one rank per case waits for no other
    assert core_warning(busy, 2) is None  # a run: the load average is not looked at
    assert core_warning(busy, 2, fewer) == (
        "host node is busy (load average 5.4 over the last minute on 2 cores): a case of 2 "
        "ranks waits for its slowest at every exchange while others' processes hold the "
        "cores (5-10x slower measured); one rank per case (--ranks-per-case 1) is faster "
        "then")
    # Two ranks of its own busy over the last minute: a load of 2 to 3 on 2 cores.
    assert core_warning(HostUsage("node", 2, 2, 2.9), 2, fewer) is None


def test_host_usage(monkeypatch):
    """The ranks of this host and the union of their affinities (a scheduler binding
    each rank to one core gives each a single core, the host all of them)."""
    bound = {COMM.rank % (os.cpu_count() or 1)}
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: bound)
    monkeypatch.setattr(os, "getloadavg", lambda: (3.0, 2.0, 1.0))
    usage = host_usage(COMM)
    cores = len({r % (os.cpu_count() or 1) for r in range(COMM.size)})
    assert usage == HostUsage(socket.gethostname(), COMM.size, cores, 3.0)
