"""The surfaces of a general contact pair: its facets on every rank.

:func:`gather_surface` gives the facets of one side, gathered on every rank in an order
that does not depend on the partition, and :func:`surface_dofs` the DOFs of every
pair's surfaces (the interface unknowns of the fast solver,
:mod:`breakwater.stepping.bulk`). The pair's settings, :class:`SurfacePair`, are the
model's (:mod:`breakwater.model.pairs`, re-exported here); its forces are
:class:`breakwater.contact.general.SurfaceContact`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from dolfinx import fem

from breakwater.model.pairs import INTEGRATIONS, SurfacePair, check_pair_settings

if TYPE_CHECKING:
    from breakwater.model.layout import MonolithicLayout
    from breakwater.model.model import ContactModel

__all__ = ["INTEGRATIONS", "Surface", "SurfacePair", "check_pair_settings", "gather_surface",
           "surface_dofs"]


@dataclass
class Surface:
    """The facets of one surface, gathered on every rank and sorted by coordinates.

    Attributes:
        X: Reference node coordinates, ``(F, nn, gdim)`` (closure order: the two
            vertices, then the mid-edge node).
        dofs: Global stacked indices of the nodes' components, ``(F, nn, gdim)``.
        interior: A point inside each facet's cell, ``(F, gdim)``.
    """

    X: np.ndarray
    dofs: np.ndarray
    interior: np.ndarray


def gather_surface(model: ContactModel, layout: MonolithicLayout | None, body: str,
                   groups: Sequence[str]) -> Surface:
    """The facets of a body's facet groups (collective).

    Without a layout the DOFs are −1 (the geometry only).
    """
    b = model.body(body)
    V, sub = b.V, b.submesh
    tdim = sub.topology.dim
    fdim, gdim = tdim - 1, model.gdim
    sub.topology.create_connectivity(fdim, tdim)
    sub.topology.create_connectivity(tdim, fdim)
    f2c, c2f = sub.topology.connectivity(fdim, tdim), sub.topology.connectivity(tdim, fdim)
    facets = model.surface_facets(body, groups)
    facets = facets[facets < sub.topology.index_map(fdim).size_local]
    closure = V.dofmap.dof_layout.entity_closure_dofs
    coords = V.tabulate_dof_coordinates()[:, :gdim]
    bs = V.dofmap.index_map_bs
    nn = len(closure(fdim, 0))
    X = np.zeros((len(facets), nn, gdim))
    dofs = np.zeros((len(facets), nn, gdim), np.int64)
    interior = np.zeros((len(facets), gdim))
    for k, f in enumerate(facets):
        c = f2c.links(f)[0]
        local = int(np.flatnonzero(c2f.links(c) == f)[0])
        cell = V.dofmap.cell_dofs(c)
        blocks = cell[closure(fdim, local)]
        X[k] = coords[blocks]
        dofs[k] = -1 if layout is None else \
            layout.global_index[b.index][(blocks[:, None] * bs + np.arange(gdim))]
        interior[k] = coords[cell].mean(axis=0)
    X, dofs, interior = (np.concatenate(model.comm.allgather(a)) for a in (X, dofs, interior))
    mid = X.mean(axis=1)
    order = np.lexsort(mid.T[::-1])
    return Surface(X[order], dofs[order], interior[order])


def surface_dofs(model: ContactModel, layout: MonolithicLayout) -> np.ndarray:
    """Global stacked indices of the DOFs of every general pair's two surfaces (local)."""
    fdim = model.mesh.topology.dim - 1
    out = []
    for spec in model.surface_pairs:
        for name, groups in ((spec.slave, (spec.slave_surface,)),
                             (spec.master, spec.master_groups)):
            b = model.body(name)
            blocks = fem.locate_dofs_topological(b.V, fdim,
                                                 model.surface_facets(name, groups))
            bs = b.V.dofmap.index_map_bs
            out.append(layout.global_index[b.index][(blocks[:, None] * bs
                                                     + np.arange(bs)).ravel()])
    return np.concatenate(out) if out else np.zeros(0, np.int64)
