"""Nodal values of a discontinuous field: the volume-weighted average of the cells at a vertex.

A stress of P_k displacements is discontinuous between cells; the ParaView fields
(:class:`~breakwater.outputs.writers.BodyFields`) keep it so, exactly (discontinuous
P_k). The nodal snapshots (``static.npz``, ``snapshot_max_ux.npz``) need one value per
vertex: :class:`VertexAverage` gives at vertex v

    f̄(v) = Σ_c |c| f_c(v) / Σ_c |c|,

over the cells c that have the vertex, f_c(v) the field of cell c at v and |c| its
volume (area in 2D). Every cell is summed once, on the rank that owns it, and the
ranks' sums are added at the shared vertices: the value does not depend on the
partition (to round-off). It replaced the value of whichever cell interpolation met
last at the vertex, a ghost's or an owned one's by the partition (von Mises up to
30 % apart between 1 and 2 ranks at some nodes).
"""

from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem, la

__all__ = ["VertexAverage"]


class VertexAverage:
    """The vertex averages of discontinuous fields of one mesh, into its P1 spaces (collective).

    Args:
        scalar: The P1 space of the scalar fields (its dofs: the vertices).
    """

    def __init__(self, scalar: fem.FunctionSpace) -> None:
        msh = scalar.mesh
        self._scalar = scalar
        self._cells = msh.topology.index_map(msh.topology.dim).size_local
        dg0 = fem.functionspace(msh, ("Discontinuous Lagrange", 0))
        volumes = fem.assemble_vector(fem.form(ufl.TestFunction(dg0) * ufl.dx))
        owned = np.arange(self._cells, dtype=np.int32)
        self._volume = volumes.array[dg0.dofmap.list[owned, 0]]
        self._dofs = scalar.dofmap.list[owned]  # (cells, vertices of a cell)
        weight = fem.Function(scalar)
        np.add.at(weight.x.array, self._dofs.ravel(), np.repeat(self._volume,
                                                                self._dofs.shape[1]))
        weight.x.scatter_reverse(la.InsertMode.add)
        weight.x.scatter_forward()
        self._weight = weight.x.array.copy()
        self._dg: dict[tuple[int, ...], fem.FunctionSpace] = {}

    def __call__(self, f: fem.Function, space: fem.FunctionSpace) -> np.ndarray:
        """The P1 nodal values (owned and ghost dofs, blocked) of the averages of ``f``.

        Args:
            f: A field on the mesh (discontinuous or not).
            space: The P1 space of ``f``'s shape (the scalar space's dof layout).
        """
        shape = f.ufl_shape
        if shape not in self._dg:
            self._dg[shape] = fem.functionspace(self._scalar.mesh,
                                                ("Discontinuous Lagrange", 1, shape))
        dg = self._dg[shape]
        g = fem.Function(dg)
        g.interpolate(f)  # each cell's own values at its vertices
        bs = space.dofmap.index_map_bs
        values = g.x.array.reshape(-1, bs)[dg.dofmap.list[:self._cells]]
        out = fem.Function(space)
        np.add.at(out.x.array.reshape(-1, bs), self._dofs.ravel(),
                  (values * self._volume[:, None, None]).reshape(-1, bs))
        out.x.scatter_reverse(la.InsertMode.add)
        out.x.scatter_forward()
        return (out.x.array.reshape(-1, bs) / self._weight[:, None]).ravel()
