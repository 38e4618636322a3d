"""The 3-D general pair's nodal pressure (:mod:`breakwater.contact.nodalpressure3d`)."""

from __future__ import annotations

import numpy as np
import pytest

from breakwater.contact.clip3d import rule
from breakwater.contact.nodalpressure3d import VertexPressure, linear_basis
from breakwater.contact.projection3d import shape
from breakwater.contact.surfacesearch3d import area_element


def _square(order: int) -> tuple[np.ndarray, np.ndarray, int]:
    """The unit square z = 0 in two triangles (3 or 6 nodes, basix's order)."""
    corners = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    faces = [(0, 1, 2), (0, 2, 3)]
    X, node_of, nodes = [], [], {tuple(c): i for i, c in enumerate(corners)}
    for f in faces:
        pts = [corners[i] for i in f]
        if order == 2:
            pts += [0.5 * (pts[a] + pts[b]) for a, b in ((1, 2), (0, 2), (0, 1))]
        X.append(pts)
        node_of.append([nodes.setdefault(tuple(p), len(nodes)) for p in pts])
    return np.array(X), np.array(node_of), len(nodes)


@pytest.mark.parametrize("order", [1, 2])
def test_uniform_pressure_is_exact_and_conserved(order: int) -> None:
    X, node_of, n = _square(order)
    g, w = rule(3)
    faces = np.repeat(np.arange(len(X)), len(w))
    xi = np.tile(g, (len(X), 1))
    weight = np.tile(w, len(X)) * area_element(X[faces], xi)
    Ns = shape(xi, X.shape[1])[0]
    project = VertexPressure(X, node_of, n, area_element)
    # ∫ L_v dS over the square: its vertex hats' integrals (area 1, shared by 4 vertices:
    # 1/6 at each corner of one triangle, 2 × 1/6 at the diagonal's ends).
    assert project.weight[:4] == pytest.approx([1 / 3, 1 / 6, 1 / 3, 1 / 6], rel=1e-14)
    p = project(faces, Ns, weight, np.full(len(faces), 2.5e6))
    assert p == pytest.approx(np.full(n, 2.5e6), rel=1e-14)  # every node, mid-edge too
    # Any pressure: the nodal field is ≥ 0 and carries ∫p dS.
    rng = np.random.default_rng(3)
    q = rng.uniform(0.0, 1.0, len(faces)) * (rng.uniform(size=len(faces)) > 0.4)
    nodal = project(faces, Ns, weight, q)
    assert nodal.min() >= 0.0
    assert project.weight @ nodal == pytest.approx(np.sum(q * weight), rel=1e-13)


def test_linear_basis_of_the_quadratic_triangle() -> None:
    # The quadratic basis reproduces the linear functions: L from N equals the
    # barycentric coordinates (1 − ξ − η, ξ, η).
    xi = np.random.default_rng(1).uniform(0.0, 0.5, (7, 2))
    L = linear_basis(shape(xi, 6)[0])
    assert L == pytest.approx(np.column_stack([1 - xi.sum(1), xi[:, 0], xi[:, 1]]), abs=1e-14)
