"""The mortar segmentation of a 3-D slave surface (breakwater.contact.clip3d).

Two independent triangulations of the same flat square (slave and master facets of
sizes in the ratios 1.5 and 1.7, jittered, diagonals the other way, the master facing the
slave across a gap, the square in a rotated plane): the integration points' weights sum
to the square's area and integrate x, y, x², xy exactly (to 1e-12), and each point's
master face holds its closest-point projection; a slave triangle partly outside the
master surface gets the overlap's area; coinciding meshes give each slave face its own
master face; the compiled segmentation (searchkernels3d) gives the same points. Pure
array tests: serial only.
"""

from __future__ import annotations

import numpy as np
import pytest

from breakwater.contact import searchkernels3d
from breakwater.contact.clip3d import (
    ON_LINE,
    SLIVER,
    clip,
    integration_points,
    rule,
    segment_points,
)
from breakwater.contact.projection3d import closest_point, inside, shape, surface

pytestmark = pytest.mark.serial  # arrays alone (no MPI): once is enough

L = 1.3  # the square's side
# A rotation of the square's plane: its local axes u, v and normal w in space.
_Q, _ = np.linalg.qr(np.array([[0.8, -0.3, 0.5], [0.2, 0.9, -0.4], [0.6, 0.1, 0.7]]))
ORIGIN = np.array([0.3, -0.2, 1.1])


def _place(uvw: np.ndarray) -> np.ndarray:
    """Local coordinates (u, v, w) → space."""
    return ORIGIN + uvw @ _Q.T


def _local(x: np.ndarray) -> np.ndarray:
    """Space → local coordinates (u, v, w)."""
    return (x - ORIGIN) @ _Q


def _square(n: int, seed: int, flip: bool, w: float = 0.0, nn: int = 3,
            facing_down: bool = False, side: float = L, jitter: float = 0.25) -> np.ndarray:
    """Faces ``(2n², nn, 3)`` of the square [0, side]² at height w, in space: an n×n grid,
    interior vertices jittered by up to ``jitter`` h, each cell split along one diagonal
    (which one: ``flip``); normal +w, or −w (``facing_down``). 6 nodes: flat faces."""
    rng = np.random.default_rng(seed)
    s = np.linspace(0.0, side, n + 1)
    U, V = np.meshgrid(s, s, indexing="ij")
    shift = rng.uniform(-jitter, jitter, (2, n + 1, n + 1)) * side / n
    shift[:, [0, -1], :] = 0
    shift[:, :, [0, -1]] = 0
    P = np.stack([U + shift[0], V + shift[1], np.full_like(U, w)], axis=-1)
    faces = []
    for i in range(n):
        for j in range(n):
            a, b, c, d = P[i, j], P[i + 1, j], P[i + 1, j + 1], P[i, j + 1]
            faces.extend([(a, b, c), (a, c, d)] if flip else [(a, b, d), (b, c, d)])
    corners = np.array(faces)
    if facing_down:
        corners = corners[:, [0, 2, 1]]
    if nn == 6:
        mids = np.stack([0.5 * (corners[:, 1] + corners[:, 2]),
                         0.5 * (corners[:, 0] + corners[:, 2]),
                         0.5 * (corners[:, 0] + corners[:, 1])], axis=1)
        corners = np.concatenate([corners, mids], axis=1)
    return _place(corners)


def _surface_weights(slave: np.ndarray, face: np.ndarray, xi: np.ndarray,
                     weight: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The points in space and their surface weights w |x_ξ × x_η|."""
    x, dx, _ = surface(slave[face], xi)
    return x, weight * np.linalg.norm(np.cross(dx[:, 0], dx[:, 1]), axis=1)


@pytest.mark.parametrize(("n_slave", "n_master", "jitter", "flip"),
                         [(6, 4, 0.25, True), (17, 10, 0.25, True), (6, 3, 0.0, False)])
@pytest.mark.parametrize("nn", [3, 6])
def test_flat_patch_is_integrated_exactly(n_slave: int, n_master: int, jitter: float,
                                          flip: bool, nn: int) -> None:
    """∫1, ∫u, ∫v, ∫u², ∫uv over the square (L², L³/2, L³/2, L⁴/3, L⁴/4) from the points'
    surface weights to 1e-12 (a degree-2 rule on each overlap triangle: exact for
    quadratics, round-off ≈ 1e-15 a point), and each point's master face holds the
    closest-point projection of its position (at the gap's distance). Facet sizes in
    the ratios 1.5 and 1.7, jittered; and 2, nested (every master edge along slave
    edges: polygons of round-off area, which must be dropped, not given points)."""
    gap = 1e-3
    slave = _square(n_slave, 1, False, 0.0, nn, jitter=jitter)
    master = _square(n_master, 2, flip, gap, nn, facing_down=True, jitter=jitter)
    face, xi, weight, m_face = integration_points(slave, master, 0.01, degree=2, facing=True)
    assert np.all(weight >= SLIVER * rule(2)[1].min())  # no sliver: 2·area ≥ SLIVER
    x, w = _surface_weights(slave, face, xi, weight)
    u, v = _local(x)[:, 0], _local(x)[:, 1]
    for f, exact in ((1.0, L ** 2), (u, L ** 3 / 2), (v, L ** 3 / 2), (u * u, L ** 4 / 3),
                     (u * v, L ** 4 / 4)):
        assert abs(np.sum(w * f) - exact) < 1e-12
    # Each point's master face holds its projection (strictly: Gauss points are interior).
    zeta = closest_point(x, master[m_face])
    assert np.all(inside(zeta, 0.0))
    y = surface(master[m_face], zeta)[0]
    np.testing.assert_allclose(np.linalg.norm(y - x, axis=1), gap, rtol=1e-9)
    # Each slave face is covered: its weights sum to ½, its reference area.
    np.testing.assert_allclose(np.bincount(face, weight, len(slave)), 0.5, rtol=0, atol=1e-14)
    assert len(np.unique(m_face)) == len(master)


def test_a_slave_triangle_partly_outside_gets_the_overlap() -> None:
    """A slave triangle over the master square's corner gets the area of its part over
    the square: (½, ½), (3/2, ½), (½, 3/2) over [0, 1]² covers [½, 1]², ¼; (−½, 0.2),
    (0.6, 0.2), (−½, 0.9) covers 0.7·0.6²/(2·1.1) over u ≥ 0; one beyond it nothing."""
    master = _square(3, 3, True, 0.0, 3, facing_down=True, side=1.0)
    for corners, area in (([[0.5, 0.5], [1.5, 0.5], [0.5, 1.5]], 0.25),
                          ([[-0.5, 0.2], [0.6, 0.2], [-0.5, 0.9]], 0.7 * 0.36 / 2.2),
                          ([[1.1, 0.0], [2.0, 0.0], [1.1, 1.0]], 0.0)):
        slave = _place(np.column_stack([corners, np.zeros(3)]))[None]
        face, xi, weight, _ = integration_points(slave, master, 0.01, facing=True)
        _, w = _surface_weights(slave, face, xi, weight)
        assert abs(w.sum() - area) < 1e-14
        assert np.all(inside(xi, 1e-14))


def test_coinciding_meshes_pair_each_face_with_itself() -> None:
    """The same triangulation as slave and master: every slave face's points lie on its
    own master face alone, weights ½ each; the neighbours sharing its edges or corners
    leave nothing (their clipped polygons degenerate to the shared edge or corner)."""
    slave = _square(5, 4, False)
    master = slave[:, [0, 2, 1]]
    face, _, weight, m_face = integration_points(slave, master, 0.01, facing=True)
    np.testing.assert_array_equal(face, m_face)
    assert np.all(weight > SLIVER)
    np.testing.assert_allclose(np.bincount(face, weight), 0.5, rtol=0, atol=1e-14)


def test_facing_and_clip() -> None:
    """facing=True skips master faces whose normal does not oppose the slave's; clip()
    keeps a polygon holding the triangle as the triangle and drops one outside it."""
    slave = _square(2, 5, False)
    same_way = _square(3, 6, True, 1e-3)
    assert not len(integration_points(slave, same_way, 0.01, facing=True)[0])
    _, _, weight, _ = integration_points(slave, same_way, 0.01, facing=False)
    assert abs(weight.sum() - 0.5 * len(slave)) < 1e-13
    big = np.array([[-1.0, -1.0], [3.0, -1.0], [-1.0, 3.0]])
    polygon = clip(big)
    assert len(polygon) == 3
    assert {tuple(p) for p in np.round(polygon, 14)} == {(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)}
    assert not len(clip(np.array([[1.1, 0.0], [2.0, 0.0], [1.1, 1.0]])))
    # The degree of the rule: a single triangle (its master the same) integrates ξ⁵.
    tri = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    xi, weight, _ = segment_points(tri, tri[None], degree=5)
    assert abs(np.sum(weight * xi[:, 0] ** 5) - 1 / 42) < 1e-15  # ∫ξ⁵ = 5!·1!/7! = 1/42


def test_clip_decides_on_lines_not_round_off() -> None:
    """A master corner 1e-16 (round-off) or 3e-12 (past ON_LINE) inside or outside the
    hypotenuse gives the same five vertices (to 1e-11), and a master edge along η = 0
    whose ends are 1e-16 on either side of it adds no vertex along it: the polygon's
    vertices, and so its fan, do not depend on round-off (the segmentation of nested
    meshes, and the compiled one, agree)."""
    for eps in (1e-16, -1e-16, 3e-12, -3e-12):
        polygon = clip(np.array([[0.2, 0.8 + eps], [1.9, -0.9], [-1.5, 0.8]]))
        # The master's edges: η = 0.8, along ξ + η = 1, and η = 0.05 − ξ/2.
        expect = [[0.0, 0.8], [0.2, 0.8], [1.0, 0.0], [0.1, 0.0], [0.0, 0.05]]
        assert polygon.shape == (5, 2)
        np.testing.assert_allclose(polygon[np.lexsort(np.round(polygon, 9).T)],
                                   np.array(expect)[np.lexsort(np.array(expect).T)],
                                   rtol=0, atol=1e-11)
    polygon = clip(np.array([[0.0, 1e-16], [1.5, -1e-16], [1.2, 1.8]]))
    assert len(polygon) == 3  # (0, 0), (1, 0) and where the third edge meets ξ + η = 1
    assert sum(abs(p[1]) <= ON_LINE for p in polygon) == 2


@pytest.mark.parametrize(("n_slave", "n_master", "jitter", "flip"),
                         [(6, 4, 0.25, True), (17, 10, 0.25, True), (6, 3, 0.0, False)])
def test_compiled_segmentation_is_the_reference(n_slave: int, n_master: int, jitter: float,
                                                flip: bool) -> None:
    """searchkernels3d.segment_points against integration_points: the same points in the
    same order (slave and master faces equal), ξ to 1e-13 and weights to 1e-15 (the same
    arithmetic, the plane's coordinates summed in another order)."""
    slave = _square(n_slave, 1, False, jitter=jitter)
    master = _square(n_master, 2, flip, 1e-3, facing_down=True, jitter=jitter)
    g, w = rule(2)
    for facing in (True, False):
        ref = integration_points(slave, master, 0.01, facing=facing)
        got = searchkernels3d.segment_points(slave, master, 0.01, g, w, SLIVER, facing)
        np.testing.assert_array_equal(got[0], ref[0])
        np.testing.assert_array_equal(got[3], ref[3])
        np.testing.assert_allclose(got[1], ref[1], rtol=0, atol=1e-13)
        np.testing.assert_allclose(got[2], ref[2], rtol=0, atol=1e-15)


def test_mortar_products_of_six_node_faces() -> None:
    """On a flat patch of 6-node faces, ∫ N_s,k Σ_j N̄_m,j f_j over the segments (f = u²
    at the master's nodes: its P2 interpolant is u² itself) equals ∫ N_s,k u² over each
    slave face alone (a rule of degree 6 there: exact) to 1e-13: a degree-4 integrand
    (N_s quadratic, N̄_m quadratic in ξ at the projection), exact with the degree-4 rule,
    not with the degree-2 one (off by more than 1e-6)."""
    slave = _square(6, 1, False, 0.0, 6)
    master = _square(4, 2, True, 1e-3, 6, facing_down=True)
    g6, w6 = rule(6)
    S = len(slave)
    xs = surface(np.repeat(slave, len(w6), 0), np.tile(g6, (S, 1)))
    jac = np.linalg.norm(np.cross(xs[1][:, 0], xs[1][:, 1]), axis=1)
    Ns = shape(np.tile(g6, (S, 1)), 6)[0]
    u2 = _local(xs[0])[:, 0] ** 2
    exact = (Ns * (np.tile(w6, S) * jac * u2)[:, None]).reshape(S, len(w6), 6).sum(axis=1)
    f = _local(master)[..., 0] ** 2  # (M, 6): u² at the master's nodes
    for degree, ok in ((4, True), (2, False)):
        face, xi, weight, m_face = integration_points(master=master, slave=slave,
                                                      radius=0.01, degree=degree, facing=True)
        x, w = _surface_weights(slave, face, xi, weight)
        zeta = closest_point(x, master[m_face])
        interpolated = np.sum(shape(zeta, 6)[0] * f[m_face], axis=1)
        got = np.zeros((S, 6))
        np.add.at(got, face, shape(xi, 6)[0] * (w * interpolated)[:, None])
        err = np.abs(got - exact).max() / np.abs(exact).max()
        assert (err < 1e-13) if ok else (err > 1e-6), (degree, err)
