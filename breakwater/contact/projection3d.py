"""Closest-point projection onto a surface of triangular faces (3-D), vectorised NumPy.

The 3-D counterpart of :mod:`breakwater.contact.projection` (issue 25), not yet used by a
pair. A face is a Lagrange triangle through ``nn`` nodes on the reference triangle
``ξ ≥ 0, η ≥ 0, ξ + η ≤ 1``: three nodes (flat, the vertices (0, 0), (1, 0), (0, 1)) or
six (quadratic: the vertices, then the mid-edge nodes of the edges (1, 2), (0, 2),
(0, 1), i.e. at (½, ½), (0, ½), (½, 0)). Six is the order of a P2 tetrahedron's facet
closure DOFs in dolfinx (basix's triangle: edge k is opposite vertex k;
``tests/test_projection3d.py`` checks it on a mesh); gmsh's 6-node triangle numbers the
mid-edge nodes (0, 1), (1, 2), (2, 0) instead: ``nodes[:, GMSH_TO_BASIX]`` of a gmsh
triangle is in this order. The face's position is ``x(ξ) = Σ_k N_k(ξ) x_k``.

The closest point of p on a face solves ``f(ξ) = ((x(ξ) − p)·x_ξ, (x(ξ) − p)·x_η) = 0``
by Newton's method (Jacobian ``J_ab = x_a·x_b + (x − p)·x_ab``, solved in closed form).
Every routine is written with analytic operations only, so that it runs in complex
arithmetic too (a complex-step derivative of anything built on it then includes the
implicit dependence of the projection on the nodes and on p); decisions (which face,
inside or not) are taken on real parts.

The candidate faces of each point come from :class:`~breakwater.contact.projection.FacetGrid`,
which is written for any dimension (a uniform grid of the faces' bounding boxes). A
projection is kept if it falls inside its face (:func:`inside`); of several, the
nearest wins, so a point whose projection leaves one face continues onto the
neighbour. A point with no projection within the search radius (beyond a convex edge
or corner, past the surface's boundary, or farther than the radius) has none.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from breakwater.contact.projection import INSIDE, STEP_TOL, FacetGrid

__all__ = ["FLIP", "GMSH_TO_BASIX", "INSIDE", "NODES", "STEP_TOL", "FacetGrid", "closest_point",
           "inside", "near", "project", "residual", "shape", "surface", "unit_normal"]

GMSH_TO_BASIX = np.array([0, 1, 2, 4, 5, 3])
"""``nodes[:, GMSH_TO_BASIX]`` of a gmsh 6-node triangle are in this module's order."""

FLIP = np.array([0, 2, 1, 3, 5, 4])
"""``nodes[:, FLIP[:nn]]`` is the same face with the opposite normal (vertices 1 and 2
swapped, and with them the mid-edge nodes of the edges (0, 2) and (0, 1))."""

NODES = {3: np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]),
         6: np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.5, 0.5], [0.0, 0.5],
                      [0.5, 0.0]])}
"""The reference coordinates (ξ, η) of a face's nodes, by node count."""

# The barycentric coordinates' gradients (∂/∂ξ, ∂/∂η): L₀ = 1 − ξ − η, L₁ = ξ, L₂ = η.
_DL = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])
# The mid-edge nodes' edges (a, b): node 3 + k joins the two vertices other than k.
_EDGES = ((1, 2), (0, 2), (0, 1))
# The second derivatives' index pairs, in the order ξξ, ξη, ηη.
_PAIRS = ((0, 0), (0, 1), (1, 1))
# Newton keeps each coordinate of its iterate in [−1, 2]: a face's width beyond it.
_LO, _HI = -1.0, 2.0


def shape(xi: Any, nn: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triangle Lagrange shape functions and their first and second derivatives.

    Args:
        xi: Reference coordinates (ξ, η), shape ``(m, 2)`` (real or complex).
        nn: Nodes per face: 3 (linear) or 6 (quadratic, :data:`NODES` order).

    Returns:
        N ``(m, nn)``; ∂N ``(m, nn, 2)`` (∂/∂ξ, ∂/∂η); ∂²N ``(m, nn, 3)`` (ξξ, ξη, ηη).
    """
    xi = np.asarray(xi)
    if nn not in (3, 6):
        raise ValueError(f"faces of {nn} nodes are not supported (3 or 6)")
    m = xi.shape[0]
    dtype = np.result_type(xi, float)
    L = (1 - xi[:, 0] - xi[:, 1], xi[:, 0], xi[:, 1])
    N = np.empty((m, nn), dtype)
    dN = np.empty((m, nn, 2), dtype)
    d2N = np.zeros((m, nn, 3), dtype)
    if nn == 3:
        for k in range(3):
            N[:, k] = L[k]
            dN[:, k] = _DL[k]
        return N, dN, d2N
    for k in range(3):  # vertices: L_k (2 L_k − 1)
        N[:, k] = L[k] * (2 * L[k] - 1)
        dN[:, k] = (4 * L[k] - 1)[:, None] * _DL[k]
        for c, (i, j) in enumerate(_PAIRS):
            d2N[:, k, c] = 4 * _DL[k, i] * _DL[k, j]
    for k, (a, b) in enumerate(_EDGES):  # mid-edge nodes: 4 L_a L_b
        N[:, 3 + k] = 4 * L[a] * L[b]
        dN[:, 3 + k] = 4 * (L[b][:, None] * _DL[a] + L[a][:, None] * _DL[b])
        for c, (i, j) in enumerate(_PAIRS):
            d2N[:, 3 + k, c] = 4 * (_DL[a, i] * _DL[b, j] + _DL[a, j] * _DL[b, i])
    return N, dN, d2N


def surface(nodes: np.ndarray, xi: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position, tangents and second derivatives of faces at reference points.

    Args:
        nodes: Node positions, shape ``(m, nn, 3)``.
        xi: Reference coordinates per face, shape ``(m, 2)``.

    Returns:
        x ``(m, 3)``; the tangents x_ξ, x_η ``(m, 2, 3)``; x_ξξ, x_ξη, x_ηη ``(m, 3, 3)``.
    """
    N, dN, d2N = shape(xi, nodes.shape[1])
    return (np.einsum("mk,mkd->md", N, nodes), np.einsum("mka,mkd->mad", dN, nodes),
            np.einsum("mkc,mkd->mcd", d2N, nodes))


def unit_normal(dx: np.ndarray) -> np.ndarray:
    """The unit normal ``x_ξ × x_η / |x_ξ × x_η|`` from the tangents ``(m, 2, 3)``.

    Analytic (``sqrt(n·n)``, not ``|n|``): a complex step differentiates it.
    """
    a, b = dx[:, 0], dx[:, 1]
    n = np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
                  a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                  a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)
    return n / np.sqrt(np.sum(n * n, axis=1))[:, None]


def residual(points: np.ndarray, nodes: np.ndarray, xi: Any) -> np.ndarray:
    """The closest-point conditions ``((x − p)·x_ξ, (x − p)·x_η)``, shape ``(m, 2)``."""
    x, dx, _ = surface(nodes, xi)
    return np.einsum("md,mad->ma", x - points, dx)


def _flat_start(points: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """The reference coordinates of each point's foot on its face's vertex plane."""
    o = nodes[:, 0]
    e = np.stack([nodes[:, 1] - o, nodes[:, 2] - o], axis=1)  # (m, 2, 3)
    G = np.einsum("mad,mbd->mab", e, e)
    r = np.einsum("mad,md->ma", e, points - o)
    det = G[:, 0, 0] * G[:, 1, 1] - G[:, 0, 1] * G[:, 1, 0]
    return np.stack([G[:, 1, 1] * r[:, 0] - G[:, 0, 1] * r[:, 1],
                     G[:, 0, 0] * r[:, 1] - G[:, 1, 0] * r[:, 0]], axis=1) / det[:, None]


def closest_point(points: np.ndarray, nodes: np.ndarray, xi: np.ndarray | None = None,
                  iterations: int = 30, tol: float = 1e-14) -> np.ndarray:
    """Reference coordinates of the closest point of each point on its face (Newton).

    Args:
        points: Shape ``(m, 3)``.
        nodes: The face of each point, shape ``(m, nn, 3)``.
        xi: Newton's start (default: the foot of the perpendicular on the plane of the
            face's vertices, exact for a flat face).
        iterations: At most this many Newton steps (each coordinate of an iterate is kept
            in [−1, 2]).
        tol: Each point stops after a real step below this in both coordinates (a NaN
            step does not stop it), or when its clip returns the iterate it started
            from (a fixed point: every further iteration is the same).

    Returns:
        (ξ, η), shape ``(m, 2)``; complex if any input is.
    """
    if xi is None:
        xi = _flat_start(points, nodes)
    xi = np.asarray(xi) + 0 * points[:, :2]  # a new array: changed in place below
    going = np.arange(len(xi))
    for _ in range(iterations):
        if not len(going):
            break
        x, dx, d2x = surface(nodes[going], xi[going])
        r = x - points[going]
        f = np.einsum("md,mad->ma", r, dx)
        J = np.einsum("mad,mbd->mab", dx, dx)
        rd = np.einsum("md,mcd->mc", r, d2x)  # (x − p)·x_ξξ, ·x_ξη, ·x_ηη
        J[:, 0, 0] += rd[:, 0]
        J[:, 0, 1] += rd[:, 1]
        J[:, 1, 0] += rd[:, 1]
        J[:, 1, 1] += rd[:, 2]
        det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
        step = np.stack([J[:, 1, 1] * f[:, 0] - J[:, 0, 1] * f[:, 1],
                         J[:, 0, 0] * f[:, 1] - J[:, 1, 0] * f[:, 0]], axis=1) / det[:, None]
        old = xi[going]
        new = old - step
        real = np.real(new)
        new = np.where((real < _LO) | (real > _HI), np.clip(real, _LO, _HI), new)
        xi[going] = new
        small = np.all(np.abs(np.real(step)) < tol, axis=1)
        going = going[~(small | np.all(new == old, axis=1))]
    return xi


def inside(xi: np.ndarray, tol: float = INSIDE) -> np.ndarray:
    """Whether reference points lie in the triangle: ξ ≥ −tol, η ≥ −tol, ξ + η ≤ 1 + tol.

    Args:
        xi: Shape ``(m, 2)`` (real parts are tested).
        tol: The round-off allowed beyond the edges.
    """
    xi = np.real(xi)
    return (xi[:, 0] >= -tol) & (xi[:, 1] >= -tol) & (xi[:, 0] + xi[:, 1] <= 1 + tol)


def _clip_inside(xi: np.ndarray) -> np.ndarray:
    """The nearest point of the reference triangle to each (real) point within ``tol``."""
    xi = np.maximum(xi, 0.0)
    over = np.maximum(xi.sum(axis=1) - 1, 0.0)
    return xi - 0.5 * over[:, None]


def project(points: np.ndarray, nodes: np.ndarray, grid: FacetGrid, tol: float = INSIDE,
            iterations: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """Closest-point projection of points onto a surface of faces (real arithmetic).

    Each candidate (point, face) pair runs :func:`closest_point` from the flat start; a
    projection counts if it is stationary (the conditions vanish to 1e-10 of
    ``|x_ξ|² + |x_η|²``: converged), :func:`inside` its face and within the grid's
    radius; the nearest counts per point (ties: the lowest face index).

    Args:
        points: Shape ``(m, 3)``.
        nodes: Face node positions, shape ``(F, nn, 3)``.
        grid: The candidate search of these faces (:class:`FacetGrid` of ``nodes``).
        tol: Inside-test tolerance (:func:`inside`).
        iterations: Newton steps at most (with the stop of :data:`STEP_TOL`).

    Returns:
        The face of each point (−1: no projection) and its (ξ, η) (moved onto the
        triangle by at most ``tol``), shapes ``(m,)`` and ``(m, 2)``.
    """
    m = len(points)
    face = np.full(m, -1, np.int64)
    xi_out = np.zeros((m, 2))
    point, cand = near(points, *grid.candidates(points), nodes, grid.radius, tol)
    if not len(point):
        return face, xi_out
    xi = np.real(closest_point(points[point], nodes[cand], iterations=iterations,
                               tol=STEP_TOL))
    x, dx, _ = surface(nodes[cand], xi)
    r = x - points[point]
    dist = np.sum(r * r, axis=1)
    f = np.einsum("md,mad->ma", r, dx)
    scale = np.sum(dx * dx, axis=(1, 2))
    stationary = np.all(np.abs(f) <= 1e-10 * scale[:, None], axis=1)
    ok = inside(xi, tol) & (dist <= grid.radius ** 2) & stationary
    point, cand, xi, dist = point[ok], cand[ok], xi[ok], dist[ok]
    order = np.lexsort((cand, dist, point))
    first = np.ones(len(order), bool)
    first[1:] = point[order][1:] != point[order][:-1]
    best = order[first]
    face[point[best]] = cand[best]
    xi_out[point[best]] = _clip_inside(xi[best])
    return face, xi_out


def near(points: np.ndarray, point: np.ndarray, cand: np.ndarray, nodes: np.ndarray,
         radius: float, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """The (point, face) pairs whose projection :func:`project` can accept.

    Per coordinate, a face is ``x = x₀ + ξ(x₁ − x₀) + η(x₂ − x₀) + Σ_e 4 L_a L_b c_e``
    with ``c_e`` the mid-edge node's offset from its edge's midpoint (0 on a flat
    face). On the triangle widened by ``tol`` each barycentric coordinate lies in
    [−2 tol, 1 + 2 tol], so each ``4 L_a L_b ≤ (1 + 2 tol)²`` and ≥ −8 tol(1 + 2 tol);
    the linear part leaves the vertices' range by at most 2 tol (|x₁ − x₀| + |x₂ − x₀|).
    Candidates of the grid (boxes of the nodes, cells of several faces) outside the
    nodes' range widened by that and ``radius`` cannot be accepted: dropped before the
    projection's Newton, which runs all pairs in lockstep.
    """
    if not len(point):
        return point, cand
    X = np.real(nodes[cand])  # (pairs, nn, 3)
    lo, hi = X.min(axis=1), X.max(axis=1)
    linear = np.abs(X[:, 1] - X[:, 0]) + np.abs(X[:, 2] - X[:, 0])
    c = np.zeros_like(lo)
    if X.shape[1] == 6:
        for k, (a, b) in enumerate(_EDGES):
            c += np.abs(X[:, 3 + k] - 0.5 * (X[:, a] + X[:, b]))
    margin = radius + c * (1 + 2 * tol) ** 2 + 2 * tol * linear
    x = np.real(points[point])
    keep = np.all((x >= lo - margin) & (x <= hi + margin), axis=1)
    return point[keep], cand[keep]
