"""The index bookkeeping of the stacked vectors: one Function per body, one vector.

The fast solver (:mod:`breakwater.stepping.condensed`) and the contact forces it sums
(:mod:`breakwater.contact`) address the bodies' unknowns by their global stacked index.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from breakwater.model.model import ContactModel

__all__ = ["MonolithicLayout"]


class MonolithicLayout:
    """Index bookkeeping of the stacked ("mpi" kind) vector of one Function per body.

    On each rank a stacked vector holds ``[body 0 owned, body 1 owned, ...]`` followed by
    the ghosts; its global index is the rank's ownership start plus the owned position.

    Args:
        model: The contact model.
    """

    def __init__(self, model: ContactModel) -> None:
        self.model = model
        self.comm = comm = model.comm
        spaces = [b.V for b in model.bodies]
        self.bs = [V.dofmap.index_map_bs for V in spaces]
        self.sizes = [V.dofmap.index_map.size_local * bs for V, bs in zip(spaces, self.bs,
                                                                          strict=True)]
        self.offsets = np.cumsum([0, *self.sizes])
        self.vec = fem_petsc.create_vector(spaces, kind="mpi")
        self.start = self.vec.getOwnershipRange()[0]
        # Per rank: the stacked start, and each body's owned offset and block range start.
        table = comm.allgather((self.start, list(self.offsets[:-1]),
                                [V.dofmap.index_map.local_range[0] for V in spaces]))
        self._starts = np.array([t[0] for t in table], np.int64)
        self._offsets = np.array([t[1] for t in table], np.int64)  # (ranks, bodies)
        self._ranges = np.array([t[2] for t in table], np.int64)
        # Global stacked index of every local entry (owned and ghost) of every body.
        self.global_index = []
        for i, V in enumerate(spaces):
            imap = V.dofmap.index_map
            n = imap.size_local + imap.num_ghosts
            blocks = imap.local_to_global(np.arange(n, dtype=np.int32))
            self.global_index.append(self.stacked(i, blocks))

    def stacked(self, body: int, blocks: np.ndarray) -> np.ndarray:
        """Global stacked indices of all components of global blocks of a body's space.

        Returns:
            Shape ``(len(blocks) * bs,)``: the components of each block in turn.
        """
        blocks = np.asarray(blocks, np.int64)
        bs = self.bs[body]
        starts = self._ranges[:, body]
        owner = np.searchsorted(starts, blocks, side="right") - 1
        base = self._starts[owner] + self._offsets[owner, body] \
            + (blocks - starts[owner]) * bs
        return (base[:, None] + np.arange(bs)).ravel()

    def assign(self, functions: Sequence[fem.Function], vec: PETSc.Vec) -> None:
        """Copy the owned entries of one Function per body into a stacked vector."""
        self.fill(functions, vec.array)

    def fill(self, functions: Sequence[fem.Function], out: np.ndarray) -> np.ndarray:
        """Copy the owned entries of one Function per body into ``out`` (returned).

        ``out``: the owned part of a stacked vector, or any array of that length.
        """
        for f, lo, hi in zip(functions, self.offsets[:-1], self.offsets[1:], strict=True):
            out[lo:hi] = f.x.array[: hi - lo]
        return out

    def owned_local(self, body: int, dofs: np.ndarray) -> np.ndarray:
        """Positions in the stacked vector's owned array of owned body-local DOFs."""
        return self.offsets[body] + dofs
