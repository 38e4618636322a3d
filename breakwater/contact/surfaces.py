"""The surfaces of a general contact pair: its facets on every rank.

:func:`gather_surface` gives the facets of one side, gathered on every rank in an order
that does not depend on the partition, and :func:`surface_dofs` the DOFs of every
pair's surfaces (the interface unknowns of the fast solver,
:mod:`breakwater.stepping.bulk`). The pair's settings, :class:`SurfacePair`, are the
model's (:mod:`breakwater.model.pairs`, re-exported here); its forces are
:class:`breakwater.contact.general.SurfaceContact`.
"""

from __future__ import annotations

import logging
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater.common.errors import MeshError
from breakwater.model.mesh import DEGENERATE
from breakwater.model.pairs import INTEGRATIONS, SurfacePair, check_pair_settings

if TYPE_CHECKING:
    from breakwater.model.layout import MonolithicLayout
    from breakwater.model.model import ContactModel

__all__ = ["CORNER", "INTEGRATIONS", "TURN", "Surface", "SurfacePair", "check_faces",
           "check_pair_settings", "chord_sag", "collapsed", "gather_surface", "surface_dofs",
           "warn_first_order"]

log = logging.getLogger("breakwater.contact.surfaces")

TURN = 1e-4
"""A surface turning by more than this angle (rad) at consecutive vertices is
curved (a chord h of a circle turning by θ at its ends sags hθ/8: above 1e-5 h)."""

CORNER = np.pi / 3
"""A vertex turning by this angle (rad) or more is a corner of the geometry, not a
curve's (a circle meshed in 6 facets or fewer): a notch one facet wide and deep in a
first-order soil surface (four right angles in a row) was warned about as "curved",
its chords sagging 8.7 cm inside a circle that is not there."""

_warned: weakref.WeakKeyDictionary[ContactModel, set[tuple[str, str]]] = \
    weakref.WeakKeyDictionary()
"""(pair, surface) warned about, per model: once per case built, not per stepper (the
adaptive levels') nor per run of the same model. Once per process, as before, a case
run after another in a notebook or a study's next case said nothing of its own mesh."""


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


def collapsed(X: np.ndarray) -> np.ndarray:
    """Per face (2-D: facet) of ``X`` ``(F, nn, gdim)``, whether it is collapsed.

    In 3-D its corners' triangle has a height below
    :data:`~breakwater.model.mesh.DEGENERATE` of its longest edge (two corners at one
    point, or the three on one line; a six-node face whatever its mid-edge nodes), in
    2-D its ends lie closer than that fraction of the surface's longest facet. (A
    non-finite node is the mesh's refusal, :class:`~breakwater.model.model.ContactModel`.)
    """
    if X.shape[-1] == 3:
        c = X[:, :3]
        twice_area = np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1)
        longest = np.linalg.norm(c[:, [1, 2, 0]] - c, axis=2).max(axis=1)
        return np.asarray(twice_area <= DEGENERATE * longest**2)  # height 2A/l ≤ DEGENERATE l
    chord = np.linalg.norm(X[:, 1] - X[:, 0], axis=1)
    return np.asarray(chord <= DEGENERATE * (chord.max() if len(chord) else 0.0))


def check_faces(model: ContactModel) -> None:
    """Refuse a general pair's surface group with collapsed faces (collective).

    A collapsed face (:func:`collapsed`) has no plane or chord: the search divides by
    its area or length (Newton's start on a master face's plane or chord, the slave's
    segmentation on a slave face's plane, the slave's normals), a raw
    ZeroDivisionError; in 3-D it is a facet of a tetrahedron without volume, whose
    stiffness is NaN, so that no search could make the run right. Each group is
    gathered (the same faces on every rank, in one order) and the decision reduced
    over the ranks besides: every rank refuses, with the same line. Called where a
    case's model is built (before a calibration's searches) and by
    :func:`~breakwater.run.simulation.run` before the output folder is touched (a
    model built in Python).

    Raises:
        MeshError: One line naming the pair, the side, the group, how many faces and
            where the first is.
    """
    for spec in model.surface_pairs:
        for role, body, group in (("slave", spec.slave, spec.slave_surface),
                                  *(("master", spec.master, g) for g in spec.master_groups)):
            X = gather_surface(model, None, body, (group,)).X
            flat = collapsed(X)
            if not model.comm.allreduce(bool(flat.any()), op=MPI.LOR):
                continue
            kind, corners = ("face", 3) if X.shape[-1] == 3 else ("facet", 2)
            what = ("no area: two corners at one point or the three on one line"
                    if corners == 3 else "no length: its two ends at one point")
            f = int(np.flatnonzero(flat)[0])
            centre = X[f, :corners].mean(axis=0)
            centre[np.abs(centre) <= 1e-12 * np.abs(X[f]).max()] = 0.0  # round-off of a 0
            raise MeshError(f"contact.{spec.name}.{role}_surface: '{group}' on '{body}' has "
                            f"{int(flat.sum())} collapsed {kind}(s) ({what}), the first "
                            f"centred at ({_xyz(centre)}) m: remesh there")


def _xyz(x: np.ndarray) -> str:
    """A point's coordinates, ``'0.1, 2, nan'``."""
    return ", ".join(f"{float(c):.4g}" for c in x)


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


def chord_sag(surface: Surface) -> tuple[int, float, float]:
    """Where a first-order surface is a polygon of chords of a curve.

    The turn θ between the chords of consecutive facets at each shared vertex; a
    vertex is on a curve where it and a neighbouring vertex both turn by more than
    :data:`TURN` and less than :data:`CORNER`, and the surface is curved where it has
    three such vertices or more (an isolated corner, or two a facet apart, are the
    geometry's own). A chord
    h of the circle through such a vertex and its neighbours (facets h₁, h₂) sags
    h²/(8R) = h²θ/(4(h₁ + h₂)) below it.

    Returns:
        The number of such vertices, their largest turn (rad) and the largest sag
        (m) of their facets.
    """
    if surface.X.shape[0] < 3:
        return 0, 0.0, 0.0
    ends = surface.dofs[:, :2, 0]  # the vertices' ids (the x DOF)
    chord = surface.X[:, 1] - surface.X[:, 0]
    length = np.linalg.norm(chord, axis=1)
    vertex, end = np.unique(ends, return_inverse=True)  # each facet end's vertex
    end = end.reshape(ends.shape)
    # The two facets at each vertex (−1: an end of the surface).
    at = np.full((len(vertex), 2), -1)
    count = np.zeros(len(vertex), np.int64)
    for f, k in np.ndindex(*end.shape):
        v = end[f, k]
        if count[v] < 2:
            at[v, count[v]] = f
        count[v] += 1
    shared = count == 2
    t = chord / np.maximum(length, 1e-300)[:, None]
    a, b = at[shared, 0], at[shared, 1]
    turn = np.zeros(len(vertex))
    turn[shared] = np.arccos(np.clip(np.abs(np.sum(t[a] * t[b], axis=1)), 0.0, 1.0))
    bent = (turn > TURN) & (turn < CORNER)
    # A vertex whose two facets' other ends both turn too.
    v = np.flatnonzero(shared)
    ends_a, ends_b = end[a], end[b]
    other_a = np.where(ends_a[:, 0] == v, ends_a[:, 1], ends_a[:, 0])
    other_b = np.where(ends_b[:, 0] == v, ends_b[:, 1], ends_b[:, 0])
    curved = np.zeros(len(vertex), bool)
    curved[v] = bent[v] & (bent[other_a] | bent[other_b])
    if curved.sum() < 3:
        return 0, 0.0, 0.0
    # The circle through a vertex and its neighbours: radius (h₁ + h₂)/(2θ); a chord
    # h of it sags h²/(8R) = h²θ/(4(h₁ + h₂)).
    sag = np.zeros(len(vertex))
    sag[v] = np.maximum(length[a], length[b])**2 * turn[v] / (4 * (length[a] + length[b]))
    return int(curved.sum()), float(turn[curved].max()), float(sag[curved].max())


def warn_first_order(model: ContactModel, spec: SurfacePair, surfaces: Sequence[Surface]
                     ) -> None:
    """Warn where a first-order mesh's P2 contact surface is curved (once per surface).

    :func:`chord_sag`: its P2 nodes lie on the chords, which the elements flatten
    against the other surface, and the pressure alternates between vertices and
    mid-edge nodes where the sag exceeds the penalty overlap p/ε_n. The decision is the
    same on every rank (the surfaces are gathered); rank 0 logs.
    """
    if model.mesh.geometry.cmaps[0].degree != 1:
        return
    names = (spec.slave_surface, "+".join(spec.master_groups))
    warned = _warned.setdefault(model, set())
    for name, surface in zip(names, surfaces, strict=True):
        if surface.X.shape[1] != 3 or (spec.name, name) in warned:
            continue
        n, turn, sag = chord_sag(surface)
        if n and model.comm.rank == 0:
            log.warning(
                "contact '%s': surface '%s' is curved (its facets turn by up to %.2g° at %d "
                "nodes) but the mesh is first order: its P2 mid-edge nodes lie on the "
                "straight chords, up to %.1e m inside the curve, and the contact pressure "
                "alternates between vertices and mid-edge nodes where that exceeds the "
                "penalty overlap p/ε_n; mesh it second order (a .geo as mesh.source is; "
                "gmsh: Mesh.ElementOrder = 2, or -order 2)", spec.name, name,
                np.degrees(turn), n, sag)
        if n:
            warned.add((spec.name, name))
