"""The surfaces of a general contact pair: its settings and its facets on every rank.

:class:`SurfacePair` is a general pair as the model holds it (:mod:`breakwater.model.model`),
:func:`gather_surface` the facets of one side, gathered on every rank in an order that
does not depend on the partition, and :func:`surface_dofs` the DOFs of every pair's
surfaces (the interface unknowns of the fast solver, :mod:`breakwater.stepping.bulk`). The pair's
forces are :class:`breakwater.contact.general.SurfaceContact`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from dolfinx import fem

if TYPE_CHECKING:
    from breakwater.model.model import ContactModel
    from breakwater.stepping.bulk import MonolithicLayout

__all__ = ["INTEGRATIONS", "Surface", "SurfacePair", "check_pair_settings", "gather_surface",
           "surface_dofs"]

INTEGRATIONS = ("segments", "gauss", "nodes")


def check_pair_settings(penalty: float, friction: float, regularisation: float, slave: str,
                        master: str) -> None:
    """Check the law's settings and bodies of a contact pair (conforming or general).

    Raises:
        ValueError: A setting out of range, or the same body on both sides.
    """
    if not penalty > 0:
        raise ValueError(f"contact penalty must be > 0 (got {penalty})")
    if not friction >= 0:
        raise ValueError(f"friction coefficient must be >= 0 (got {friction})")
    if not regularisation > 0:
        raise ValueError(f"regularisation must be > 0 (got {regularisation})")
    if slave == master:
        raise ValueError("a contact pair needs two different bodies")


@dataclass(frozen=True)
class SurfacePair:
    """Penalty contact with regularised Coulomb friction between two surfaces.

    Attributes:
        name: The pair's name (the case's ``[contact.NAME]``).
        slave: Body whose integration points are projected.
        master: Body whose surface (and outward normal) they are projected on.
        slave_surface: Facet group on the slave's boundary.
        master_surface: Facet group on the master's boundary, or several making one
            surface (:attr:`master_groups`).
        penalty: Normal penalty ε_n (N/m³).
        friction: Coulomb coefficient μ (-).
        regularisation: Regularisation velocity χ (m/s).
        points: Gauss points per integration segment (``segments``, ``gauss``).
        integration: The slave's integration points: ``segments`` (each slave facet
            cut where the master facets' vertices project onto it, ``points`` Gauss
            points per segment: segment-to-segment, exact on a flat patch),
            ``gauss`` (``points`` Gauss points per slave facet: Gauss-point-to-segment)
            or ``nodes`` (the slave facet's nodes with Gauss–Lobatto weights,
            Simpson's on a P2 facet: node-to-segment, the conforming pair's
            quadrature).
        rotations: ``finite``: the normal and tangent of the current master surface
            at the projection (eq. 7); ``small``: those of the reference surface there
            (the bodies' small rotations, as the conforming pair's fixed normal; the
            projection, the gap and the slip still follow the current surfaces).
        radius: Search radius (m): a point farther from the master surface has no
            projection (out of contact); None: the longest master facet.
    """

    name: str
    slave: str
    master: str
    slave_surface: str
    master_surface: str | tuple[str, ...]
    penalty: float
    friction: float = 0.0
    regularisation: float = 1e-10
    points: int = 3
    integration: str = "segments"
    rotations: str = "finite"
    radius: float | None = None

    gap = 0.0  # the law's g_0: the geometry carries the initial gap of a general pair

    def __post_init__(self) -> None:
        check_pair_settings(self.penalty, self.friction, self.regularisation, self.slave,
                            self.master)
        if not self.points >= 1:
            raise ValueError(f"points per facet must be >= 1 (got {self.points})")
        if self.integration not in INTEGRATIONS:
            raise ValueError(f"integration must be one of {', '.join(INTEGRATIONS)} "
                             f"(got {self.integration!r})")
        if self.rotations not in ("finite", "small"):
            raise ValueError(f"rotations must be finite or small (got {self.rotations!r})")
        if not self.master_groups:
            raise ValueError("a master surface needs at least one facet group")
        if self.radius is not None and not self.radius > 0:
            raise ValueError(f"search radius must be > 0 (got {self.radius})")


    @property
    def master_groups(self) -> tuple[str, ...]:
        """The facet groups of the master surface (one or several)."""
        m = self.master_surface
        return (m,) if isinstance(m, str) else tuple(m)


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
