"""The ``static`` entry of the summary: the first contact pair's static state.

The paper's Fig. 17: the contact resultant against the weight it carries (the pair's
upper body and every body resting on it), the mean, edge and centre pressure; a general
pair's when the model has no conforming one. Reads the history row and the nodal
interface data of the static state; solves nothing.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import dolfinx.mesh
import numpy as np

from breakwater.contact.general import SurfaceContact
from breakwater.contact.general3d import SurfaceContact3D
from breakwater.model.mesh import facet_type, group_tag
from breakwater.model.model import ContactModel
from breakwater.model.pairs import Pair, pair_names
from breakwater.outputs.quality import PairInputs
from breakwater.outputs.section import mid_row

__all__ = ["PRESSED", "RESOLVED_FACETS", "edge_centre", "resolution_warnings", "resting_on",
           "static_summary"]

RESOLVED_FACETS = 3
"""A static contact shorter than this many interface facets is warned about: its
pressure is not resolved (a block on a cylinder, its contact 5.6 mm long on 10 mm
facets, gave a centre pressure from one or two integration points)."""


def resting_on(model: ContactModel, body: int,
               links: Sequence[tuple[int, int]] | None = None) -> set[int]:
    """A body and every body resting on it (collective).

    Pairs of both kinds (conforming and general), each oriented by :func:`_links`.
    Under gravity their weight is what the body's contacts below it carry. ``links``:
    :func:`_links`' result, if known.
    """
    links = _links(model) if links is None else links
    found = {body}
    while new := {s for s, m in links if m in found} - found:
        found |= new
    return found


def _links(model: ContactModel) -> list[tuple[int, int]]:
    """Each pair's bodies as (upper, lower): which rests on the other (collective).

    Conforming pairs first, then general ones (the model's order). The upper body is
    the one whose centroid lies above the pair's contact surface (its interface, or a
    general pair's slave surface) against gravity: the body whose contact is below it.
    Comparing the two bodies' centroids instead took a long slope as resting on the
    block sliding down it (the slope's centroid is the higher: the summary gave the
    slope's weight, 20x the block's). Without gravity the slave rests on the master.
    """
    height = _heights(model)
    out = []
    for s, m, group in model.pair_bodies():
        contact = _mean_height(model, _facet_midpoints(model, group))
        out.append((s, m) if height[s] >= contact else (m, s))
    return out


def _upper_body(model: ContactModel, slave: int, master: int,
                links: Sequence[tuple[int, int]] | None = None) -> int:
    """Of a pair's two bodies, the one resting on the other (:func:`_links`)."""
    links = _links(model) if links is None else links
    return next(u for u, lo in links if {u, lo} == {slave, master})


def _facet_midpoints(model: ContactModel, group: str) -> np.ndarray:
    """The midpoints of a facet group's owned facets (this rank's)."""
    data, dim = model.mesh_data, model.mesh.topology.dim - 1
    assert data.facet_tags is not None
    facets = data.facet_tags.find(group_tag(data, group, dim))
    facets = facets[facets < model.mesh.topology.index_map(dim).size_local]
    return dolfinx.mesh.compute_midpoints(model.mesh, dim, facets.astype(np.int32))


def _mean_height(model: ContactModel, x: np.ndarray) -> float:
    """The mean of the points' heights along −g over every rank (0 without gravity)."""
    g = np.asarray(model.gravity.value, dtype=float)
    norm = float(np.linalg.norm(g))
    total = model.comm.allreduce(x[:, :len(g)].sum(axis=0))
    count = model.comm.allreduce(len(x))
    return -float(total @ g) / (norm * max(count, 1)) if norm > 0 else 0.0


def _heights(model: ContactModel) -> list[float]:
    """Each body's centroid of its geometry nodes along −g (0 without gravity; collective)."""
    out = []
    for b in model.bodies:
        geometry = b.submesh.geometry
        out.append(_mean_height(model, geometry.x[:geometry.index_map().size_local]))
    return out


PRESSED = 1e-3
"""A slave node under less than this fraction of the interface's largest pressure is past
the contact's ends for :func:`edge_centre`: the nodal pressure leaks a little beyond
them (3e-11 Pa on a slope under a block; 0.04 Pa, 6e-6 of the largest, at the mound
crest's node 10 mm past the Goda caisson's corner with the crest as the slave, whose
summary gave an edge pressure of 0.04 Pa against the corner's 6533 Pa)."""


def edge_centre(x: np.ndarray, pressure: np.ndarray | None = None) -> tuple[int, int, int]:
    """Indices of the two end nodes of an interface's contact and of the node halfway along.

    The nodes are sorted lexicographically (x, then y), so for a straight interface (or
    a curve that x runs along) the first and last are its ends, and the rows between
    them follow it. In 3D the same along the row of nodes nearest the
    interface's mid z (:func:`~breakwater.outputs.section.mid_row`). With ``pressure``
    (nodal), the row from its first to its last node under pressure (above
    :data:`PRESSED` of the largest): the contact's
    ends (a slope as the slave, longer than the block on it, gave the pressure 0 at its
    own ends and middle, where nothing touched it).
    """
    row = np.flatnonzero(mid_row(x))
    if pressure is not None and np.any(pressure[row] > 0):
        pressed = np.flatnonzero(pressure[row] > PRESSED * pressure[row].max())
        row = row[pressed[0]:pressed[-1] + 1]
    first, last = int(row[0]), int(row[-1])
    # Halfway along the row (on a straight interface the node nearest the middle of its
    # ends; on a curved one, an arc, that middle is off the surface: every node of a
    # half-cylinder's is as far from it, and the pick was arbitrary).
    along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(x[row], axis=0), axis=1))])
    centre = int(row[np.argmin(np.abs(along - 0.5 * along[-1]))])
    return first, last, centre


def triangle_row(model: ContactModel, group: str, x: np.ndarray, pressure: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray] | None:
    """The nodal pressure along the line z = mid z across a triangulated interface.

    An unstructured interface (linear tetrahedra: three-node triangles, P1) has no row
    of nodes at its mid z, :func:`~breakwater.outputs.section.mid_row`'s: its nodes at
    the exact z nearest it were a few, not reaching the interface's ends (measured: 4
    nodes at x = 0.3 ... 0.64 on a 0.3 ... 0.7 block, its rear "edge" pressure an
    interior node's, 5960 Pa for the edge's 9272). Instead each facet is cut by the
    plane, the pressure linear along its edges (exact for P1). Collective.

    Returns:
        The cut's points (k, 3) sorted by x then y, and their pressures; None where the
        interface's facets are not triangles (hexahedra: their node rows are complete).
    """
    msh, comm = model.mesh, model.comm
    if model.gdim != 3 or facet_type(msh) != dolfinx.mesh.CellType.triangle:
        return None
    from breakwater.outputs.checkpoint import match_nodes

    assert model.mesh_data.facet_tags is not None
    facets = model.mesh_data.facet_tags.find(group_tag(model.mesh_data, group, 2))
    corners = msh.geometry.x[dolfinx.mesh.entities_to_geometry(msh, 2, facets)[:, :3]]
    extent = float(np.ptp(x, axis=0).max())
    z = 0.5 * (x[:, 2].min() + x[:, 2].max())
    values = pressure[match_nodes(x, corners.reshape(-1, 3), 1e-6 * extent)].reshape(-1, 3)
    d = corners[:, :, 2] - z
    d[np.abs(d) <= 1e-9 * extent] = 0.0
    points, found = [], []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        on = d[:, a] == 0.0
        points.append(corners[on, a])
        found.append(values[on, a])
        cross = d[:, a] * d[:, b] < 0.0
        t = (d[cross, a] / (d[cross, a] - d[cross, b]))[:, None]
        points.append((1 - t) * corners[cross, a] + t * corners[cross, b])
        found.append((1 - t[:, 0]) * values[cross, a] + t[:, 0] * values[cross, b])
    gathered = comm.allgather((np.vstack(points), np.concatenate(found)))
    pts = np.vstack([g[0] for g in gathered])
    p = np.concatenate([g[1] for g in gathered])
    key = np.round(pts / (1e-9 * extent)).astype(np.int64)
    _, first = np.unique(key, axis=0, return_index=True)  # each point once
    pts, p = pts[first], p[first]
    order = np.lexsort((pts[:, 1], pts[:, 0]))
    return pts[order], p[order]


def _row_values(points: np.ndarray, p: np.ndarray) -> tuple[float, float, float]:
    """The pressures at a cut's contact ends and halfway along it (linear between)."""
    pressed = np.flatnonzero(p > 0)
    if len(pressed):
        points, p = points[pressed[0]:pressed[-1] + 1], p[pressed[0]:pressed[-1] + 1]
    along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    return float(p[0]), float(p[-1]), float(np.interp(0.5 * along[-1], along, p))


def _first_pair(model: ContactModel, row: Mapping[str, float], pairs: Sequence[Pair]
                ) -> tuple[str, int, int, float] | None:
    """The first contact pair's name, slave and master bodies and normal resultant ∫ p dS.

    The first conforming pair (its ``<name>_normal_force``), else the first general pair:
    Σ w p over its integration points (w their reference lengths, p = ε_n⟨−g_n⟩₊:
    :meth:`breakwater.contact.general.SurfaceContact.state`), the same integral.
    None: no pair (or the general pair is not among ``pairs``).
    """
    if model.pairs:
        name = pair_names([p.spec for p in model.pairs])[0]
        return (name, model.pairs[0].slave, model.pairs[0].master,
                row[f"{name}_normal_force"])
    if not model.surface_pairs:
        return None
    spec = model.surface_pairs[0]
    contact = next((p for p in pairs if isinstance(p, SurfaceContact | SurfaceContact3D)
                    and p.name == spec.name), None)
    if contact is None:
        return None
    state = contact.state()
    return (spec.name, model.body(spec.slave).index, model.body(spec.master).index,
            float(np.sum(state["weight"] * state["pressure"])))


def static_summary(model: ContactModel, row: Mapping[str, float],
                   interface: Mapping[str, np.ndarray], iterations: int,
                   pairs: Sequence[Pair] = ()) -> dict[str, Any]:
    """The ``static`` entry of the summary: the first contact pair's static state.

    The first conforming pair's, or, in a model without one, the first general pair's
    (the same keys, the same meaning): the normal resultant ∫ p dS on the slave, the
    weight of the pair's upper body and of every body resting on it (:func:`resting_on`), the mean
    pressure over the contact length (the history's ``<name>_contact_length``), the
    pressures at the ends of the interface's contact (a general pair's on its slave
    surface) and at its node nearest the centre (:func:`edge_centre`, on the snapshot's
    nodes).

    Args:
        model: The contact model.
        row: The history row of the static state.
        interface: Its nodal interface data (:func:`~breakwater.outputs.monitor.interface_state`).
        iterations: Newton iterations of the static solve.
        pairs: The stepper's pairs (:attr:`~breakwater.stepping.gn22.GN22.contacts`;
            a general pair's resultant is measured on its object).
    """
    static: dict[str, Any] = {"newton_iterations": iterations}
    first = _first_pair(model, row, pairs)
    if first is None:
        return static
    name, slave, master, resultant = first
    weights = model.weight()
    links = _links(model)  # (collective: once)
    upper = _upper_body(model, slave, master, links)
    weight = sum(weights[i] for i in resting_on(model, upper, links))
    # (a 3-D general pair's column is <name>_contact_area)
    length = row.get(f"{name}_contact_length", row.get(f"{name}_contact_area", 0.0))
    pressure = interface[f"contact_{name}_pressure"]
    x = interface[f"contact_{name}_x"]
    first_node, last, centre = edge_centre(x, pressure)
    ends = (pressure[first_node], pressure[last], pressure[centre])
    cut = triangle_row(model, model.pairs[0].spec.interface, x, pressure) if model.pairs else None
    if cut is not None and len(cut[1]):
        ends = _row_values(*cut)
    static.update({
        "slave": model.bodies[slave].spec.name,
        "weight": weight,
        "contact_resultant": resultant,
        "contact_area" if model.gdim == 3 else "contact_length": length,
        "mean_contact_pressure": resultant / length if length > 0 else None,
        "edge_pressure": 0.5 * (ends[0] + ends[1]),
        "edge_pressures": [ends[0], ends[1]],
        "center_pressure": ends[2],
        "max_pressure": float(pressure.max()),
        "resultant_over_weight": resultant / weight if weight > 0 else None,
    })
    return static


def resolution_warnings(row: Mapping[str, float], inputs: Sequence[PairInputs], gdim: int,
                        interface: Mapping[str, np.ndarray] | None = None, degree: int = 2
                        ) -> list[str]:
    """One line per pair whose static contact spans fewer than :data:`RESOLVED_FACETS` facets.

    The facets across the contact are counted from its pressed nodes where ``interface``
    gives the pressure (n of them: ``(n − 1)/degree`` facets in 2D, ``(√n − 1)/degree``
    across in 3D), so that a surface refined at its contact and coarse elsewhere (a
    cylinder of 0.4 mm facets within its 3.4 mm contact and 4 mm ones beyond, mean 1.3 mm:
    17 facets across) is judged by the facets there, not by the surface's mean facet;
    without it, by the mean facet length.

    Args:
        row: The static state's history row (``<pair>_contact_length``: m, m² in 3D).
        inputs: The pairs' quality inputs (their mean interface facet length h).
        gdim: The model's dimension (3D: the contact's size is the square root of its
            area).
        interface: The static state's nodal arrays
            (:func:`~breakwater.outputs.monitor.interface_state`:
            ``contact_<name>_pressure``).
        degree: The displacement's polynomial degree (nodes per facet edge).
    """
    out = []
    for q in inputs:
        measured = row.get(f"{q.name}_contact_length", row.get(f"{q.name}_contact_area", 0.0))
        size = measured if gdim == 2 else float(np.sqrt(measured))
        if not size > 0:
            continue
        pressure = None if interface is None else interface.get(f"contact_{q.name}_pressure")
        if pressure is None:
            facets, h = size / q.element_size, q.element_size
            what_h = f"of its mean interface facet (h = {h:.3g} m)"
        else:
            pressed = int(np.count_nonzero(np.asarray(pressure) > 0))
            if not pressed:  # touching, nothing pressed (no gravity): nothing to resolve
                continue
            across = pressed if gdim == 2 else math.sqrt(pressed)
            facets = max(across - 1.0, 0.0) / degree
            what_h = (f"interface facets across it ({pressed} nodes pressed; mean interface "
                      f"facet h = {q.element_size:.3g} m)")
        if facets < RESOLVED_FACETS:
            what = f"{size:.3g} m long" if gdim == 2 else f"{measured:.3g} m² ({size:.3g} m across)"
            out.append(f"contact '{q.name}': the static contact is {what}, {facets:.2g} "
                       f"{what_h}: its pressure (edge, centre, maximum) is not resolved; "
                       f"refine the surfaces there (h ≤ {size / (2 * RESOLVED_FACETS):.2g} m)")
    return out
