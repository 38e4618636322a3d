"""The closest-point projection onto triangular faces (breakwater.contact.projection3d).

Shape functions (partition of unity, interpolation, derivatives against a complex step),
the projection onto a flat face (the foot of the perpendicular) and onto a quadratic face
on a sphere, the projection's complex-step derivative against finite differences, the
candidate search against a brute-force loop, the node order of dolfinx's P2
tetrahedron facets, and the compiled projection (searchkernels3d) against these
references. Pure array tests (dolfinx on COMM_SELF): serial only.
"""

from __future__ import annotations

import numpy as np
import pytest

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater.contact import searchkernels3d
from breakwater.contact.projection3d import (
    FLIP,
    GMSH_TO_BASIX,
    NODES,
    FacetGrid,
    closest_point,
    inside,
    near,
    project,
    residual,
    shape,
    surface,
    unit_normal,
)
from breakwater.contact.searchkernels3d import RADIUS_GROWTH

pytestmark = pytest.mark.serial  # arrays alone (no MPI): once is enough

H = 1e-30  # complex step: exact derivatives to round-off, no cancellation


@pytest.mark.parametrize("nn", [3, 6])
def test_shape_functions(nn: int) -> None:
    """Partition of unity, N_k(node j) = δ_kj, reproduction of the coordinates, and the
    first and second derivatives against complex steps of N and ∂N."""
    rng = np.random.default_rng(0)
    xi = rng.uniform(-0.3, 1.0, (20, 2))
    N, dN, d2N = shape(xi, nn)
    np.testing.assert_allclose(N.sum(axis=1), 1.0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(dN.sum(axis=1), 0.0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(N @ NODES[nn], xi, rtol=0, atol=1e-15)  # x = Σ N_k x_k
    np.testing.assert_allclose(shape(NODES[nn], nn)[0], np.eye(nn), rtol=0, atol=1e-15)
    for a in range(2):
        z = xi.astype(complex)
        z[:, a] += 1j * H
        Nz, dNz, _ = shape(z, nn)
        np.testing.assert_allclose(dN[..., a], Nz.imag / H, rtol=0, atol=1e-14)
        # ∂/∂a of (∂N/∂ξ, ∂N/∂η): columns (ξξ, ξη) for a = ξ, (ξη, ηη) for a = η.
        np.testing.assert_allclose(d2N[..., [a, a + 1]], dNz.imag / H, rtol=0, atol=1e-13)
    if nn == 6:  # a quadratic: interpolates ξ² + 3ξη − η² exactly
        f = NODES[6][:, 0] ** 2 + 3 * NODES[6][:, 0] * NODES[6][:, 1] - NODES[6][:, 1] ** 2
        np.testing.assert_allclose(N @ f, xi[:, 0] ** 2 + 3 * xi[:, 0] * xi[:, 1]
                                   - xi[:, 1] ** 2, rtol=0, atol=1e-14)


def test_flat_face_is_the_foot_of_the_perpendicular() -> None:
    """On a flat face (3 nodes, and 6 with the mid-edge nodes at the edges' midpoints)
    the projection is the foot of the perpendicular, p − ((p − x₀)·n) n, to 1e-14
    (coordinates of O(1); points over the triangle and up to a third of it beyond its
    edges: the Newton keeps its iterates within a face's width of it)."""
    rng = np.random.default_rng(1)
    m = 50
    corners = rng.normal(size=(m, 3, 3))
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None]
    xi_over = rng.uniform(-0.3, 0.8, (m, 2))
    points = np.einsum("ma,mad->md", np.column_stack([1 - xi_over.sum(axis=1), xi_over]),
                       corners) + rng.normal(size=(m, 1)) * n
    foot = points - np.sum((points - corners[:, 0]) * n, axis=1)[:, None] * n
    mids = np.stack([0.5 * (corners[:, 1] + corners[:, 2]), 0.5 * (corners[:, 0] + corners[:, 2]),
                     0.5 * (corners[:, 0] + corners[:, 1])], axis=1)
    for nodes in (corners, np.concatenate([corners, mids], axis=1)):
        xi = closest_point(points, nodes)
        x, dx, _ = surface(nodes, xi)
        np.testing.assert_allclose(x, foot, rtol=0, atol=1e-14)  # coordinates of O(1)
        np.testing.assert_allclose(np.abs(np.sum(unit_normal(dx) * n, axis=1)), 1.0,
                                   rtol=0, atol=1e-14)


@pytest.mark.parametrize("nn", [3, 6])
def test_flipped_face_is_the_same_surface_reversed(nn: int) -> None:
    """nodes[:, FLIP] is the same (curved) face, (ξ, η) ↦ (η, ξ), with the opposite normal."""
    nodes, _ = _sphere_patch(1.0, 0.4)
    nodes = nodes[None, :nn]
    rng = np.random.default_rng(6)
    xi = rng.dirichlet([1.0, 1.0, 1.0], 10)[:, 1:]
    face = np.repeat(nodes, 10, 0)
    x, dx, _ = surface(face, xi)
    y, dy, _ = surface(face[:, FLIP[:nn]], xi[:, ::-1])
    np.testing.assert_allclose(y, x, rtol=0, atol=1e-15)
    np.testing.assert_allclose(unit_normal(dy), -unit_normal(dx), rtol=0, atol=1e-14)


def _sphere_patch(R: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    """A 6-node face whose nodes lie on the sphere |x| = R: a flat triangle of size h
    near the north pole and its edges' midpoints pushed radially onto the sphere."""
    flat = np.array([[0.0, 0.0], [h, 0.1 * h], [0.2 * h, 0.9 * h]]) - 0.3 * h
    corners = np.column_stack([flat, np.full(3, R)])
    mids = np.array([0.5 * (corners[1] + corners[2]), 0.5 * (corners[0] + corners[2]),
                     0.5 * (corners[0] + corners[1])])
    nodes = np.concatenate([corners, mids])
    return R * nodes / np.linalg.norm(nodes, axis=1)[:, None], corners


def test_quadratic_face_on_a_sphere() -> None:
    """Points at distance d outside and inside a sphere of radius R project onto a 6-node
    face with its nodes on the sphere at distance |d| to within δ, and the closest-point
    conditions vanish to 1e-12.

    The bound: if every point of the face lies within δ of the sphere (| |x| − R | ≤ δ),
    then |x̄ − p| ≥ | |p| − |x̄| | ≥ | |p| − R | − δ (triangle inequality), and the
    face's point x* on the ray from the centre through p (the points are chosen on rays
    through the face) is within | |p| − R | + δ of p, and so is its closest point: the
    distance is | |p| − R | to ±δ. δ is the face's radial interpolation error, measured
    on a lattice of 1/400 of the reference triangle and doubled (the error is a smooth
    function of ξ, of size h³/R²; between lattice points it changes by far less than
    itself). h/R = 0.4 makes δ ≈ 1e-4 R, far above the Newton's accuracy, so the test
    checks the closest point, not the round-off.
    """
    R, h = 1.0, 0.4
    nodes, corners = _sphere_patch(R, h)
    n = 400
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    lattice = np.column_stack([i.ravel(), j.ravel()])[(i + j).ravel() <= n] / n
    radial = np.linalg.norm(surface(np.repeat(nodes[None], len(lattice), 0), lattice)[0],
                            axis=1) - R
    delta = 2 * float(np.abs(radial).max())
    assert 1e-5 < delta < 1e-3
    rng = np.random.default_rng(2)
    m = 200
    bary = rng.dirichlet([3.0, 3.0, 3.0], m)  # rays through the face, away from its edges
    direction = bary @ corners
    direction /= np.linalg.norm(direction, axis=1)[:, None]
    d = np.concatenate([rng.uniform(0.01, 0.5, m // 2), -rng.uniform(0.01, 0.5, m // 2)])
    points = (R + d)[:, None] * direction
    face = np.repeat(nodes[None], m, axis=0)
    xi = closest_point(points, face)
    assert np.all(inside(xi, 0.0))
    x = surface(face, xi)[0]
    dist = np.linalg.norm(x - points, axis=1)
    err = np.abs(dist - np.abs(d))
    assert np.all(err <= delta)
    assert err.max() > 0.01 * delta  # the quadratic face, not a sphere: δ is not slack
    assert np.abs(residual(points, face, xi)).max() < 1e-12
    # The distance is a minimum: no lattice point of the face is nearer.
    lattice_x = surface(np.repeat(nodes[None], len(lattice), 0), lattice)[0]
    for k in range(0, m, 20):
        assert dist[k] <= np.linalg.norm(lattice_x - points[k], axis=1).min() + 1e-15


def test_projection_derivative_complex_step_against_differences() -> None:
    """∂ξ/∂p and ∂ξ/∂x_node of the projection onto a curved face by a complex step
    against central differences (step 1e-6: truncation ≈ 1e-12 · ξ''', round-off
    ≈ 1e-16 |ξ|/1e-6 = 1e-10 |ξ|; tolerance 1e-8 + 1e-7 of the derivative)."""
    nodes, _ = _sphere_patch(1.0, 0.4)
    rng = np.random.default_rng(3)
    m = 10
    face = np.repeat(nodes[None], m, 0) + 0.01 * rng.normal(size=(m, 6, 3))
    points = face[:, :3].mean(axis=1) + rng.normal(scale=0.2, size=(m, 3))
    eps = 1e-6
    for which in ("point", "node"):
        for c in range(3):
            dp = np.zeros((m, 3))
            dn = np.zeros((m, 6, 3))
            if which == "point":
                dp[:, c] = 1.0
            else:
                dn[:, 4, c] = 1.0  # a mid-edge node
            cs = np.imag(closest_point(points + 1j * H * dp, face + 1j * H * dn)) / H
            fd = (np.real(closest_point(points + eps * dp, face + eps * dn))
                  - np.real(closest_point(points - eps * dp, face - eps * dn))) / (2 * eps)
            np.testing.assert_allclose(cs, fd, rtol=1e-7, atol=1e-8)
            assert np.abs(cs).max() > 0.1  # the derivative is not trivially zero


def test_unit_normal_complex_step_against_differences() -> None:
    """The unit normal at the projection, as a function of a node (through ξ̄ too), by a
    complex step against central differences (step 1e-6, tolerance as above): it is
    written with sqrt(n·n), analytic, where |n| would drop the imaginary part."""
    nodes, _ = _sphere_patch(1.0, 0.4)
    rng = np.random.default_rng(8)
    m = 10
    face = np.repeat(nodes[None], m, 0) + 0.01 * rng.normal(size=(m, 6, 3))
    points = face[:, :3].mean(axis=1) + rng.normal(scale=0.2, size=(m, 3))

    def normal(dn: np.ndarray) -> np.ndarray:
        f = face + dn
        return unit_normal(surface(f, closest_point(points + 0 * dn[:, 0], f))[1])

    eps = 1e-6
    for c in range(3):
        dn = np.zeros((m, 6, 3))
        dn[:, 1, c] = 1.0
        cs = np.imag(normal(1j * H * dn)) / H
        fd = (np.real(normal(eps * dn)) - np.real(normal(-eps * dn))) / (2 * eps)
        np.testing.assert_allclose(cs, fd, rtol=1e-7, atol=1e-8)
        assert np.abs(cs).max() > 0.1


def _bumpy(n: int, nn: int, graded: bool = False) -> np.ndarray:
    """Faces ``(2n², nn, 3)`` of z = 0.1 sin 3x cos 2y over [0, 1]², a structured grid
    with alternating diagonals, interior vertices jittered, mid-edge nodes on the surface
    (curved faces); ``graded``: the grid's coordinates squared (faces from about 1/n² at
    the origin's corner to 2/n at the far one)."""
    rng = np.random.default_rng(4)
    s = np.linspace(0.0, 1.0, n + 1)
    X, Y = np.meshgrid(s, s, indexing="ij")
    jitter = rng.uniform(-0.2, 0.2, (2, n + 1, n + 1)) / n
    jitter[:, [0, -1], :] = 0
    jitter[:, :, [0, -1]] = 0
    X, Y = X + jitter[0], Y + jitter[1]
    if graded:
        X, Y = X**2, Y**2

    def lift(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return np.stack([x, y, 0.1 * np.sin(3 * x) * np.cos(2 * y)], axis=-1)

    V = lift(X, Y)
    faces = []
    for i in range(n):
        for j in range(n):
            a, b, c, d = V[i, j], V[i + 1, j], V[i + 1, j + 1], V[i, j + 1]
            tris = [(a, b, c), (a, c, d)] if (i + j) % 2 else [(a, b, d), (b, c, d)]
            faces.extend(tris)
    corners = np.array(faces)
    if nn == 3:
        return corners
    pairs = ((1, 2), (0, 2), (0, 1))
    mids = np.stack([0.5 * (corners[:, a] + corners[:, b]) for a, b in pairs], axis=1)
    return np.concatenate([corners, lift(mids[..., 0], mids[..., 1])], axis=1)


@pytest.mark.parametrize("nn", [3, 6])
def test_candidate_search_is_the_brute_force_nearest(nn: int) -> None:
    """project() (grid candidates, box filter, Newton, nearest inside projection) gives the
    face and (ξ, η) of a loop over every face (same acceptance), for points above and
    below a bumpy surface; many points land on a face other than their start's."""
    faces = _bumpy(8, nn)
    rng = np.random.default_rng(5)
    m = 300
    x, y = rng.uniform(-0.05, 1.05, m), rng.uniform(-0.05, 1.05, m)
    points = np.column_stack([x, y, 0.1 * np.sin(3 * x) * np.cos(2 * y)
                              + rng.uniform(-0.06, 0.06, m)])
    radius = 0.12
    face, xi = project(points, faces, FacetGrid(faces, radius))
    expect = np.full(m, -1)
    expect_xi = np.zeros((m, 2))
    for k in range(m):
        p = np.repeat(points[k][None], len(faces), 0)
        z = np.real(closest_point(p, faces, iterations=10, tol=1e-12))
        x, dx, _ = surface(faces, z)
        r = x - p
        dist = np.sum(r * r, axis=1)
        stationary = np.all(np.abs(np.einsum("md,mad->ma", r, dx))
                            <= 1e-10 * np.sum(dx * dx, axis=(1, 2))[:, None], axis=1)
        ok = np.flatnonzero(inside(z) & (dist <= radius ** 2) & stationary)
        if len(ok):
            best = ok[np.argmin(dist[ok])]
            expect[k], expect_xi[k] = best, z[best]
    np.testing.assert_array_equal(face, expect)
    np.testing.assert_allclose(xi, expect_xi, rtol=0, atol=1e-12)
    assert (face >= 0).sum() > 0.7 * m and (face < 0).sum() > 0  # some off the surface
    # The nearest of all faces' closest points is the one found: the continuation onto
    # the neighbouring face where the projection leaves a face.
    start = np.array([np.argmin(np.linalg.norm(faces[:, :3].mean(axis=1) - p, axis=1))
                      for p in points])
    assert np.sum((face >= 0) & (face != start)) > 10


def test_a_bulging_face_is_a_candidate() -> None:
    """A 6-node face bulges beyond its nodes' box (flat corners at z = 0, mid-edge nodes
    at z = ½: the surface reaches z = 2(L₀L₁ + L₁L₂ + L₀L₂) = ⅔ at the centroid): a point
    0.05 above the top, within the radius 0.1 of it but 0.217 above the nodes' box, is
    projected (project()'s box filter widens the box by the mid-edge nodes' offsets),
    onto the centroid, at distance 0.05."""
    corners = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    mids = np.array([[0.5, 0.5, 0.5], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]])
    faces = np.concatenate([corners, mids])[None]
    point = np.array([[1 / 3, 1 / 3, 2 / 3 + 0.05]])
    face, xi = project(point, faces, FacetGrid(faces, 0.1))
    assert face[0] == 0
    np.testing.assert_allclose(xi[0], [1 / 3, 1 / 3], rtol=0, atol=1e-14)
    np.testing.assert_allclose(surface(faces, xi)[0][0], [1 / 3, 1 / 3, 2 / 3], rtol=0,
                               atol=1e-14)


@pytest.mark.parametrize("nn", [3, 6])
def test_compiled_projection_in_passes_is_the_reference(nn: int) -> None:
    """On a graded surface (faces 0.006–0.25, the radius the longest face edge, the
    default search radius), the compiled projection works in passes of a growing radius
    (from the shortest face size, ×4 a pass): its faces and (ξ, η) are the reference's
    one pass (equal; to 1e-12, the arithmetic summed in another order, the graded
    faces' small Jacobians amplifying it to 1.3e-13 on 2 of 1200), and those of the
    compiled single pass bit for bit, for points near the surface and up to the radius
    off it."""
    faces = _bumpy(12, nn, graded=True)
    edges = np.linalg.norm(faces[:, [1, 2, 0], :] - faces[:, :3, :], axis=2).max(axis=1)
    radius = float(edges.max())
    assert edges.min() < radius / RADIUS_GROWTH**2  # three passes at least
    rng = np.random.default_rng(11)
    m = 600
    x, y = rng.uniform(-0.02, 1.02, m) ** 2, rng.uniform(-0.02, 1.02, m) ** 2
    off = np.concatenate([rng.uniform(-1e-3, 1e-3, m // 2),
                          rng.uniform(-1.2 * radius, 1.2 * radius, m - m // 2)])
    points = np.column_stack([x, y, 0.1 * np.sin(3 * x) * np.cos(2 * y) + off])
    f_ref, xi_ref = project(points, faces, FacetGrid(faces, radius))
    f, xi = searchkernels3d.project(points, faces, radius, 1e-9)
    np.testing.assert_array_equal(f, f_ref)
    np.testing.assert_allclose(xi, xi_ref, rtol=0, atol=1e-12)
    f_one, xi_one = searchkernels3d._project_within(points, faces, radius, radius, 1e-9)
    np.testing.assert_array_equal(f, f_one)
    np.testing.assert_array_equal(xi, xi_one)
    assert (f >= 0).sum() > m // 2 and (f < 0).sum() > 0


@pytest.mark.parametrize("bad", ["collapsed", "nan"])
def test_compiled_passes_end_on_degenerate_faces(bad: str) -> None:
    """A collapsed face (its three corners one point: the shortest face size 0) or a
    non-finite node among the faces: the passes end where the single pass does, in its
    ZeroDivisionError (the face's plane has no area: Newton's flat start). Before, a
    radius grown from 0 by ×4 a pass never reached the search radius and the search
    never ended (measured: still running after 90 s). A run never brings such faces
    here: a case's or a run's set-up refuses them in one line
    (:func:`breakwater.contact.surfaces.check_faces`, the mesh's non-finite nodes
    :class:`~breakwater.model.model.ContactModel`; tests/bad_cases/run/y1-y5); the kernel
    keeps raising, not hanging, for a caller that skipped it."""
    faces = _bumpy(6, 6)
    faces[3] = faces[3, 0] if bad == "collapsed" else np.nan
    rng = np.random.default_rng(3)
    points = np.column_stack([rng.uniform(0, 1, 200), rng.uniform(0, 1, 200),
                              rng.uniform(-0.1, 0.1, 200)])
    with pytest.raises(ZeroDivisionError):
        searchkernels3d._project_within(points, faces, 0.3, 0.3, 1e-9)
    with pytest.raises(ZeroDivisionError):
        searchkernels3d.project(points, faces, 0.3, 1e-9)


def test_collapsed_faces_are_those_the_set_up_refuses() -> None:
    """surfaces.collapsed (the set-up's refusal, check_faces): a 3-D face whose corners'
    height is at most 1e-6 (mesh.DEGENERATE) of its longest edge, whatever its mid-edge
    nodes; a 2-D facet at most 1e-6 of the surface's longest. The height of a triangle
    with base 1 and apex offset t is t: 0.5e-6 is collapsed, 2e-6 is not."""
    from breakwater.contact.surfaces import collapsed

    def face(apex: list[float]) -> np.ndarray:
        return _straight(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], apex]))

    curved = face([2.0, 0.0, 0.0])
    curved[3:, 2] = 0.3  # corners on a line, mid-edge nodes off it: still no plane
    faces = np.stack([face([0.0, 1.0, 0.0]), face([0.0, 0.0, 0.0]), face([0.5, 0.0, 0.0]),
                      curved, face([0.5, 0.5e-6, 0.0]), face([0.5, 2e-6, 0.0]),
                      np.zeros((6, 3))])
    np.testing.assert_array_equal(collapsed(faces),
                                  [False, True, True, True, True, False, True])
    facets = np.array([[[0.0, 0.0], [1.0, 0.0]], [[1.0, 0.0], [1.0, 0.5e-6]],
                       [[1.0, 0.0], [1.0, 2e-6]], [[2.0, 1.0], [2.0, 1.0]]])
    np.testing.assert_array_equal(collapsed(facets), [False, True, False, True])


def test_compiled_passes_find_a_bulging_face() -> None:
    """test_a_bulging_face_is_a_candidate in passes: beside the bulging face, a small
    face (the first pass's radius, 0.014) and a flat face 0.1 above the point. The
    point, 0.05 above the bulge and 0.217 above its nodes' box, projects onto the
    bulge, its nearest face, not onto the flat one."""
    corners = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    mids = np.array([[0.5, 0.5, 0.5], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]])
    point = np.array([[1 / 3, 1 / 3, 2 / 3 + 0.05]])
    flat = corners + np.array([0.0, 0.0, point[0, 2] + 0.1])
    small = corners * 0.01 + np.array([2.0, 0.0, 0.0])
    faces = np.stack([np.concatenate([c, 0.5 * (c[[1, 0, 0]] + c[[2, 2, 1]])])
                      for c in (flat, small)])
    faces = np.concatenate([np.concatenate([corners, mids])[None], faces])
    face, xi = searchkernels3d.project(point, faces, 1.0, 1e-9)
    assert face[0] == 0
    np.testing.assert_allclose(xi[0], [1 / 3, 1 / 3], rtol=0, atol=1e-13)


def test_compiled_passes_keep_the_nearest() -> None:
    """A point 0.3 above a small face (0.03 across: the first pass's radius 0.042) and
    0.495 from a large tilted face whose box holds it: the passes of radius 0.042 and
    0.17 accept neither (the tilted face is a candidate of both, beyond their radius),
    the pass of 0.67 takes the nearest, the small face, at (⅓, ⅓) (its centroid below
    the point)."""
    small = np.array([[-0.01, -0.01, -0.3], [0.02, -0.01, -0.3], [-0.01, 0.02, -0.3]])
    tilted = np.array([[-1.0, -1.0, 1.7], [2.0, -1.0, -1.3], [-1.0, 2.0, 1.7]])
    faces = np.stack([small, tilted])
    point = np.zeros((1, 3))
    face, xi = searchkernels3d.project(point, faces, 1.0, 1e-9)
    assert face[0] == 0
    np.testing.assert_allclose(xi[0], [1 / 3, 1 / 3], rtol=0, atol=1e-13)
    f_ref, _ = project(point, faces, FacetGrid(faces, 1.0))
    assert f_ref[0] == 0


def _straight(corners: np.ndarray) -> np.ndarray:
    """A flat 6-node face: its corners and its edges' midpoints (NODES[6]'s order)."""
    return np.concatenate([corners, 0.5 * (corners[[1, 0, 0]] + corners[[2, 2, 1]])])


def test_compiled_pass_grid_is_widened_by_the_box_margin() -> None:
    """A pass's grid holds every face its box filter can keep: the faces' boxes grown
    by the pass's radius and by the filter's margin beyond it (a quadratic face's bulge).

    A 6-node face F: corners at z = 0 on the unit triangle, mid-edge nodes at z = h =
    0.9, its top the centroid at z = 4h/3 = 1.2, 0.3 above its nodes' box. The point
    is 0.1 above that top, a flat face G 0.2 above the point, and a small face off at
    x = 5 sets the first pass's radius (its longest edge, 0.0141). The filter's margin
    is F's 3h = 2.7 (its mid-edge offsets), the search radius 3.5: the passes of
    0.0141, 0.0566 and 0.226 come before the last. The pass of 0.226 has F (0.1) and G
    (0.2) within it; the point lies 0.4 above F's box, and the grid of boxes grown by
    0.226 alone (cells 1.452 across, from z = −0.226) puts it in the cell above F's:
    that pass took G. Grown by the margin too, the pass takes F, the reference's
    nearest, at the centroid.
    """
    h = 0.9
    corners = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    bulging = np.concatenate([corners, [[0.5, 0.5, h], [0.0, 0.5, h], [0.5, 0.0, h]]])
    point = np.array([[1 / 3, 1 / 3, 4 * h / 3 + 0.1]])
    above = _straight(corners + np.array([0.0, 0.0, point[0, 2] + 0.2]))
    far = _straight(0.01 * corners + np.array([5.0, 0.0, 0.0]))
    faces = np.stack([bulging, above, far])
    radius, tol = 3.5, 1e-9
    shortest, widen = searchkernels3d._scales(faces, tol)
    r = shortest * RADIUS_GROWTH**2
    assert 0.2 < r < 0.3 and r + widen < radius  # the pass of 0.226, not the last
    # The pass's grid without the margin holds G, not F; with it both.
    assert set(searchkernels3d.candidates(point, faces, r)[1]) == {1}
    assert {0, 1} <= set(searchkernels3d.candidates(point, faces, r + widen)[1])
    assert searchkernels3d._project_within(point, faces, r, r, tol)[0][0] == 1
    f_ref, _ = project(point, faces, FacetGrid(faces, radius), tol=tol)
    assert f_ref[0] == 0
    face, xi = searchkernels3d.project(point, faces, radius, tol)
    assert face[0] == 0
    np.testing.assert_allclose(xi[0], [1 / 3, 1 / 3], rtol=0, atol=1e-13)


def test_compiled_pass_accepts_within_its_own_radius() -> None:
    """A pass accepts projections within its own radius, not the search radius: a
    farther face in a pass's grid does not take a point whose nearest face only a
    later pass's grid holds.

    The point (−0.5, 0, 0.5) lies 0.495 from a large tilted face G (the plane
    x + z = 0.7; the foot (−0.15, 0, 0.85) inside G, whose box holds the point) and
    0.3 above a small flat face F (0.03 across: the first pass's radius 0.0424). A
    small face off at (5, 0, −2.7) sets the grid's origin: the cells of the passes of
    0.0424 and 0.170 (3.08 and 3.34 across, from z = −2.7 − r) part the point (z = 0.5,
    the second cell) from F's box (z = 0.2, the first): F is no candidate of those
    passes, G is. They accept nothing (G is beyond their radius); the pass of 0.679
    takes F, the reference's nearest (search radius 1), at (⅓, ⅓) under the point.
    Accepting up to the search radius, the first pass took G.
    """
    tri = np.array([[-0.01, -0.01, 0.0], [0.02, -0.01, 0.0], [-0.01, 0.02, 0.0]])
    point = np.array([[-0.5, 0.0, 0.5]])
    small = _straight(tri + np.array([-0.5, 0.0, 0.2]))
    tilted = _straight(np.array([[-1.0, -1.0, 1.7], [2.0, -1.0, -1.3], [-1.0, 2.0, 1.7]]))
    far = _straight(tri + np.array([5.0, 0.0, -2.7]))
    faces = np.stack([small, tilted, far])
    radius, tol = 1.0, 1e-9
    shortest, widen = searchkernels3d._scales(faces, tol)
    for r in (shortest, shortest * RADIUS_GROWTH):  # the passes before the last
        assert r + widen < radius
        assert set(searchkernels3d.candidates(point, faces, r + widen)[1]) == {1}
        assert searchkernels3d._project_within(point, faces, r, r + widen, tol)[0][0] == -1
        assert searchkernels3d._project_within(point, faces, radius, r + widen, tol)[0][0] == 1
    f_ref, _ = project(point, faces, FacetGrid(faces, radius), tol=tol)
    assert f_ref[0] == 0
    face, xi = searchkernels3d.project(point, faces, radius, tol)
    assert face[0] == 0
    np.testing.assert_allclose(xi[0], [1 / 3, 1 / 3], rtol=0, atol=1e-13)


def test_dolfinx_p2_tetrahedron_facet_closure_order() -> None:
    """dolfinx's closure DOFs of a P2 tetrahedron's facet: the three vertices, then the
    mid-edge nodes of the edges (1, 2), (0, 2), (0, 1), the order of NODES[6], on every
    facet of every cell of a mesh; a gmsh 6-node triangle (mid-edge nodes (0, 1), (1, 2),
    (2, 0)) reordered by GMSH_TO_BASIX."""
    from dolfinx import fem, mesh
    from mpi4py import MPI

    msh = mesh.create_unit_cube(MPI.COMM_SELF, 2, 2, 1, cell_type=mesh.CellType.tetrahedron)
    V = fem.functionspace(msh, ("Lagrange", 2, (3,)))
    closure = V.dofmap.dof_layout.entity_closure_dofs
    coords = V.tabulate_dof_coordinates()
    linear = shape(NODES[6], 3)[0]  # the vertices' interpolation at the six nodes
    for c in range(msh.topology.index_map(3).size_local):
        cell = V.dofmap.cell_dofs(c)
        for f in range(4):
            X = coords[cell[closure(2, f)]]
            # Straight edges: the nodes are the vertices' interpolation at NODES[6].
            np.testing.assert_allclose(linear @ X[:3], X, rtol=0, atol=1e-15)
    corners = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    gmsh = np.concatenate([corners, 0.5 * (corners[[0, 1, 2]] + corners[[1, 2, 0]])])
    np.testing.assert_array_equal(gmsh[GMSH_TO_BASIX], NODES[6])


@pytest.mark.parametrize("nn", [3, 6])
def test_compiled_projection_is_the_reference(nn: int) -> None:
    """searchkernels3d against this module's references: the grid's candidates (same
    pairs, same order), the box filter (same pairs), the Newton's iterates from the same
    start (to 1e-12) and the faces at points (to 1e-14: the same arithmetic summed in
    another order), the faces found (equal) and their (ξ, η) (to 1e-13)."""
    faces = _bumpy(8, nn)
    rng = np.random.default_rng(7)
    m = 400
    x, y = rng.uniform(-0.05, 1.05, m), rng.uniform(-0.05, 1.05, m)
    points = np.column_stack([x, y, 0.1 * np.sin(3 * x) * np.cos(2 * y)
                              + rng.uniform(-0.06, 0.06, m)])
    for radius in (0.03, 0.12):
        grid = FacetGrid(faces, radius)
        ref = grid.candidates(points)
        got = searchkernels3d.candidates(points, faces, radius)
        for a, b in zip(ref, got, strict=True):
            np.testing.assert_array_equal(a, b)
        for tol in (1e-9, 1e-3):
            np.testing.assert_array_equal(
                np.stack(searchkernels3d.near(points, ref[0], faces, ref[1], radius, tol)),
                np.stack(near(points, *ref, faces, radius, tol)))
            f_ref, xi_ref = project(points, faces, grid, tol=tol)
            f, xi = searchkernels3d.project(points, faces, radius, tol)
            np.testing.assert_array_equal(f, f_ref)
            np.testing.assert_allclose(xi, xi_ref, rtol=0, atol=1e-13)
            assert (f >= 0).sum() > m // 4
    point, cand = ref
    start = searchkernels3d.flat_start(points, point, faces, cand)
    for iterations, tol in ((10, 1e-14), (2, 0.0)):
        xi = start.copy()
        searchkernels3d.closest_points(points, point, faces, cand, xi, iterations, tol)
        expected = closest_point(points[point], faces[cand], iterations=iterations, tol=tol)
        # All candidate pairs, far ones too (iterates out at the clip, ill-conditioned
        # Jacobians: round-off of the sums' order amplified to 1.5e-13 on 10 of 36432).
        np.testing.assert_allclose(xi, expected, rtol=0, atol=1e-12)
    k = np.arange(0, len(point), 7)
    x_ref, dx_ref, d2x_ref = surface(faces[cand[k]], start[k])
    for j, i in enumerate(k):
        xj, dxj, d2xj = searchkernels3d.face_at(faces, cand[i], start[i, 0], start[i, 1])
        np.testing.assert_allclose(xj, x_ref[j], rtol=0, atol=1e-14)
        np.testing.assert_allclose(dxj, dx_ref[j], rtol=0, atol=1e-14)
        np.testing.assert_allclose(d2xj, d2x_ref[j], rtol=0, atol=1e-13)
