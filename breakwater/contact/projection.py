"""Closest-point projection onto a surface of line facets (2-D), vectorised NumPy.

A facet is a Lagrange curve through ``nn`` nodes on the local coordinate ξ ∈ [−1, 1]:
two nodes (straight segment, ξ = −1, 1) or three (quadratic curve, ξ = −1, 1, 0: the
two vertices and the mid-edge node, the order of a P2 facet's closure DOFs). Its
position is ``x(ξ) = Σ_k N_k(ξ) x_k``.

The closest point of p on a facet solves ``f(ξ) = (x(ξ) − p)·x'(ξ) = 0`` (the paper's §2,
eqs. 5-6) by Newton's method. Every routine is written with analytic operations only,
so that it runs in complex arithmetic too: a complex-step derivative of anything built
on it (:mod:`breakwater.contact.general`) then includes the implicit dependence of the
projection on the nodes and on p exactly. Decisions (which facet, inside or not) are
taken on real parts.

The candidate facets of each point come from a uniform grid of the facets' bounding
boxes (:class:`FacetGrid`): O(points + facets), not all pairs. A projection is kept
if it falls inside its facet (``|ξ| ≤ 1 + tol``); of several, the nearest wins, so a point
whose projection leaves one facet continues onto the neighbour. A point with no
projection within the search radius (beyond a convex corner, past the end of the
surface, or farther than the radius) has none: it is out of contact.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["FACING", "INSIDE", "STEP_TOL", "FacetGrid", "closest_point", "curve", "near", "project",
           "shape"]

#: The search's projection Newton stops at a point after a |Δξ| below this. Newton
#: converges quadratically: after a step below 1e-12 the error is of its square,
#: round-off. A tighter test is below the round-off of ξ itself on a curved facet (its
#: steps wander at 1e-14).
STEP_TOL = 1e-12


def shape(xi: Any, nn: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """1-D Lagrange shape functions, first and second derivatives at ξ.

    Args:
        xi: Local coordinates, shape ``(m,)`` (real or complex).
        nn: Nodes per facet: 2 (ξ = −1, 1) or 3 (ξ = −1, 1, 0).

    Returns:
        N, N', N'' each of shape ``(m, nn)``.
    """
    xi = np.asarray(xi)
    if nn not in (2, 3):
        raise ValueError(f"facets of {nn} nodes are not supported (2 or 3)")
    N, dN, d2N = (np.empty((*xi.shape, nn), dtype=np.result_type(xi, float))
                  for _ in range(3))
    if nn == 2:
        N[..., 0], N[..., 1] = 0.5 * (1 - xi), 0.5 * (1 + xi)
        dN[..., 0], dN[..., 1] = -0.5, 0.5
        d2N[...] = 0.0
    else:
        N[..., 0], N[..., 1], N[..., 2] = 0.5 * xi * (xi - 1), 0.5 * xi * (xi + 1), 1 - xi * xi
        dN[..., 0], dN[..., 1], dN[..., 2] = xi - 0.5, xi + 0.5, -2 * xi
        d2N[..., :2], d2N[..., 2] = 1.0, -2.0
    return N, dN, d2N


def curve(nodes: np.ndarray, xi: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position x(ξ), tangent x'(ξ) and x''(ξ) of facets.

    Args:
        nodes: Node positions, shape ``(m, nn, gdim)``.
        xi: Local coordinate per facet, shape ``(m,)``.

    Returns:
        Three arrays of shape ``(m, gdim)``.
    """
    N, dN, d2N = shape(xi, nodes.shape[1])
    return (np.einsum("mk,mkd->md", N, nodes), np.einsum("mk,mkd->md", dN, nodes),
            np.einsum("mk,mkd->md", d2N, nodes))


def closest_point(points: np.ndarray, nodes: np.ndarray, xi: np.ndarray | None = None,
                  iterations: int = 30, tol: float = 1e-14) -> np.ndarray:
    """Local coordinate of the closest point of each point on its facet (Newton).

    Args:
        points: Shape ``(m, gdim)``.
        nodes: The facet of each point, shape ``(m, nn, gdim)``.
        xi: Newton's start (default: the projection onto the chord).
        iterations: At most this many Newton steps (each iterate is kept in [−2, 2]).
        tol: Each point stops after a real ``|Δξ|`` below this (a NaN step does not
            stop it), or when its clip at ±2 returns the iterate it started from (a
            fixed point: every further iteration is the same).

    Returns:
        ξ, shape ``(m,)``; complex if any input is.
    """
    if xi is None:
        a, b = nodes[:, 0], nodes[:, 1]
        chord = b - a
        xi = 2 * np.sum((points - a) * chord, axis=1) / np.sum(chord * chord, axis=1) - 1
    xi = np.asarray(xi) + 0 * points[:, 0]  # a new array: changed in place below
    going = np.arange(len(xi))
    for _ in range(iterations):
        if not len(going):
            break
        x, dx, d2x = curve(nodes[going], xi[going])
        r = x - points[going]
        f = np.sum(r * dx, axis=1)
        df = np.sum(dx * dx, axis=1) + np.sum(r * d2x, axis=1)
        step = f / df
        old = xi[going]
        new = old - step
        real = np.real(new)
        new = np.where(np.abs(real) > 2, np.clip(real, -2, 2), new)
        xi[going] = new
        going = going[~((np.abs(np.real(step)) < tol) | (new == old))]
    return xi


class FacetGrid:
    """A uniform grid of facet bounding boxes for the candidate search.

    Args:
        nodes: Facet node positions, shape ``(F, nn, gdim)`` (real).
        radius: Search radius: a facet is a candidate of a point within ``radius`` of
            its bounding box.
    """

    def __init__(self, nodes: np.ndarray, radius: float) -> None:
        nodes = np.real(nodes)
        self.radius = radius
        lo = nodes.min(axis=1) - radius
        hi = nodes.max(axis=1) + radius
        self.origin = lo.min(axis=0) if len(nodes) else np.zeros(nodes.shape[-1])
        self.cell = float(np.max(hi - lo)) if len(nodes) else 1.0
        ilo = np.floor((lo - self.origin) / self.cell).astype(np.int64)
        ihi = np.floor((hi - self.origin) / self.cell).astype(np.int64)
        self.shape = (ihi.max(axis=0) + 1) if len(nodes) else np.ones(nodes.shape[-1], int)
        # Each facet in every grid cell its box touches (at most 2^gdim cells: the
        # cell size is the largest box).
        keys, owners = [], []
        for offset in np.ndindex(*(2,) * nodes.shape[-1]):
            idx = ilo + np.array(offset)
            inside = np.all(idx <= ihi, axis=1)
            keys.append(self._key(idx[inside]))
            owners.append(np.flatnonzero(inside))
        key = np.concatenate(keys)
        owner = np.concatenate(owners)
        order = np.lexsort((owner, key))
        self.keys, self.facets = key[order], owner[order]

    def _key(self, idx: np.ndarray) -> np.ndarray:
        key = np.zeros(len(idx), np.int64)
        for d in range(idx.shape[1]):
            key = key * (int(self.shape[d]) + 2) + (idx[:, d] + 1)
        return key

    def candidates(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(point, facet) index pairs: the facets whose inflated box holds each point."""
        points = np.real(points)
        idx = np.floor((points - self.origin) / self.cell).astype(np.int64)
        ok = np.all((idx >= 0) & (idx < self.shape), axis=1)
        key = np.where(ok, self._key(np.where(ok[:, None], idx, -1)), -1)
        lo = np.searchsorted(self.keys, key, side="left")
        hi = np.searchsorted(self.keys, key, side="right")
        counts = np.where(ok, hi - lo, 0)
        point = np.repeat(np.arange(len(points)), counts)
        start = np.repeat(lo - np.cumsum(counts) + counts, counts)
        facet = self.facets[start + np.arange(counts.sum())] if counts.sum() else \
            np.zeros(0, np.int64)
        return point, facet


FACING = -0.1
"""A slave point projects onto a master facet only where their outward normals oppose:
n_s · n_m below this (within 84° of opposite, as :data:`breakwater.contact.facing.OPPOSED`
for surfaces)."""

INSIDE = 1e-9
"""A projection at ``|ξ| ≤ 1 + INSIDE`` is inside its facet (round-off; :func:`project`)."""


def project(points: np.ndarray, nodes: np.ndarray, grid: FacetGrid,
            tol: float = INSIDE) -> tuple[np.ndarray, np.ndarray]:
    """Closest-point projection of points onto a surface of facets (real arithmetic).

    Args:
        points: Shape ``(m, gdim)``.
        nodes: Facet node positions, shape ``(F, nn, gdim)``.
        grid: The candidate search of these facets.
        tol: A projection at ``|ξ| ≤ 1 + tol`` is inside its facet.

    Returns:
        The facet of each point (−1: no projection) and its local coordinate ξ.
    """
    m = len(points)
    facet = np.full(m, -1, np.int64)
    xi_out = np.zeros(m)
    point, cand = near(points, *grid.candidates(points), nodes, grid.radius, tol)
    if not len(point):
        return facet, xi_out
    xi = np.real(closest_point(points[point], nodes[cand], iterations=8, tol=STEP_TOL))
    x, dx, _ = curve(nodes[cand], xi)
    r = x - points[point]
    dist = np.sum(r * r, axis=1)
    # Converged: the residual (x − p)·x' vanishes to round-off of the facet's size.
    stationary = np.abs(np.sum(r * dx, axis=1)) <= 1e-10 * np.sum(dx * dx, axis=1)
    ok = (np.abs(xi) <= 1 + tol) & (dist <= grid.radius ** 2) & stationary
    point, cand, xi, dist = point[ok], cand[ok], xi[ok], dist[ok]
    best = _nearest_per_point(point, cand, dist)
    facet[point[best]] = cand[best]
    xi_out[point[best]] = np.clip(xi[best], -1, 1)
    return facet, xi_out


def near(points: np.ndarray, point: np.ndarray, cand: np.ndarray, nodes: np.ndarray,
         radius: float, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """The (point, facet) pairs whose projection :func:`project` can accept.

    A projection is accepted within ``radius`` of x(ξ), |ξ| ≤ 1 + tol. Per coordinate,
    x(ξ) = a + bξ + cξ² (c = ½(x₋₁ + x₁) − x₀ for 3 nodes, 0 for 2) stays within the
    nodes' range widened by |c| for |ξ| ≤ 1 (a parabola overshoots the nearer end of
    its range by c(1 ∓ ξ*)² ≤ |c|), and moves less than (|b| + 3|c|)·tol beyond ±1
    (tol ≤ 1). The grid's candidates (boxes of the nodes, cells of several facets)
    outside that range widened by ``radius`` cannot be accepted: dropped before the
    projection's Newton, which runs all pairs in lockstep (on the separately meshed
    Goda case the grid gave 8.4 candidates a point, this leaves about 2).
    """
    if not len(point):
        return point, cand
    X = np.real(nodes[cand])  # (pairs, nn, gdim)
    lo, hi = X.min(axis=1), X.max(axis=1)
    b = 0.5 * np.abs(X[:, 1] - X[:, 0])
    c = np.abs(0.5 * (X[:, 0] + X[:, 1]) - X[:, 2]) if X.shape[1] == 3 else np.zeros_like(b)
    margin = radius + c + tol * (b + 3 * c)
    x = np.real(points[point])
    keep = np.all((x >= lo - margin) & (x <= hi + margin), axis=1)
    return point[keep], cand[keep]


def _nearest_per_point(point: np.ndarray, cand: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """The index of each point's nearest (point, facet, squared distance) triple.

    Ties go to the lowest facet index.
    """
    order = np.lexsort((cand, dist, point))
    first = np.ones(len(order), bool)
    first[1:] = point[order][1:] != point[order][:-1]
    return order[first]


def nearest_end(points: np.ndarray, nodes: np.ndarray, grid: FacetGrid
                ) -> tuple[np.ndarray, np.ndarray]:
    """The nearest facet end (vertex) of each point within the search radius.

    For points that have no projection (beyond the end of the surface): the
    surface's closest point is then a vertex, ``ξ = ±1`` of a facet.

    Args:
        points: Shape ``(m, gdim)``.
        nodes: Facet node positions, shape ``(F, nn, gdim)`` (the two vertices first).
        grid: The candidate search of these facets.

    Returns:
        The facet of each point (−1: no vertex within the radius) and ξ (±1).
    """
    m = len(points)
    facet = np.full(m, -1, np.int64)
    xi_out = np.zeros(m)
    point, cand = grid.candidates(points)
    if not len(point):
        return facet, xi_out
    ends = nodes[cand][:, :2]  # (pairs, 2, gdim)
    dist = np.sum((ends - points[point][:, None]) ** 2, axis=2)
    end = np.argmin(dist, axis=1)
    dist = dist[np.arange(len(end)), end]
    ok = dist <= grid.radius ** 2
    point, cand, end, dist = point[ok], cand[ok], end[ok], dist[ok]
    best = _nearest_per_point(point, cand, dist)
    facet[point[best]] = cand[best]
    xi_out[point[best]] = np.where(end[best] == 0, -1.0, 1.0)
    return facet, xi_out
