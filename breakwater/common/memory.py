"""The memory a run may still take: what the operating system says each node has left.

Large arrays (the fast solver's X = A⁻¹E, a factorisation for another Δt) are sized
against the memory the node has available *now*, shared by the ranks on that node, so
that a model too large for one way of solving takes another instead of being killed by
the operating system. :func:`available_bytes` reads Linux's ``MemAvailable``;
:func:`fits` asks every node at once (collective, the same answer on every rank).
Where the available memory is unknown (not Linux) everything fits, as before.
"""

from __future__ import annotations

import pathlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["MEMINFO", "available_bytes", "fits"]

MEMINFO = pathlib.Path("/proc/meminfo")


def available_bytes(meminfo: pathlib.Path = MEMINFO) -> float | None:
    """The memory this node can still give without swapping (bytes), or None if unknown.

    Linux's ``MemAvailable`` (free memory plus the page cache and reclaimable memory it
    can drop), read from ``meminfo``.
    """
    try:
        for line in meminfo.read_text().splitlines():
            if line.startswith("MemAvailable:"):
                value, unit = line.split()[1:3]
                return float(value) * {"kB": 1024.0}.get(unit, 1.0)
    except (OSError, ValueError, IndexError):
        return None
    return None


def fits(comm: MPI.Comm, need: float, fraction: float,
         available: float | None = None) -> bool:
    """Whether every node has ``need`` bytes for each of its ranks within ``fraction``.

    Collective: the ranks on a node add up their needs and compare the sum with
    ``fraction`` of the node's available memory; the answer is True only if it is True
    on every node, the same on every rank.

    Args:
        comm: The ranks that will allocate.
        need: Bytes this rank will allocate.
        fraction: The share of the available memory they may take (0 to 1).
        available: The node's available bytes (None: :func:`available_bytes`; a test
            sets it).

    """
    from mpi4py import MPI

    have = available_bytes() if available is None else available
    if comm.size == 1:
        ok = have is None or need <= fraction * have
        return bool(ok)
    node = comm.Split_type(MPI.COMM_TYPE_SHARED)
    try:
        total = node.allreduce(need, op=MPI.SUM)
        have = node.bcast(have, root=0)  # one reading per node
    finally:
        node.Free()
    ok = have is None or total <= fraction * have
    return bool(comm.allreduce(ok, op=MPI.LAND))
