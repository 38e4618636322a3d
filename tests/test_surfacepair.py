"""General contact pairs: surfaces that need not match, finite sliding (issue 12).

The projection (:mod:`breakwater.contact.projection`) against closed-form closest points; the
contact Jacobian (complex steps) against finite differences; and four histories of
bodies meshed separately (:mod:`meshes.apart`), references from formulas:

- non-matching patch test (two blocks, element sizes 1/7 and 1/4: ratio 1.75, under a
  uniform pressure p): the exact solution is a uniform uniaxial strain, contact
  pressure p and σ_yy = −p everywhere (Taylor & Papadopoulos 1991, the contact patch
  test);
- a block released g₀ above the base falls freely and lands at t = sqrt(2 g₀/g)
  (constant acceleration), then settles: the contact resultant equals its weight;
- a block pushed along a long base by F = 1.5 μN slides with the acceleration
  (F − μN)/m of a rigid block under Coulomb friction, x(t) = (F − μN) t²/(2m), over
  more than 10 master element lengths;
- under ``mpiexec -n 2`` the falling and sliding histories on two ranks equal the serial
  ones (rank 0 repeats them on ``COMM_SELF``).
"""

from __future__ import annotations

import itertools
import json
import pathlib

import numpy as np
import pytest
from blocks import run_killed_at
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
import ufl
from breakwater.meshes.apart import Rectangle, rectangles
from dolfinx import fem

from breakwater import forms  # type: ignore[attr-defined]
from breakwater.common.errors import MeshError
from breakwater.contact.general import SurfaceContact
from breakwater.contact.pointkernels import normal_forces
from breakwater.contact.projection import FacetGrid, closest_point, curve, nearest_end, project
from breakwater.contact.surfaces import SurfacePair
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Damping, Fixed, Material, SurfaceLoad
from breakwater.stepping.gn22 import GN22, GN22Parameters
from breakwater.stepping.solver import NewtonOptions

COMM = MPI.COMM_WORLD
G = 9.81
STEEL_LIKE = Material(density=2000.0, poisson=0.25, young_modulus=1e9)


# --- projection --------------------------------------------------------------------

def _straight(xs: np.ndarray, y: float = 0.0) -> np.ndarray:
    """P2 facets (ends, mid-node) along y between consecutive xs."""
    return np.array([[[a, y], [b, y], [(a + b) / 2, y]] for a, b in itertools.pairwise(xs)])


def test_projection_straight_and_continuation() -> None:
    """Points above a straight surface project vertically; across facet ends, onto the
    next facet (continuation); beyond the ends or the search radius, nowhere."""
    xs = np.array([0.0, 0.3, 0.5, 1.0])
    nodes = _straight(xs)
    grid = FacetGrid(nodes, radius=0.2)
    x = np.linspace(0.01, 0.99, 50)
    points = np.stack([x, 0.05 * np.ones_like(x)], axis=1)
    facet, xi = project(points, nodes, grid)
    expected = np.searchsorted(xs, x) - 1
    np.testing.assert_array_equal(facet, expected)
    a, b = xs[facet], xs[facet + 1]
    np.testing.assert_allclose(xi, 2 * (x - a) / (b - a) - 1, atol=1e-12)
    # Beyond the ends (no facet under the point), or farther than the radius: none.
    facet, _ = project(np.array([[-0.1, 0.05], [1.1, 0.0], [0.4, 0.5]]), nodes, grid)
    np.testing.assert_array_equal(facet, [-1, -1, -1])


def test_nearest_end_beyond_the_surface() -> None:
    """Points past either end of a surface (no projection) take its end vertex within
    the radius (the friction of a slave node that slid past the master's end)."""
    nodes = _straight(np.array([0.0, 0.3, 0.5, 1.0]))
    grid = FacetGrid(nodes, radius=0.2)
    points = np.array([[-0.05, 0.01], [1.1, -0.02], [1.5, 0.0]])
    assert np.all(project(points, nodes, grid)[0] == -1)
    facet, xi = nearest_end(points, nodes, grid)
    np.testing.assert_array_equal(facet, [0, 2, -1])  # the last: beyond the radius
    np.testing.assert_array_equal(xi[:2], [-1.0, 1.0])


def test_projection_convex_corner_has_none() -> None:
    """Outside a convex corner (two facets meeting at a right angle) a point has no
    projection on either facet: it is out of contact."""
    nodes = np.array([[[0.0, 0.0], [1.0, 0.0], [0.5, 0.0]],
                      [[1.0, 0.0], [1.0, -1.0], [1.0, -0.5]]])
    facet, _ = project(np.array([[1.1, 0.1]]), nodes, FacetGrid(nodes, 0.5))
    assert facet[0] == -1


def test_projection_onto_curved_facet() -> None:
    """Closest point on a quadratic facet against a dense sampling of the curve (1e-9)."""
    rng = np.random.default_rng(1)
    nodes = np.array([[[0.0, 0.0], [1.0, 0.2], [0.5, 0.35]]] * 20)
    points = rng.uniform([0.1, 0.3], [0.9, 0.8], size=(20, 2))
    xi = closest_point(points, nodes)
    s = np.linspace(-1, 1, 20001)
    for k in range(len(points)):
        x, _, _ = curve(np.repeat(nodes[:1], len(s), axis=0), s)
        best = s[np.argmin(np.sum((x - points[k]) ** 2, axis=1))]
        assert abs(xi[k] - best) < 2e-4  # the sampling step is 1e-4
        x, dx, _ = curve(nodes[k:k + 1], xi[k:k + 1])
        assert abs(np.dot(x[0] - points[k], dx[0])) < 1e-12  # stationary: exact


def test_projection_complex_step_is_the_derivative() -> None:
    """The projection's Newton in complex arithmetic carries dξ/dp (implicit function):
    against central differences of the real projection."""
    nodes = np.array([[[0.0, 0.0], [1.0, 0.2], [0.5, 0.35]]])
    p = np.array([[0.4, 0.6]])
    h = 1e-20
    for d in range(2):
        e = np.zeros((1, 2))
        e[0, d] = 1.0
        derivative = closest_point(p + 1j * h * e, nodes.astype(complex)).imag / h
        fd = (closest_point(p + 1e-6 * e, nodes) - closest_point(p - 1e-6 * e, nodes)) / 2e-6
        np.testing.assert_allclose(derivative, fd, rtol=1e-7)


def test_grid_candidates_are_complete() -> None:
    """The grid search finds every facet whose inflated box holds a point (all pairs)."""
    rng = np.random.default_rng(2)
    a = rng.uniform(0, 1, size=(200, 2))
    nodes = np.stack([a, a + rng.uniform(-0.05, 0.05, size=(200, 2))], axis=1)
    radius = 0.03
    grid = FacetGrid(nodes, radius)
    points = rng.uniform(0, 1, size=(300, 2))
    point, facet = grid.candidates(points)
    found = set(zip(point.tolist(), facet.tolist(), strict=True))
    lo, hi = nodes.min(axis=1) - radius, nodes.max(axis=1) + radius
    inside = np.all((points[:, None] >= lo) & (points[:, None] <= hi), axis=2)
    assert {(int(i), int(j)) for i, j in zip(*np.nonzero(inside), strict=True)} <= found


def test_small_rotations_take_the_reference_normal() -> None:
    """A master facet turned rigidly by θ, a slave point 1e-3 m inside it along its
    current normal: with the current normal (``rotations = "finite"``, eq. 7) the
    traction is ε_n·1e-3 along that normal; with the reference one (``"small"``) it
    is along the unturned normal, g_n = −1e-3 cos θ (the offset on the reference
    normal). Exact to round-off (1e-12 relative)."""
    θ, ε = 0.1, 1e10
    turn = np.array([[np.cos(θ), -np.sin(θ)], [np.sin(θ), np.cos(θ)]])
    reference = _straight([-1.0, 1.0])  # (1, 3, 2): the facet along x
    current = reference @ turn.T
    n_current = turn @ np.array([0.0, -1.0])  # (t_y, −t_x) of the turned tangent
    x_s = current[0, 2] - 1e-3 * n_current  # 1e-3 behind the master's surface
    slave = np.repeat(x_s[None, None], 3, axis=1)  # a P2 slave facet collapsed on x_s
    law = forms.ContactLaw.of(SurfacePair("c", "a", "b", "s", "m", ε))
    Ns, xi, w = np.array([[0.0, 0.0, 1.0]]), np.zeros(1), np.ones(1)
    groups = [(slave, np.zeros_like(slave)), (current, np.zeros_like(current))]
    finite = -normal_forces(law, Ns, xi, w, groups)[0, :3].sum(axis=0)
    small = -normal_forces(law, Ns, xi, w, groups, reference=reference)[0, :3].sum(axis=0)
    # The traction on the slave: p along the master's outward normal n̄ (p ≥ 0 pushes
    # the slave out: t_s = p n̄).
    assert np.allclose(finite, ε * 1e-3 * n_current, rtol=1e-12, atol=0)
    assert np.allclose(small, ε * 1e-3 * np.cos(θ) * np.array([0.0, -1.0]), rtol=1e-12,
                       atol=1e-12 * ε * 1e-3)


# --- models ------------------------------------------------------------------------

def _model(path: pathlib.Path, comm: MPI.Comm, bodies: list[Rectangle], pair: SurfacePair,
           **kwargs: object) -> ContactModel:
    mesh = rectangles(path, comm, bodies)
    return ContactModel(read_mesh(mesh, comm), [Body(b.name, STEEL_LIKE) for b in bodies],
                        surface_pairs=[pair], **kwargs)  # type: ignore[arg-type]


def _provider(stepper: GN22) -> SurfaceContact:
    provider = stepper.surfaces[-1]
    assert isinstance(provider, SurfaceContact)
    return provider


@pytest.mark.parametrize("options", [{}, {"integration": "nodes", "rotations": "small"},
                                     {"integration": "gauss"}],
                         ids=["segments-finite", "nodes-small", "gauss-finite"])
def test_jacobian_matches_finite_differences(options: dict[str, str],
                                             shared_dir: pathlib.Path) -> None:
    """The complex-step Jacobian (normal and friction parts) against central differences
    of the residual, on a block pressed into a base and sliding on it, for each
    integration and both normals (current; reference: small rotations)."""
    pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", 1e10, friction=0.5,
                       **options)  # type: ignore[arg-type]
    model = _model(shared_dir / "jac.msh", COMM,
                   [Rectangle("base", -0.5, -0.2, 1.0, 0.2, 50, 2),
                    Rectangle("block", -0.1, 0.0, 0.2, 0.1, 3, 2)], pair,
                   fixed=[Fixed("base_bottom")], gravity=(0.0, -G))
    stepper = GN22(model, 1e-3)
    stepper.initialise()
    stepper.stage()
    provider, solver = _provider(stepper), stepper.fast
    assert solver is not None
    for f in (*stepper.a, *stepper.v):
        f.x.array[:] = 0.0
    for f in stepper.v[1:]:  # the block slides at 0.1 m/s with a 1e-5 m penetration
        f.x.array.reshape(-1, 2)[:, 0] = 0.1
    cu = 0.5 * 0.605 * 1e-6
    y = np.zeros(solver.n)
    y[provider.pos_s[..., 1][provider.pos_s[..., 1] >= 0]] = -1e-5 / cu
    y += np.random.default_rng(3).normal(size=solver.n) * 1e-7 / cu
    solver.interface.write(solver.da, y)
    J = provider.matrix()
    # The left product the fast solver takes (from the matrix's structure) is X J.
    X = np.random.default_rng(4).normal(size=(solver.n, solver.n))
    np.testing.assert_allclose(provider.left_product(X), X @ J, rtol=0,
                               atol=1e-13 * np.abs(X @ J).max())
    fd = np.zeros_like(J)
    h = 1e-9 / cu  # 1e-9 m: round-off of the positions (1e-16 m) is 1e-7 of it
    for j in range(solver.n):
        for sign in (1, -1):
            z = y.copy()
            z[j] += sign * h
            solver.interface.write(solver.da, z)
            fd[:, j] += sign * provider.vector() / (2 * h)
    assert np.abs(J).max() > 0
    # Tolerance: central differences of step 1e-9 m on a penalty residual of curvature
    # ~ ε/|g| carry up to 1e-6 relative truncation; measured 4e-11.
    assert np.abs(J - fd).max() < 1e-5 * np.abs(J).max()
    stepper.destroy()


def _patch(path: pathlib.Path, **options: str) -> tuple[GN22, SurfaceContact, list[float]]:
    """The non-matching patch (see :func:`test_patch_non_matching`) after 0.12 s.

    Returns:
        The stepper, the pair and the largest |σ_yy/(−p) − 1| of each block.
    """
    pair = SurfacePair("c", "upper", "lower", "upper_bottom", "lower_top", 1e10, points=3,
                       **options)  # type: ignore[arg-type]
    model = _model(path, COMM,
                   [Rectangle("lower", 0.0, 0.0, 1.0, 0.5, 7, 4),
                    Rectangle("upper", 0.0, 0.5, 1.0, 0.5, 4, 2)], pair,
                   fixed=[Fixed("lower_bottom", (1,)), Fixed("lower_left", (0,)),
                          Fixed("upper_left", (0,))],
                   loads=[SurfaceLoad("upper_top", (0.0, -PATCH), lambda t: 1.0)],
                   damping=Damping(alpha=700.0))
    stepper = GN22(model, 1e-3)
    stepper.initialise()
    for _ in range(120):
        assert stepper.step() <= 10
    errors = []
    for i, b in enumerate(model.bodies):
        Q = fem.functionspace(b.submesh, ("DG", 1))
        e = ufl.sym(ufl.grad(stepper.u[i]))
        σ_yy = (2 * b.μ * e + b.λ * ufl.tr(e) * ufl.Identity(2))[1, 1]
        q = fem.Function(Q)
        q.interpolate(fem.Expression(σ_yy, Q.element.interpolation_points))
        errors.append(COMM.allreduce(np.abs(q.x.array / -PATCH - 1).max(initial=0.0),
                                     op=MPI.MAX))
    return stepper, _provider(stepper), errors


PATCH = 1e5  # Pa: the patch test's pressure


def test_patch_non_matching(shared_dir: pathlib.Path) -> None:
    """Two blocks, element sizes 1/7 (lower) and 1/4 (upper), uniform pressure p on
    top, rollers on the left sides and the bottom, frictionless: the exact state is a
    uniform uniaxial strain, contact pressure p and σ_yy = −p in both blocks.

    The segment-to-segment integration of the slave (the upper block) passes it: the
    transient from the sudden load is damped out (mass-proportional damping, critical
    for the fundamental mode: α = 2ω, ω = π c/(2·1 m), c = sqrt((λ+2μ)/ρ)), and after
    0.12 s the pressure is uniform to 1e-7 (measured 3e-8: the remaining dynamics)
    and σ_yy to 1e-8 (measured 2e-10). Gauss-point-to-segment integration (no cuts)
    misses it by 2-24 % (measured, 2-8 points per facet).
    """
    stepper, contact, errors = _patch(shared_dir / "patch.msh")
    state = contact.state()
    assert np.all(state["facet"] >= 0)
    assert np.abs(state["pressure"] / PATCH - 1).max() < 1e-7
    assert max(errors) < 1e-8, errors
    stepper.destroy()


def test_patch_non_matching_node_to_segment(shared_dir: pathlib.Path) -> None:
    """The same patch with ``integration = "nodes"`` (single-pass node-to-segment, the
    conforming pair's quadrature): it does not pass the patch test, as expected of
    the scheme (the slave nodes' lumped forces on a finer master), but it converges
    (≤ 10 Newton iterations a step: the slave's end node, 1e-5 of a facet past the
    master's end, stays on it, see ``contact.surfacesearch._EDGE``) and holds the load: the
    resultant is p × 1 m to 1e-6 (the remaining dynamics, as above). Measured: nodal
    pressures 0.91-1.20 p, σ_yy off by 79 % (lower block, at the interface) and 14 %
    (upper); asked: pressures within 0.8-1.3 p, every node in contact."""
    stepper, contact, errors = _patch(shared_dir / "patch_nts.msh", integration="nodes")
    state = contact.state()
    assert np.all(state["facet"] >= 0)
    assert np.all((state["pressure"] > 0.8 * PATCH) & (state["pressure"] < 1.3 * PATCH))
    np.testing.assert_allclose(contact.resultant(), [0.0, PATCH], atol=1e-6 * PATCH)
    assert max(errors) > 0.01  # not the patch test's uniform state (measured 0.79)
    stepper.destroy()


def _mean_displacement(stepper: GN22, comm: MPI.Comm) -> np.ndarray:
    """The mean nodal displacement of the block (the second body), on every rank."""
    u = stepper.u[1]
    owned = u.x.array.reshape(-1, 2)[:u.function_space.dofmap.index_map.size_local]
    return comm.allreduce(owned.sum(axis=0)) / comm.allreduce(len(owned))


def _falling(comm: MPI.Comm, path: pathlib.Path, steps: int = 250,
             newton: NewtonOptions | None = None) -> dict[str, np.ndarray]:
    """A 0.2 m × 0.1 m block released 1 mm above a base (μ = 0.5, χ = 1e-10)."""
    pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", 1e10, friction=0.5)
    model = _model(path, comm, [Rectangle("base", -0.5, -0.2, 1.0, 0.2, 50, 2),
                                Rectangle("block", -0.1, 1e-3, 0.2, 0.1, 4, 2)], pair,
                   fixed=[Fixed("base_bottom")], gravity=(0.0, -G),
                   damping=Damping(0.0, 1e-4))
    # β₁ = β₂ = 1: GN22's strongest numerical damping, so that the penalty bounce dies
    # out; free fall is exact for any β (constant acceleration).
    stepper = GN22(model, 1e-3, GN22Parameters(1.0, 1.0), newton=newton)
    stepper.initialise()
    provider = _provider(stepper)
    t, x, force, its = [], [], [], []
    for _ in range(steps):
        its.append(stepper.step())
        t.append(float(stepper.t.value))
        x.append(_mean_displacement(stepper, comm))
        force.append(provider.resultant())
    out = {"t": np.array(t), "x": np.array(x), "force": np.array(force),
           "its": np.array(its), "weight": np.array([model.weight()[1]])}
    stepper.destroy()
    return out


def test_falling_block_lands_and_settles(shared_dir: pathlib.Path) -> None:
    """Contact starts in the step that contains t = sqrt(2 g₀/g) = 14.28 ms, and the
    resultant settles to the weight (1e-6; measured 1e-10 at 0.25 s) with no shear."""
    r = _falling(COMM, shared_dir / "fall.msh")
    t_land = np.sqrt(2 * 1e-3 / G)
    first = np.flatnonzero(r["force"][:, 1] > 0)[0]
    assert r["t"][first] - 1e-3 < t_land <= r["t"][first]
    weight = r["weight"][0]
    assert abs(r["force"][-1, 1] / weight - 1) < 1e-6
    assert abs(r["force"][-1, 0]) < 1e-6 * weight
    # Once settled, Newton converges in one iteration (the contact state is fixed).
    assert np.all(r["its"][-50:] == 1)


def _sliding(comm: MPI.Comm, path: pathlib.Path, steps: int = 95,
             newton: NewtonOptions | None = None) -> dict[str, np.ndarray]:
    """A 0.1 m × 0.05 m block (3 elements wide) pushed along a 0.4 m base (20 elements)."""
    μ, w, h = 0.6, 0.1, 0.05
    m = STEEL_LIKE.density * w * h
    F = 1.5 * μ * m * G
    pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", 1e10, friction=μ)
    model = _model(path, comm, [Rectangle("base", -0.1, -0.05, 0.4, 0.05, 20, 2),
                                Rectangle("block", -0.05, 0.0, w, h, 3, 2)], pair,
                   fixed=[Fixed("base_bottom")], gravity=(0.0, -G),
                   loads=[SurfaceLoad("block_left", (F / h, 0.0), lambda t: 1.0)],
                   damping=Damping(0.0, 1e-4))
    stepper = GN22(model, 4e-3, newton=newton)
    stepper.initialise()
    provider = _provider(stepper)
    t, x, force, its = [], [], [], []
    for _ in range(steps):
        its.append(stepper.step())
        t.append(float(stepper.t.value))
        x.append(_mean_displacement(stepper, comm)[0])
        force.append(provider.resultant())
    out = {"t": np.array(t), "x": np.array(x), "force": np.array(force),
           "its": np.array(its), "F": np.array([F]), "m": np.array([m]),
           "N": np.array([m * G]), "mu": np.array([μ]),
           "search": np.array([provider.search_seconds / max(provider.searches, 1)])}
    stepper.destroy()
    return out


def test_finite_sliding(shared_dir: pathlib.Path) -> None:
    """x(t) = (F − μN) t²/(2m) within 2 % after the first 0.02 s (measured 3e-4, then
    falling to 1e-6), over more than 10 master element lengths (0.02 m; measured
    0.212 m); the friction force μN with no snags at the master nodes once the vertical
    transient of the block placed at zero gap has died out (t > 0.15 s): within 1e-3
    of μN (measured 1e-5 while the block crosses 8 master nodes)."""
    r = _sliding(COMM, shared_dir / "slide.msh")
    F, m, N, μ = r["F"][0], r["m"][0], r["N"][0], r["mu"][0]
    ref = (F - μ * N) * r["t"] ** 2 / (2 * m)
    assert r["x"][-1] > 10 * 0.02
    early = r["t"] > 0.02
    assert np.abs(r["x"][early] / ref[early] - 1).max() < 0.02
    late = r["t"] > 0.15
    assert np.abs(r["force"][late, 0] / (μ * N) + 1).max() < 1e-3
    assert np.abs(r["force"][late, 1] / N - 1).max() < 1e-3
    assert r["its"][late].max() <= 3


@pytest.mark.parametrize("master", [("base_top",), ("base_top", "base_right")])
def test_sliding_over_the_master_end(shared_dir: pathlib.Path,
                                     master: tuple[str, ...]) -> None:
    """A block hanging a third over its base's end, pushed back along it by 1.5 μN: the
    friction is μ times the normal resultant at every step (1e-5; measured 1e-6), and
    the block slides as the rigid one, (F − μN) t²/(2m), to 1 % at 0.08 s (measured
    0.02 %). The slave facet the base's end cuts gave its far node a negative normal
    force λ_k = ∫ p N_k, left out of the friction: μ × 1.04 to 1.0, and 9 % less slide
    (newtonaids.friction_normals; found by a user). With the base's end face in the
    master surface (the whole surface a sliding body can reach), the nodes past the
    base's corner took their start-of-step projection, the friction's tangent, on the
    end face: the friction fell to 0.45 μN as a block slid over the end (found on the
    user path, 2026-11-28; searchkernels.frozen faces the node's normal now)."""
    μ, w, h = 0.6, 0.1, 0.05
    m = STEEL_LIKE.density * w * h
    F = 1.5 * μ * m * G
    pair = SurfacePair("c", "block", "base", "block_bottom", master, 1e10, friction=μ)
    model = _model(shared_dir / "overhang.msh", COMM,
                   [Rectangle("base", -0.1, -0.05, 0.4, 0.05, 20, 2),
                    Rectangle("block", 0.25, 0.0, w, h, 3, 2)], pair,
                   fixed=[Fixed("base_bottom")], gravity=(0.0, -G),
                   loads=[SurfaceLoad("block_right", (-F / h, 0.0), lambda t: 1.0)],
                   damping=Damping(0.0, 1e-4))
    stepper = GN22(model, 4e-3)
    stepper.initialise()
    provider = _provider(stepper)
    for _ in range(20):
        stepper.step()
        force = provider.resultant()
        assert force[0] / force[1] == pytest.approx(μ, rel=1e-5)
    t = float(stepper.t.value)
    x = _mean_displacement(stepper, COMM)[0]
    stepper.destroy()
    assert 0.25 + w + x > 0.3  # still hanging over the end
    assert -x == pytest.approx((F - μ * m * G) * t**2 / (2 * m), rel=0.01)


# --- validation --------------------------------------------------------------------

def test_surface_on_the_wrong_body(shared_dir: pathlib.Path) -> None:
    """A slave surface on the master body (or a missing group) is a clear error."""
    bodies = [Rectangle("base", -0.5, -0.2, 1.0, 0.2, 50, 2),
              Rectangle("block", -0.1, 0.0, 0.2, 0.1, 2, 1)]
    wrong = SurfacePair("c", "block", "base", "base_top", "base_top", 1e10)
    with pytest.raises(MeshError, match="contact.c.slave_surface: 'base_top' lies on body "
                                        r"'base', not on the slave 'block' \(facet groups on "
                                        "'block': block_bottom, block_left, block_right, "
                                        r"block_top\)"):
        _model(shared_dir / "bad.msh", COMM, bodies, wrong)
    missing = SurfacePair("c", "block", "base", "block_base", "base_top", 1e10)
    with pytest.raises(Exception, match="block_base"):
        _model(shared_dir / "bad.msh", COMM, bodies, missing)
    with pytest.raises(ValueError, match="two different bodies"):
        SurfacePair("c", "block", "block", "block_bottom", "base_top", 1e10)


@pytest.mark.parametrize(("slave", "master", "key"), [
    ("block_top", "base_top", "slave_surface"), ("block_left", "base_top", "slave_surface"),
    ("block_bottom", "base_bottom", "master_surface")])
def test_surfaces_that_do_not_face_each_other(shared_dir: pathlib.Path, slave: str,
                                              master: str, key: str) -> None:
    """A slave surface that exists on the slave, but faces away from the master (the
    block's top or side for its bottom; or the base's underside for its top), is refused
    before the static state, naming the key and the groups that face. Before: the top
    sank the block through the base until its top met the base's (exit 0), the side ended
    in "no static equilibrium"."""
    bodies = [Rectangle("base", -0.5, -0.2, 1.0, 0.2, 50, 2),
              Rectangle("block", -0.1, 0.0, 0.2, 0.1, 2, 1)]
    model = _model(shared_dir / "facing.msh", COMM, bodies,
                   SurfacePair("c", "block", "base", slave, master, 1e10),
                   fixed=[Fixed("base_bottom")], gravity=(0.0, -G))
    with pytest.raises(MeshError) as info:
        GN22(model, 1e-3)
    message = str(info.value)
    assert message.startswith(f"contact.c.{key}: slave_surface '{slave}' does not face "
                              f"master_surface '{master}' anywhere")
    assert message.endswith("groups of 'block' that face 'base_top': block_bottom; groups "
                            "of 'base' that 'block_top' faces: none" if slave == "block_top"
                            else "groups of 'base' that 'block_bottom' faces: base_top"
                            if key == "master_surface" else "block_bottom; groups of "
                            "'base' that 'block_left' faces: none")
    assert "\n" not in message


def test_reference_solver_refuses_general_pairs(shared_dir: pathlib.Path) -> None:
    """General pairs run on the fast solver only."""
    pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", 1e10)
    model = _model(shared_dir / "ref.msh", COMM,
                   [Rectangle("base", -0.5, -0.2, 1.0, 0.2, 50, 2),
                    Rectangle("block", -0.1, 0.0, 0.2, 0.1, 2, 1)], pair)
    with pytest.raises(ValueError, match="fast solver"):
        GN22(model, 1e-3, solver="reference")


# --- partitions --------------------------------------------------------------------

@pytest.mark.skipif(COMM.size < 2, reason="compares serial and parallel runs")
@pytest.mark.parametrize("run", [_falling, _sliding], ids=["falling", "sliding"])
def test_histories_equal_serial(run, shared_dir: pathlib.Path) -> None:  # type: ignore[no-untyped-def]
    """The same history on 2 ranks as serially (rank 0 repeats it on COMM_SELF), to
    1e-10 relative: every rank evaluates the same points in the same order, so the
    partition changes only the bulk's round-off."""
    # Newton to round-off: the tolerances of a run (1e-9) let two partitions stop at
    # iterates 1e-9 apart, and a sticking impact keeps that difference in the position.
    tight = NewtonOptions(rtol=1e-14, atol=1e-13)
    parallel = run(COMM, shared_dir / "world.msh", 60, tight)
    serial = None
    if COMM.rank == 0:
        serial = run(MPI.COMM_SELF, shared_dir / "serial.msh", 60, tight)
    serial = COMM.bcast(serial, root=0)
    np.testing.assert_array_equal(parallel["t"], serial["t"])
    # The kinematics to 1e-9 of their scale (measured 2.6e-10 falling, 2.8e-10 sliding;
    # the issue asks 1e-10 of the kinematics, which test_kinematics_equal_serial checks
    # for one state): a partition changes the bulk solve's round-off, and these runs
    # amplify round-off — serially, perturbing u and v by a relative 1e-16 after each
    # step moves the same histories by 2.4e-10 (falling) and 3.3e-10 (sliding): the
    # penalty impact and the stick tangent μλ/χ (χ = 1e-10) do it, not the pair's
    # evaluation, which is the same on every partition.
    scale = np.abs(serial["x"]).max()
    assert np.abs(parallel["x"] - serial["x"]).max() <= 1e-9 * scale
    # The forces to 1e-7 of their scale: where the interface sticks, the friction law's
    # tangent μλ/χ ~ 5e11 N s/m (χ = 1e-10) turns velocity round-off of 1e-15 m/s into
    # 5e-4 N (measured 3e-4 N against a weight of 392 N; the kinematics are unaffected).
    scale = np.abs(serial["force"]).max()
    assert np.abs(parallel["force"] - serial["force"]).max() <= 1e-7 * scale


def _kinematics(comm: MPI.Comm, path: pathlib.Path, **options: str
                ) -> dict[str, np.ndarray]:
    """The pair's kinematics and forces for one displacement field, given as a formula.

    A block (element size 1/20 m) 30 mm to the right of where it was meshed, tilted
    into a base of element size 1/7 m (non-matching: the gap from +10 μm to −30 μm),
    both strained; the velocities of a slide at 0.1 m/s.
    """
    pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", 1e10, friction=0.5,
                       **options)  # type: ignore[arg-type]
    model = _model(path, comm, [Rectangle("base", -0.5, -0.2, 1.0, 0.2, 50, 2),
                                Rectangle("block", -0.1, 0.0, 0.2, 0.1, 4, 2)], pair)
    stepper = GN22(model, 1e-3)
    stepper.initialise()

    def block(x: np.ndarray) -> np.ndarray:
        return np.vstack([0.03 + 1e-4 * x[1], -1e-5 * (1 + 20 * x[0]) - 1e-4 * x[1]])

    def base(x: np.ndarray) -> np.ndarray:
        return np.vstack([1e-5 * np.sin(3 * x[0]), 1e-5 * x[1] * np.cos(2 * x[0])])

    def slide(x: np.ndarray) -> np.ndarray:
        return np.vstack([np.full(x.shape[1], 0.1), 1e-3 * x[0]])

    stepper.u[0].interpolate(base)
    stepper.u[1].interpolate(block)
    stepper.v[1].interpolate(slide)
    provider = _provider(stepper)
    out = provider.state()
    out["resultant"] = provider.resultant()
    stepper.destroy()
    return out


@pytest.mark.skipif(COMM.size < 2, reason="compares serial and parallel runs")
@pytest.mark.parametrize("options", [{}, {"integration": "nodes", "rotations": "small"}],
                         ids=["segments-finite", "nodes-small"])
def test_kinematics_equal_serial(options: dict[str, str], shared_dir: pathlib.Path) -> None:
    """For the same displacements the pair's kinematics on 2 ranks equal the serial
    ones (issue 12: to 1e-10 relative): integration points, projections (master facet
    and ξ̄), gaps, pressures and the resultant. Every rank gathers the surfaces in one
    order and evaluates every point the same way; what differs is the last bit of the
    reference coordinates (dolfinx tabulates the P2 nodes cell by cell): measured
    5e-14 of the gap's scale, 3e-14 of the resultant, 2e-16 in ξ̄; we ask 1e-12.
    (The histories above differ by more: a partition changes the bulk solve's
    round-off, which the dynamics amplifies; see the README.)"""
    parallel = _kinematics(COMM, shared_dir / "kin_world.msh", **options)
    serial = None
    if COMM.rank == 0:
        serial = _kinematics(MPI.COMM_SELF, shared_dir / "kin_serial.msh", **options)
    serial = COMM.bcast(serial, root=0)
    closed = serial["gap"] <= 0
    assert closed.sum() > 5 and (~closed).sum() > 0  # in contact, with open points
    np.testing.assert_array_equal(parallel["facet"], serial["facet"])
    for key in ("x", "xi", "gap", "pressure", "weight", "resultant"):
        a, b = np.nan_to_num(parallel[key]), np.nan_to_num(serial[key])
        assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max(), key


# --- the case ----------------------------------------------------------------------

EXAMPLE = pathlib.Path(__file__).parents[1] / "examples" / "sliding_block" / "sliding_block.toml"


def test_example_case_runs(shared_dir: pathlib.Path) -> None:
    """The example case (a general pair) runs from its file through the CLI; the block
    starts at rest on the base (the static state under its weight, applied with friction
    active: ``[initial] loading = "frictional"``; the push is not in the initial state)
    and slides with the rigid block's acceleration (F − μN)/m: the second
    difference of the corner probe's u_x over 10-20 ms within 2 % of it (measured 2e-4).

    u_x itself runs ahead of (F − μN) t²/(2m), by 8 % at 20 ms: the regularised law
    carries no friction at rest, so GN22 starts from a₀ = F/m and keeps (1 − β₁)Δt
    (F/m − (F − μN)/m) = 2e-3 m/s as a velocity offset (+0.8 % at the end of the push,
    0.2 s, and +1.2 % at 0.3 s, where the rigid block stops after 7.36 cm)."""
    from breakwater import cli
    from breakwater.common.files import read_history

    out = shared_dir / "run"
    assert cli.main(["run", str(EXAMPLE), "--out", str(out), "--no-progress", "--quiet",
                     "--set", "time.end_time=0.02", "--set", "output.field_interval=10"]) == 0
    h = read_history(out / "history.csv")
    t, ux = h["t"], h["corner_ux"]
    a = 0.5 * 0.5 * 9.81  # (F − μN)/m with F = 1.5 μN
    assert t[10] == pytest.approx(0.01) and t[20] == pytest.approx(0.02)
    second = (ux[20] - 2 * ux[15] + ux[10]) / (t[20] - t[15]) ** 2
    assert ux[-1] > ux[10] > 0
    assert abs(second / a - 1) < 0.02
    static = json.loads((out / "summary.json").read_text())["static"]
    assert static["initial_state"] == "frictional" and static["held_bodies"] == []
    assert static["relaxation_steps"] > 0
    # The pair's history columns: while the block slides, the friction resultant is
    # μ times the normal one (every contact node slides the same way).
    fx, fy = h["sliding_force_x"][-1], h["sliding_force_y"][-1]
    assert fy > 0 and abs(fx / fy + 0.5) < 1e-3
    assert h["sliding_contact_length"][-1] == pytest.approx(0.2)
    assert 0 < h["sliding_penetration"][-1] < 1e-6


def test_resume_with_a_general_pair(shared_dir: pathlib.Path,
                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """A run with a general pair killed after its checkpoint resumes to the history of
    the uninterrupted run (the state is u, v, a, and the pair rebuilds its surfaces and
    start-of-step projections from them; its slip velocities and the master facets its
    searches use are in the checkpoint): a block dropped 1 mm and pushed by 5 μN from
    t > 0 over a base of 20 mm facets, sliding about 9 mm by the checkpoint (the facets
    marked near its start are beyond its reach then: a resumed run that marked them
    afresh differed by 1.5e-11 of the kinetic energy, above the serial bound 1e-12)."""
    from breakwater.common.files import read_history
    from breakwater.config.runspec import OutputSpec, ProbeSpec, TimeSpec
    from breakwater.run import simulation

    mesh = rectangles(shared_dir / "resume.msh", COMM,
                      [Rectangle("base", -0.5, -0.2, 1.0, 0.2, 50, 2),
                       Rectangle("block", -0.1, 1e-3, 0.2, 0.1, 4, 2)])

    def run(directory: pathlib.Path, **kwargs: object) -> dict:
        pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", 1e10,
                           friction=0.5)
        model = ContactModel(read_mesh(mesh, COMM), [Body("base", STEEL_LIKE),
                                                     Body("block", STEEL_LIKE)],
                             fixed=[Fixed("base_bottom")], gravity=(0.0, -G),
                             loads=[SurfaceLoad("block_left", (9810.0, 0.0),
                                                lambda t: float(t > 0.0))],
                             surface_pairs=[pair])
        output = OutputSpec(directory, field_interval=0, figures=False, progress=False,
                            checkpoint_interval=5,
                            probes=(ProbeSpec("corner", "block", (-0.1, 1e-3)),))
        return simulation.run(model, TimeSpec(dt=1e-3, end_time=0.03), output,
                              report=False, **kwargs)  # type: ignore[arg-type]

    full = run(shared_dir / "full")
    assert full["finished"] is True
    run_killed_at(run, shared_dir / "resumed", 0.0225, monkeypatch)
    resumed = run(shared_dir / "resumed", resume=True)
    assert resumed["finished"] is True
    assert [r["t"] for r in resumed["resumed_from"]] == pytest.approx([0.02])
    a = read_history(shared_dir / "full" / "history.csv")
    b = read_history(shared_dir / "resumed" / "history.csv")
    np.testing.assert_array_equal(a["t"], b["t"])
    # Serially the resumed history is the uninterrupted one bit for bit (measured 0).
    # On 2 ranks two uninterrupted runs already differ by 6e-9 of u_x (the parallel
    # solves are not bitwise reproducible, and the friction law's stick tangent μλ/χ
    # amplifies their round-off); the resumed run is within that (measured 4e-9).
    rtol = 1e-12 if COMM.size == 1 else 1e-7
    for key in ("corner_ux", "corner_uy", "kinetic", "strain"):
        scale = np.abs(a[key]).max()
        assert np.abs(a[key] - b[key]).max() <= rtol * scale, key


def test_energy_ledger_with_a_general_pair(shared_dir: pathlib.Path) -> None:
    """The ledger counts a general pair's penalty energy and friction dissipation: a
    block dropped 1 mm and pushed by 1.5 μN (μ = 0.5), β₁ = β₂ = ½ (the trapezoidal
    rule, no numerical dissipation), the contact resolved in time (ε_n = 1e8 N/m³:
    contact period 2π sqrt(m/(ε_n w)) = 8.9 ms against Δt = 0.2 ms): the balance
    error stays below 1 % of the friction dissipation (measured 0.5 %, made at the
    impact; without the pair's terms it would be the whole dissipation)."""
    from breakwater.energy.ledger import EnergyLedger

    N = STEEL_LIKE.density * G * 0.2 * 0.1
    pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", 1e8, friction=0.5)
    model = _model(shared_dir / "energy.msh", COMM,
                   [Rectangle("base", -0.5, -0.2, 1.0, 0.2, 50, 2),
                    Rectangle("block", -0.1, 1e-3, 0.2, 0.1, 4, 2)], pair,
                   fixed=[Fixed("base_bottom")], gravity=(0.0, -G),
                   loads=[SurfaceLoad("block_left", (1.5 * 0.5 * N / 0.1, 0.0),
                                      lambda t: 1.0)])
    stepper = GN22(model, 2e-4, GN22Parameters(0.5, 0.5))
    stepper.initialise()
    ledger = EnergyLedger(stepper)
    ledger.record()
    penalty = 0.0
    for _ in range(125):
        stepper.step()
        row = ledger.record()
        penalty = max(penalty, row.penalty)
    assert penalty > 0 and row.friction_dissipation > 0.1
    assert abs(row.balance_error) < 1e-2 * row.friction_dissipation
    stepper.destroy()


def test_step_state_kept_only_within_the_newton(shared_dir: pathlib.Path) -> None:
    # Within a step's Newton the pair reads u, v, a gathered once (begin_step) and the
    # iterate as given; outside it, every evaluation gathers the state Functions: after
    # the step nothing is kept, and the pair's forces at the accepted state are those of
    # a fresh gather (the cache would give the start of the step's state).
    pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", 1e10, friction=0.5)
    model = _model(shared_dir / "keep.msh", COMM,
                   [Rectangle("base", -0.5, -0.2, 1.0, 0.2, 50, 2),
                    Rectangle("block", -0.1, 0.0, 0.2, 0.1, 3, 2)], pair,
                   fixed=[Fixed("base_bottom")], gravity=(0.0, -G))
    stepper = GN22(model, 1e-3)
    try:
        stepper.initialise()
        provider = _provider(stepper)
        before = provider.interface_values(stepper.u)
        for _ in range(3):
            stepper.step()
        assert provider._step is None and provider._iterate is None
        u0, _, _ = provider._state()  # a kept state would be the last step's start
        after = provider.interface_values(stepper.u)
        assert not np.array_equal(after, before)  # the block moved
        assert np.array_equal(u0, after)
        assert not provider.at(np.zeros(provider.n))  # outside a step: nothing kept
    finally:
        stepper.destroy()


def _shaken(path: pathlib.Path) -> tuple[GN22, SurfaceContact]:
    """A block on a non-matching base shaken sideways below μN (50 Hz, 0.5 μmg), started."""
    μ, w, h = 0.6, 0.1, 0.05
    m = STEEL_LIKE.density * w * h
    pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", 1e10, friction=μ)
    model = _model(path, COMM, [Rectangle("base", -0.1, -0.05, 0.3, 0.05, 9, 2),
                                Rectangle("block", -0.05, 0.0, w, h, 4, 2)], pair,
                   fixed=[Fixed("base_bottom")], gravity=(0.0, -G),
                   loads=[SurfaceLoad("block_left", (0.5 * μ * m * G / h, 0.0),
                                      lambda t: float(np.sin(2 * np.pi * 50 * t)))])
    stepper = GN22(model, 5e-4)
    stepper.initialise()
    return stepper, _provider(stepper)


def test_slip_predictor_keeps_the_last_slip_velocity(shared_dir: pathlib.Path) -> None:
    """Newton's start of a step keeps each slave node's converged slip velocity.

    A block resting on a non-matching base and shaken sideways below μN (it sticks and
    rocks: the normal rate and the master's rotation move the projection and tangent
    from step to step). After each accepted step, the start of the next that
    :meth:`SlipMemory.predict` makes has, at every node in contact, the slip velocity
    the last step converged to (measured against the new step's projection and
    tangent), to 1e-6 of it or of χ (round-off of the landing); the predictor moves
    only the slave unknowns of those nodes, tangentially. Some nodes stick (|v_T| < 10 χ).
    """
    stepper, provider = _shaken(shared_dir / "shake.msh")
    χ = provider.spec.regularisation
    moved = sticking = 0
    for _ in range(12):
        stepper.step()
        assert provider.memory.slip is not None
        stuck = np.abs(provider.memory.slip) < 10 * χ  # NaN (out of contact): False
        sticking += int(stuck.sum())
        # The next step's start, as CondensedNewton.solve makes it.
        stepper.stage()
        provider.begin_step()
        try:
            y0 = provider._start()[3][:-1].copy()  # Δa = −a/β₁ at the unknowns
            y = y0.copy()
            moved += provider.memory.predict(y)
            u0, _, v1 = provider._state(y)
            frozen = provider._frozen(u0)
            along = provider.memory.along(v1, *frozen)
            # The compiled slip velocities against their NumPy statement (NaN: no
            # facet), to the round-off of a sum of four products of |v| each.
            facet, N0, t0 = frozen
            vm = np.einsum("jb,jbd->jd", N0, v1[provider._pm[np.maximum(facet, 0)]])
            ref = np.einsum("jd,jd->j", v1[provider.node_pos] - vm, t0)
            ref[facet < 0] = np.nan
            np.testing.assert_allclose(along, ref, rtol=0, atol=1e-15 * np.abs(v1).max())
            keep = np.isfinite(provider.memory.slip) & np.isfinite(along)
            scale = np.maximum(np.abs(provider.memory.slip[keep]), χ)
            assert np.all(np.abs(along[keep] - provider.memory.slip[keep]) < 1e-6 * scale)
            change = (y - y0)[provider.node_pos[keep]]
            assert np.allclose(np.einsum("jd,jd->j", change, frozen[2][keep][:, ::-1]
                                         * np.array([1.0, -1.0])), 0.0, atol=1e-12)
            others = np.ones(provider.n, bool)
            others[provider.node_pos[keep].ravel()] = False
            assert np.array_equal(y[others], y0[others])
        finally:
            provider.end_step()
    assert moved > 0 and sticking > 0
    stepper.destroy()


def test_resolution_bounds_the_round_off_of_the_forces(shared_dir: pathlib.Path) -> None:
    """``newtonaids.resolution`` bounds what round-off of the velocities does to f_c.

    The block of the slip-predictor test, shaken below μN: at each step's start, v, a
    and the iterate Δa perturbed by a relative ε (random signs, 20 draws: the round-off
    of the terms of v₁ = v + Δt a + β₁Δt Δa) move f_c by less than the estimate (an
    upper bound, the terms' magnitudes summed: measured 0.004–0.05 of it; 0.1 on the
    separately meshed Goda case) and, where nodes stick, by more than
    1e-3 of it (the estimate is the stick tangent's, not a loose constant).
    """
    stepper, provider = _shaken(shared_dir / "shake2.msh")
    rng = np.random.default_rng(23)
    ε = np.finfo(float).eps
    ratios = []
    for _ in range(10):
        stepper.step()
        stepper.stage()
        provider.begin_step()
        try:
            y = provider._start()[3][:-1].copy()
            provider.memory.predict(y)
            bound = provider.resolution(y)
            provider.at(y)
            f0 = provider.vector()
            u, v, a = (np.array(x) for x in provider._step)
            worst = 0.0
            for _ in range(20):
                def perturbed(x: np.ndarray) -> np.ndarray:
                    return x * (1 + ε * rng.choice((-1.0, 1.0), x.shape))
                provider._step = np.array([u, perturbed(v), perturbed(a)])
                provider._frozen_key = None
                provider.at(perturbed(y))
                worst = max(worst, float(np.linalg.norm(provider.vector() - f0)))
            provider._step = np.array([u, v, a])
            provider._frozen_key = None
            assert worst <= bound
            ratios.append(worst / bound if bound else np.nan)
        finally:
            provider.end_step()
    assert np.nanmax(ratios) > 1e-3
    stepper.destroy()


def test_friction_kept_per_iterate_follows_the_crawl_points(shared_dir: pathlib.Path) -> None:
    """The residual of an iterate is recomputed when its crawl points change.

    The residual and the Jacobian of one iterate share the nodal friction
    (:func:`breakwater.contact.general.nodal_friction`). The slip guard's crawl points
    and their drop (the solve tested again on the law itself) change the friction at the
    same iterate:
    the block of the sliding test, mid-slide, a step that grows every slip tenfold (so the
    guard sets crawl points; twice, so that they are written into the array the first
    evaluation read), f_c at the iterate before, with and after the drop of the crawl
    points, each against a fresh evaluation (the kept friction cleared).
    """
    μ, w, h = 0.6, 0.1, 0.05
    m = STEEL_LIKE.density * w * h
    pair = SurfacePair("c", "block", "base", "block_bottom", "base_top", 1e10, friction=μ)
    model = _model(shared_dir / "crawlkeep.msh", COMM,
                   [Rectangle("base", -0.1, -0.05, 0.4, 0.05, 20, 2),
                    Rectangle("block", -0.05, 0.0, w, h, 3, 2)], pair,
                   fixed=[Fixed("base_bottom")], gravity=(0.0, -G),
                   loads=[SurfaceLoad("block_left", (1.5 * μ * m * G / h, 0.0), lambda t: 1.0)])
    stepper = GN22(model, 4e-3)
    try:
        stepper.initialise()
        provider = _provider(stepper)
        for _ in range(20):
            stepper.step()
        stepper.stage()
        provider.begin_step()
        try:
            x = provider._start()[3][:-1].copy()
            x.setflags(write=False)
            provider.at(x)

            def fresh() -> np.ndarray:
                provider._kept_friction = None
                return provider.vector()

            law = provider.vector()
            np.testing.assert_array_equal(law, fresh())
            u0, _, v1 = provider._state()
            frozen = provider._frozen(u0)
            along = provider.memory.along(v1, *frozen)
            sliding = np.isfinite(along) & (np.abs(along) > 100 * pair.regularisation)
            assert sliding.sum() >= 3  # the block slides
            step = np.zeros(provider.n)  # c₁ = c₀ − β₁Δt t₀·δ_s = 10 c₀ at those nodes
            dv = provider.beta1 * provider.step_dt()
            for j in np.flatnonzero(sliding):
                for d in range(2):
                    if provider.node_pos[j, d] >= 0:
                        step[provider.node_pos[j, d]] = -9 * along[j] * frozen[2][j, d] / dv
            for grow in (1.0, 1e3):  # the guard's two arrays: the second writes law's
                provider.precheck(x, grow * step)
                assert provider.crawl.any  # the guard set crawl points at the iterate
            on_lines = provider.vector()
            np.testing.assert_array_equal(on_lines, fresh())
            assert not np.array_equal(on_lines, law)
            assert provider.true_law()  # the drop: the law itself again
            np.testing.assert_array_equal(provider.vector(), law)
        finally:
            provider.end_step()
    finally:
        stepper.destroy()
