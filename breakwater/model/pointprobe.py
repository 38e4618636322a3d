"""A body's field at a point of the reference configuration, the same on every rank.

:class:`PointProbe` is the point probe of the outputs
(:mod:`breakwater.outputs.probes`) and the two sides of a conforming pair's probe
(:class:`breakwater.contact.pairstate.ConformingProbe`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import dolfinx
import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater.common.errors import CaseError, MeshError
from breakwater.config.fields import suggest
from breakwater.model.model import ContactModel

__all__ = ["TOUCH", "PointProbe", "check_body", "locate_point"]


TOUCH = 1e-5
"""A point within this fraction of a cell's size outside it, and in no cell, is taken in
that cell: a point on an interface or a boundary, typed or computed to 7–10 digits, lies
a few 1e-11 to 1e-8 m off it, on the other side (a pair probe on a tilted interface
was refused, "not in body", for one side)."""


def _touching(msh: dolfinx.mesh.Mesh, owned: np.ndarray, tree: dolfinx.geometry.BoundingBoxTree,
              x: np.ndarray, comm: MPI.Comm) -> np.ndarray:
    """The cell nearest to x if x lies within :data:`TOUCH` of its size (collective).

    Returns:
        That cell on the rank that owns it (the nearest's, the lowest rank on ties), an
        empty array elsewhere or where no cell is that near.
    """
    tdim = msh.topology.dim
    distance, cell = math.inf, -1
    if len(owned):
        midpoints = dolfinx.geometry.create_midpoint_tree(msh, tdim, owned)
        cell = int(dolfinx.geometry.compute_closest_entity(tree, midpoints, msh,
                                                           x.reshape(1, 3))[0])
        if cell >= 0:
            at = np.array([cell], np.int32)
            d = math.sqrt(float(dolfinx.geometry.squared_distance(msh, tdim, at,
                                                                  x.reshape(1, 3))[0]))
            if d <= TOUCH * float(msh.h(tdim, at)[0]):
                distance = d
    nearest, rank = comm.allreduce((distance, comm.rank), op=MPI.MINLOC)
    return np.array([cell], np.int32) if rank == comm.rank and math.isfinite(nearest) \
        else np.zeros(0, np.int32)


def locate_point(msh: dolfinx.mesh.Mesh, owned: np.ndarray, x: np.ndarray, comm: MPI.Comm
                 ) -> np.ndarray:
    """The cells among ``owned`` (this rank's) that hold the point x (3 values; collective).

    A point within :data:`TOUCH` of a cell's size outside every cell is taken in the
    nearest (:func:`_touching`). Empty on every rank: the point is in none of the cells.
    """
    tdim = msh.topology.dim
    tree = dolfinx.geometry.bb_tree(msh, tdim, entities=owned)
    candidates = dolfinx.geometry.compute_collisions_points(tree, x.reshape(1, 3))
    local = dolfinx.geometry.compute_colliding_cells(msh, candidates, x.reshape(1, 3)).links(0)
    if not comm.allreduce(len(local), op=MPI.MAX):
        local = _touching(msh, owned, tree, x, comm)
    return local


def check_body(probe: str, body: str, names: Sequence[str]) -> None:
    """A probe's body checked against the model's body names.

    Raises:
        CaseError: No body of that name (one line naming the bodies; model.body's
            KeyError quoted its message, from Python).
    """
    if body not in names:
        raise CaseError(f"probe '{probe}': no body named '{body}'{suggest(body, names)} "
                        f"(bodies: {', '.join(names)})")


def _located(model: ContactModel, probe: str, body: str, point: Sequence[float]
             ) -> tuple[np.ndarray, np.ndarray, int]:
    """The point (3 values), this rank's cells of the body holding it and their owner.

    The owner is the lowest rank holding it (collective).

    Raises:
        MeshError: The point is in none of the body's cells (one line, every rank).
    """
    x = np.zeros(3)
    x[: len(point)] = point
    msh = model.body(body).submesh
    owned = np.arange(msh.topology.index_map(msh.topology.dim).size_local, dtype=np.int32)
    comm = model.comm
    local = locate_point(msh, owned, x, comm)
    owner = comm.allreduce(comm.rank if len(local) else comm.size, op=MPI.MIN)
    if owner == comm.size:
        raise MeshError(f"probe '{probe}': point {tuple(point)} is not in body '{body}'")
    return x, local, owner


def check_point(model: ContactModel, probe: str, body: str, point: Sequence[float]) -> None:
    """A probe's point checked to lie in its body (collective: each rank its cells).

    Raises:
        MeshError: The point is in none of the body's cells (one line, every rank).
    """
    _located(model, probe, body, point)


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

    Raises:
        CaseError: No body of that name (one line naming the model's bodies; the same
            on every rank).
        MeshError: The point is not in the body.
    """

    def __init__(self, model: ContactModel, body: str, point: Sequence[float],
                 name: str | None = None) -> None:
        self.model = model
        self.name = name or f"{body}@{tuple(point)}"
        check_body(self.name, body, [b.spec.name for b in model.bodies])
        self.body = b = model.body(body)
        comm = model.comm
        x, local, self.owner = _located(model, self.name, body, point)
        self.point = x
        self._cell = int(local[0]) if len(local) else -1
        # The value is Σ φ_j(x) u_j over the cell's DOF blocks: the basis functions at
        # the point, found once by evaluating each of them (the owner only).
        V = b.V
        self.size = V.dofmap.index_map_bs
        self._blocks = np.zeros(0, np.int32)
        self._phi = np.zeros(0)
        unit = fem.Function(V)  # collective (its vector's scatter), on every rank
        if comm.rank == self.owner:
            self._blocks = V.dofmap.cell_dofs(self._cell).copy()
            phi = []
            for blk in self._blocks:
                unit.x.array[:] = 0.0
                unit.x.array[blk * self.size] = 1.0
                phi.append(unit.eval(x.reshape(1, 3), np.array([self._cell], np.int32)).ravel()[0])
            self._phi = np.array(phi)
        # The entries of the blocks, (blocks, components): u.x.array[_entries] is
        # u.x.array.reshape(-1, size)[_blocks]; and the array last read (a view: a
        # Function's storage does not move).
        self._entries = self._blocks[:, None].astype(np.int64) * self.size + np.arange(self.size)
        self._last: tuple[fem.Function | None, np.ndarray] = (None, np.zeros(0))

    def local_value(self, functions: Sequence[fem.Function] | fem.Function) -> np.ndarray:
        """The value at the point on the owning rank; zeros on the others (no reduction)."""
        f = functions if isinstance(functions, fem.Function) else functions[self.body.index]
        if not len(self._blocks):
            return np.zeros(self.size)
        if self._last[0] is not f:
            self._last = (f, f.x.array)
        return self._phi @ self._last[1][self._entries]

    def value(self, functions: Sequence[fem.Function] | fem.Function) -> np.ndarray:
        """The value at the point of the body's Function (or of a list, one per body)."""
        out = self.local_value(functions)
        self.model.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        return out
