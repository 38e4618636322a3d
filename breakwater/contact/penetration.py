"""Penetration that a general pair's contact search cannot see: refused at t = 0, steps cut back.

A general pair (:mod:`breakwater.contact.general`) presses a slave point only if the search
finds its closest point on the master surface within the search radius r (the longest
master facet, or ``SurfacePair.radius``). A slave node that gets deeper than that into
the master has no projection: it carries no force, and the bodies pass through each
other silently (a block at 20 m/s with Δt = 1e-3 s moves 2 cm per step, twice the
10 mm radius of the sliding-block example's base: it went through the 0.1 m base with a
contact force of zero). Two checks keep every slave node where the search sees it:

- **At t = 0** (:func:`initial_overlap`, the pair's static check, which the static
  stage runs for every pair before it looks for the initial state): a slave node inside a
  master cell (reference configuration, dolfinx's bounding-box tree on the master body)
  deeper than :func:`allowed_depth` below the master surface, or with no master surface
  point within r, is an overlap of the meshes that the penalty cannot resolve: refused,
  naming the pair, the node and the depth.
- **Each step** (:func:`step_penetration`, on the fast solver's converged iterate; the
  step is then rejected as a :class:`~breakwater.common.errors.PenetrationError` and the time
  loop cuts it back like a step that did not converge):

  1. *one-step motion*: no slave node moves farther relative to the master than r in
     one step (relative to the master point under its projection at the start of the
     step; a node with none, farther than r from the whole master surface, against
     the master surface's mean motion plus its spread). A node farther than r from the
     surface that moves less than r relative to it cannot reach it, let alone cross
     it, in the step;
  2. *depth*: no slave node projected onto the master at the start of the step ends it
     deeper below that master point (along the normal there) than
     :func:`allowed_depth`: r, or the height of the master's element under it if
     smaller (a master thinner than r could otherwise be crossed within reach).

  Both are O(slave nodes) on the arrays the pair already holds; the start-of-step
  projection of the slave nodes is the one its friction uses (cached per step).

Induction: the initial state has no node beyond what the search sees; a step that
would leave one is cut back (its state untouched), down to ``time.max_cutbacks``
halvings, and then the run fails with the reason (a penalty too soft to stop the body
within one element, or a step too large even when halved).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from dolfinx import geometry
from mpi4py import MPI

from breakwater.common.arrays import equal
from breakwater.common.jit import kernel
from breakwater.contact.projection import FacetGrid, curve, project
from breakwater.contact.surfaces import Surface, SurfacePair, gather_surface

if TYPE_CHECKING:
    from breakwater.model.model import ContactModel

__all__ = ["OVERLAP", "StepCheck", "allowed_depth", "initial_overlap", "meshed_gaps",
           "meshed_overlap", "search_radius", "step_penetration"]


def search_radius(spec: SurfacePair, master: Surface) -> float:
    """The pair's search radius: ``spec.radius``, else the longest master facet (chord)."""
    if spec.radius is not None:
        return spec.radius
    lengths = np.linalg.norm(master.X[:, 1] - master.X[:, 0], axis=1)
    return float(lengths.max()) if len(lengths) else 1.0


def allowed_depth(master: Surface, radius: float) -> np.ndarray:
    """The deepest a slave node may lie below each master facet (m), ``(F,)``.

    The search radius, or the height of the facet's cell if smaller (three times the
    distance of the cell's centroid from the facet's chord: exact for a straight
    triangle).
    """
    if not len(master.X):
        return np.zeros(0)
    a, b = master.X[:, 0], master.X[:, 1]
    chord = b - a
    normal = np.stack([chord[:, 1], -chord[:, 0]], axis=1)
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    height = 3.0 * np.abs(np.sum((master.interior - a) * normal, axis=1))
    return np.minimum(radius, height)


def _point(x: np.ndarray) -> str:
    return "(" + ", ".join(f"{c:.4g}" for c in x) + ") m"


OVERLAP = 1e-3
"""A slave node that starts deeper inside the master than this fraction of the master
facet under it is an overlap of the meshes (:func:`meshed_overlap`), not round-off."""


def _depths(model: ContactModel, spec: SurfacePair
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float] | None:
    """The slave nodes inside the master body at t = 0 and their depths (collective).

    Returns:
        Those nodes, their depths below the master surface (inf: no master surface point
        within the search radius), the depth each may have (:func:`allowed_depth` of
        the facet under it, 0 without one), the length of that facet (chord, 0 without
        one) and the search radius; None when no slave node lies inside a master cell.
    """
    slave = gather_surface(model, None, spec.slave, (spec.slave_surface,))
    master = gather_surface(model, None, spec.master, spec.master_groups)
    gdim = model.gdim
    nodes = np.unique(slave.X.reshape(-1, gdim), axis=0)
    if not len(nodes) or not len(master.X):
        return None
    # Inside a master cell: each rank tests its cells (ghosts included), one reduction.
    sub = model.body(spec.master).submesh
    tdim = sub.topology.dim
    points = np.zeros((len(nodes), 3))
    points[:, :gdim] = nodes
    tree = geometry.bb_tree(sub, tdim)
    cells = geometry.compute_colliding_cells(sub, geometry.compute_collisions_points(tree, points),
                                             points)
    inside = (np.diff(cells.offsets) > 0).astype(np.int32)
    model.comm.Allreduce(MPI.IN_PLACE, inside, op=MPI.MAX)
    k = np.flatnonzero(inside)
    if not len(k):
        return None
    radius = search_radius(spec, master)
    gap, facet, length = _gaps(nodes[k], master, radius)
    limit = np.where(facet >= 0, allowed_depth(master, radius)[np.maximum(facet, 0)], 0.0)
    return nodes[k], np.where(facet >= 0, -gap, np.inf), limit, length, radius


def _gaps(nodes: np.ndarray, master: Surface, radius: float
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each node's signed distance outside the master surface (2-D, the meshed state).

    Returns:
        The gaps (negative inside; inf: no master surface point within ``radius``), the
        master facet each projects on (−1: none) and its length (chord; 0 without one).
    """
    # Orient each master facet so that (t_y, −t_x) points out of its cell.
    X = master.X.copy()
    mid = X.mean(axis=1)
    chord = X[:, 1] - X[:, 0]
    flip = np.sum((master.interior - mid) * np.stack([chord[:, 1], -chord[:, 0]], 1),
                  axis=1) > 0
    X[flip, 0], X[flip, 1] = master.X[flip, 1], master.X[flip, 0]
    facet, xi = project(nodes, X, FacetGrid(X, radius))
    gap = np.full(len(nodes), np.inf)
    on = facet >= 0
    if on.any():
        x_bar, tangent, _ = curve(X[facet[on]], xi[on])
        tangent /= np.linalg.norm(tangent, axis=1)[:, None]
        n = np.stack([tangent[:, 1], -tangent[:, 0]], axis=1)
        gap[on] = np.sum((nodes[on] - x_bar) * n, axis=1)
    length = np.linalg.norm(X[:, 1] - X[:, 0], axis=1)
    return gap, facet, np.where(on, length[np.maximum(facet, 0)], 0.0)


def meshed_gaps(slave: Surface, master: Surface, radius: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Every slave node's distance outside the master surface at t = 0 (not collective).

    The 2-D counterpart of :func:`breakwater.contact.general3d.nodal_gaps` on the meshed
    configuration, for :func:`breakwater.contact.meshedgap.meshed_gap2d`, of the pair's
    own surfaces (gathered on every rank when it was built: the same on every rank, no
    gather here).

    Args:
        slave: The slave surface (its reference coordinates).
        master: The master surface (oriented or not: :func:`_gaps` orients it).
        radius: The pair's search radius.

    Returns:
        The slave nodes (sorted, the same on every rank), their gaps (negative inside;
        inf: no master surface point within the search radius) and the length of the
        master facet each projects on (0 without one); None without nodes.
    """
    nodes = np.unique(slave.X.reshape(-1, slave.X.shape[-1]), axis=0)
    if not len(nodes) or not len(master.X):
        return None
    gap, _, length = _gaps(nodes, master, radius)
    return nodes, gap, length


def initial_overlap(model: ContactModel, spec: SurfacePair) -> str | None:
    """Why the pair's bodies overlap beyond what its search sees at t = 0 (collective).

    Returns:
        The reason (the deepest slave node: its position, its depth and the depth the
        pair sees), the same on every rank; None when no slave node lies inside the
        master body deeper than :func:`allowed_depth` (or beyond the search radius).
    """
    found = _depths(model, spec)
    if found is None:
        return None
    nodes, depth, limit, _, radius = found
    bad = np.flatnonzero(depth > limit)
    if not len(bad):
        return None
    worst = bad[np.argmax(np.where(np.isinf(depth[bad]), np.inf, depth[bad] / limit[bad]))]
    where = _point(nodes[worst])
    if np.isinf(depth[worst]):
        # No master surface point within the radius: measure the distance to it.
        master = gather_surface(model, None, spec.master, spec.master_groups)
        far = _distance(nodes[worst], master.X)
        # Inside or on the master's boundary: on it where master_surface leaves out
        # the part of the boundary under the node (a group forgotten from its list).
        groups = ", ".join(spec.master_groups)
        return (f"contact '{spec.name}': slave node at {where} starts inside the master "
                f"'{spec.master}' or on its boundary, {far:.3g} m from its contact "
                f"surface (master_surface: {groups}), with no projection on it within the "
                f"contact search radius {radius:.3g} m: the meshes of the two bodies "
                "overlap (move the slave body out of the master), or master_surface "
                "leaves out the part of the master's boundary under it (add its facet "
                "group)")
    return (f"contact '{spec.name}': slave node at {where} starts {depth[worst]:.3g} m "
            f"inside the master '{spec.master}', deeper than the contact sees "
            f"({limit[worst]:.3g} m: the search radius or the master's element under it): "
            "the meshes of the two bodies overlap (move the slave body out of the master)")


def meshed_overlap(model: ContactModel, spec: SurfacePair) -> str | None:
    """A warning where the meshes overlap within what the pair sees (collective).

    A slave node inside the master deeper than :data:`OVERLAP` of the master facet
    under it (0.3 mm on 12 mm facets: a caisson drawn into its mound): the static state
    pushes the bodies apart by it, silently before, so that its displacements, its
    settlement and the penalty's quality check (which then advised refining the mesh)
    include the overlap.

    Returns:
        One line (the deepest node, its depth, how many nodes), the same on every rank;
        None without such a node.
    """
    found = _depths(model, spec)
    if found is None:
        return None
    nodes, depth, _, length, _ = found
    over = np.flatnonzero(np.isfinite(depth) & (depth > OVERLAP * length))
    if not len(over):
        return None
    worst = over[np.argmax(depth[over])]
    return (f"contact '{spec.name}': the meshes overlap: {len(over)} slave node(s) start "
            f"inside the master '{spec.master}', the deepest {depth[worst]:.3g} m at "
            f"{_point(nodes[worst])} ({depth[worst] / length[worst]:.1%} of the facet "
            "under it); the static state pushes the bodies apart by it, and its "
            "displacements and settlement include it: move the slave body out of the "
            "master in the mesh")


def _distance(point: np.ndarray, X: np.ndarray) -> float:
    """Distance of a point to a surface of facets: its nearest projection or vertex."""
    vertices = X[:, :2].reshape(-1, X.shape[2])
    best = float(np.min(np.linalg.norm(vertices - point, axis=1)))
    facet, xi = project(point[None], X, FacetGrid(X, 2 * best))
    if facet[0] >= 0:
        x_bar, _, _ = curve(X[facet], xi)
        best = min(best, float(np.linalg.norm(x_bar[0] - point)))
    return best


# Σ|N_k(ξ)| over a facet's shape functions: 1 (straight), 1.25 at most (quadratic, at
# ξ = ±½): the motion of a master point is within this multiple of the nodes' spread.
_SHAPE_SUM = 1.25


def _motion_bound(du_s: np.ndarray, du_m: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """Per slave node, a bound of its motion relative to every master surface point.

    Returns:
        The bound ``|Δu_s − c| + 1.25 max|Δu_m − c|`` (c the master nodes' mean motion),
        and c and the master nodes' spread.
    """
    flat = du_m.reshape(-1, du_m.shape[-1])
    centre = flat.mean(axis=0) if len(flat) else np.zeros(du_s.shape[-1])
    spread = float(np.linalg.norm(flat - centre, axis=1).max(initial=0.0))
    return np.linalg.norm(du_s - centre, axis=1) + _SHAPE_SUM * spread, spread, centre


@kernel
def screen_bound(u0, u1, node_pos, pos_m):  # type: ignore[no-untyped-def]
    """``_motion_bound(Δu_s, Δu_m)[0].max(initial=0)`` from u0 and u1 (compiled).

    Δu = u1 − u0 at the slave nodes' positions ``node_pos`` ``(K, gdim)`` and the master
    facets' ``pos_m`` ``(F, nn, gdim)``: one pass, no temporaries.
    """
    gdim = node_pos.shape[1]
    F, nn = pos_m.shape[0], pos_m.shape[1]
    centre = np.zeros(gdim)
    for f in range(F):
        for a in range(nn):
            for d in range(gdim):
                centre[d] += u1[pos_m[f, a, d]] - u0[pos_m[f, a, d]]
    if F:
        centre /= F * nn
    spread = 0.0
    for f in range(F):
        for a in range(nn):
            r = 0.0
            for d in range(gdim):
                x = (u1[pos_m[f, a, d]] - u0[pos_m[f, a, d]]) - centre[d]
                r += x * x
            spread = max(spread, np.sqrt(r))
    bound = 0.0
    for j in range(node_pos.shape[0]):
        r = 0.0
        for d in range(gdim):
            x = (u1[node_pos[j, d]] - u0[node_pos[j, d]]) - centre[d]
            r += x * x
        bound = max(bound, np.sqrt(r) + _SHAPE_SUM * spread)
    return bound


def step_penetration(spec: SurfacePair, radius: float, allowed: np.ndarray,
                     start: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
                     node_X: np.ndarray, node_pos: np.ndarray, master_X: np.ndarray,
                     pos_m: np.ndarray, u0: np.ndarray, u1: np.ndarray
                     ) -> tuple[str | None, float]:
    """Why a step leaves a slave node beyond what the search sees (None: it does not).

    Every rank holds the same arrays and takes the same decision.

    Args:
        spec: The pair.
        radius: Its search radius (m).
        allowed: :func:`allowed_depth` of each master facet.
        start: The slave nodes' projection at the start of the step: master facet
            (−1: none within the radius), its shape functions at ξ̄₀, the unit tangent
            there (master facets oriented: ``(t_y, −t_x)`` is outward) and whether it is
            a projection (False: the nearest end of the master surface).
        node_X: The slave nodes' reference positions ``(K, gdim)``.
        node_pos: Their interface positions ``(K, gdim)`` (−1: Dirichlet).
        master_X: The master facets' reference nodes ``(F, nn, gdim)``.
        pos_m: Their interface positions.
        u0: Displacements at the interface unknowns at the start of the step (with
            the trailing 0 of the Dirichlet entries).
        u1: The same at the end of the step.

    Returns:
        The reason, and the largest depth of a slave node below its start-of-step
        master point at the end of the step (0 if none is below).
    """
    facet, N0, t0, projected = start
    du_s = u1[node_pos] - u0[node_pos]
    du_m = u1[pos_m] - u0[pos_m]
    has = facet >= 0
    moved = np.empty(len(facet))
    if has.any():
        rel = du_s[has] - np.einsum("kn,knd->kd", N0[has], du_m[facet[has]])
        moved[has] = np.linalg.norm(rel, axis=1)
    reach = np.full(len(facet), radius)
    if not has.all():
        moved[~has] = _motion_bound(du_s[~has], du_m)[0]
        # Farther than r from the surface, and at least as far as its bounding box.
        xm0 = (master_X + u0[pos_m]).reshape(-1, du_m.shape[-1])
        x0 = node_X[~has] + u0[node_pos[~has]]
        out = np.maximum(np.maximum(xm0.min(axis=0) - x0, x0 - xm0.max(axis=0)), 0.0)
        reach[~has] = np.maximum(radius, np.linalg.norm(out, axis=1))
    x1 = node_X + u1[node_pos]
    # Depth below the start-of-step master point, as a fraction of what the pair sees.
    depth, limit, deep = np.zeros(len(facet)), np.ones(len(facet)), np.zeros(len(facet))
    k = np.flatnonzero(has & projected)
    if len(k):
        f = facet[k]
        n = np.stack([t0[k, 1], -t0[k, 0]], axis=1)
        # A node that starts the step beyond what the pair sees below its master point
        # is not under it (by induction no accepted state has one): a node in a concave
        # master corner, inside neither side's range, projects onto a facet beyond them
        # (the crest beside a notch, 0.4 m above a wall's shear key; the step was refused).
        x0 = node_X[k] + u0[node_pos[k]]
        x_bar0 = np.einsum("kn,knd->kd", N0[k], master_X[f] + u0[pos_m[f]])
        seen = -np.sum((x0 - x_bar0) * n, axis=1) <= allowed[f]
        k, f, n = k[seen], f[seen], n[seen]
        x_bar = np.einsum("kn,knd->kd", N0[k], master_X[f] + u1[pos_m[f]])
        depth[k] = -np.sum((x1[k] - x_bar) * n, axis=1)
        limit[k] = allowed[f]
        deep[k] = depth[k] / limit[k]
    fast = moved / reach
    deepest = float(depth.max(initial=0.0))
    if max(deep.max(initial=0.0), fast.max(initial=0.0)) <= 1.0:
        return None, deepest
    if deep.max() >= fast.max():
        j = int(np.argmax(deep))
        return (f"contact '{spec.name}': slave node at {_point(x1[j])} ends the step "
                f"{depth[j]:.3g} m inside the master '{spec.master}', deeper than the "
                f"contact sees ({limit[j]:.3g} m: the search radius or the master's element "
                "under it; the penalty is too soft to stop it, or the step too large)"), deepest
    j = int(np.argmax(fast))
    return (f"contact '{spec.name}': slave node at {_point(x1[j])} moves {moved[j]:.3g} m "
            f"relative to the master '{spec.master}' in one step, more than "
            + (f"the contact search radius {radius:.3g} m" if reach[j] == radius else
               f"its distance {reach[j]:.3g} m from the master surface")
            + " (it could pass through the master unseen)"), deepest


class StepCheck:
    """:func:`step_penetration` of one pair at every step, with a screen that skips it.

    A step that starts from the end of a checked one (the same interface
    displacements, bit for bit) at which every slave node was at most D deep needs no
    projection when its motion bound B (:func:`_motion_bound`: every node's motion
    relative to every master point) keeps ``B ≤ r`` and ``D + B ≤ ½ min(allowed)``:
    no node can then end it deeper than ``D + B``, nor cross the surface from beyond
    the radius. The bound D + B is carried to the next step, and a full check (one
    projection of the slave nodes) resets it. A body at rest or sliding slowly is then
    checked with a handful of array operations per step.

    Args:
        spec: The pair.
        radius: Its search radius (m).
        allowed: :func:`allowed_depth` of each master facet.
        node_X: The slave nodes' reference positions.
        node_pos: Their interface positions.
        master_X: The master facets' reference nodes.
        pos_m: Their interface positions.
    """

    def __init__(self, spec: SurfacePair, radius: float, allowed: np.ndarray,
                 node_X: np.ndarray, node_pos: np.ndarray, master_X: np.ndarray,
                 pos_m: np.ndarray) -> None:
        self.spec, self.radius, self.allowed = spec, radius, allowed
        self.node_X, self.node_pos, self.master_X, self.pos_m = node_X, node_pos, master_X, pos_m
        self.floor = 0.5 * float(allowed.min()) if len(allowed) else 0.0
        self._screen: tuple[np.ndarray, float] | None = None  # (u at its end, depth bound)
        self.full_checks = 0

    def __call__(self, u0: np.ndarray, u1: np.ndarray,
                 start: Callable[[], tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]
                 ) -> str | None:
        """The reason the step from u0 to u1 is rejected, or None.

        Args:
            u0: Interface displacements at the start of the step (trailing 0).
            u1: At its end, as the accepted state will hold them.
            start: Gives the slave nodes' start-of-step projection (called only for a
                full check; see :func:`step_penetration`).
        """
        if self._screen is not None and equal(self._screen[0], u0):
            bound = float(screen_bound(u0, u1, self.node_pos, self.pos_m))
            depth = self._screen[1] + bound
            if bound <= self.radius and depth <= self.floor:
                self._screen = (u1.copy(), depth)
                return None
        self.full_checks += 1
        why, deepest = step_penetration(self.spec, self.radius, self.allowed, start(),
                                        self.node_X, self.node_pos, self.master_X,
                                        self.pos_m, u0, u1)
        self._screen = (u1.copy(), deepest) if why is None else None
        return why
