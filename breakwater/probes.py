"""Point probes: a field of one body evaluated at a point, the same on every rank."""

from __future__ import annotations

from collections.abc import Sequence

import dolfinx
import numpy as np
from dolfinx import fem
from mpi4py import MPI

from .errors import MeshError
from .model import ContactModel


class PointProbe:
    """Evaluate a body's fields at a fixed point of the reference configuration.

    Points on a boundary or an interface are allowed: the field of the named body
    is taken (its trace), so two probes at one interface node, one per body, give
    the slip and opening of the interface there.

    Args:
        model: The contact model.
        body: Name of the body to evaluate.
        point: Coordinates (gdim or 3 values).
        name: Label for outputs.
    """

    def __init__(self, model: ContactModel, body: str, point: Sequence[float],
                 name: str | None = None) -> None:
        self.model = model
        self.body = b = model.body(body)
        self.name = name or f"{body}@{tuple(point)}"
        x = np.zeros(3)
        x[: len(point)] = point
        self.point = x
        msh = b.submesh
        tdim = msh.topology.dim
        owned = np.arange(msh.topology.index_map(tdim).size_local, dtype=np.int32)
        tree = dolfinx.geometry.bb_tree(msh, tdim, entities=owned)
        candidates = dolfinx.geometry.compute_collisions_points(tree, x.reshape(1, 3))
        cells = dolfinx.geometry.compute_colliding_cells(msh, candidates, x.reshape(1, 3))
        local = cells.links(0)
        comm = model.comm
        self.owner = comm.allreduce(comm.rank if len(local) else comm.size, op=MPI.MIN)
        if self.owner == comm.size:
            raise MeshError(f"probe '{self.name}': point {tuple(point)} is not in body "
                            f"'{body}'")
        self._cell = int(local[0]) if len(local) else -1

    def value(self, functions: Sequence[fem.Function] | fem.Function) -> np.ndarray:
        """The value at the point of the body's Function (or of a list, one per body)."""
        f = functions if isinstance(functions, fem.Function) else functions[self.body.index]
        comm = self.model.comm
        out = None
        if comm.rank == self.owner:
            out = f.eval(self.point.reshape(1, 3), np.array([self._cell], np.int32)).ravel()
        return comm.bcast(out, root=self.owner)
