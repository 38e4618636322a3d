"""Static verification: self weight of a block on an elastic base, and a contact patch test.

Both run on ``MPI.COMM_WORLD`` (serially and under ``mpiexec -n 2``); nodal interface values
come from :class:`breakwater.contact.conforming.InterfaceNodes`, which gathers them on every rank.
"""

from __future__ import annotations

import pathlib
import sys

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
import ufl
from dolfinx import fem

from breakwater import forms  # type: ignore[attr-defined]
from breakwater.contact.conforming import InterfaceNodes
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, ContactPair, Fixed, Material, SurfaceLoad
from breakwater.stepping.gn22 import solve_static
from breakwater.stepping.solver import NewtonOptions

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from blocks import two_rectangles

COMM = MPI.COMM_WORLD

# Goda's caisson (the paper's §5): concrete block 0.205 m wide, 0.202 m high, ρ = 2314 kg/m³,
# G = 2e9 Pa, ν = 0.2; penalty ε_n = 5e8 N/m³. The base stands in for the mound: softer
# (G = 3e6 Pa, ν = 0.25), wider than the block, 0.19 m high (the mound height).
CAISSON = Material(density=2314.0, poisson=0.2, shear_modulus=2e9)
MOUND = Material(density=2000.0, poisson=0.25, shear_modulus=3e6)
B_CAISSON, H_CAISSON = 0.205, 0.202
B_BASE, H_BASE = 0.6, 0.19
PENALTY = 5e8
G = 9.81


def _say(*args: object) -> None:
    if COMM.rank == 0:
        print(*args)


def _nodal_pressure(model: ContactModel, u: list[fem.Function]) -> tuple[np.ndarray, np.ndarray]:
    """Nodal coordinates and pressures p = ε_n max(0, −(u_s − u_m)·n), GN22-independent."""
    pair = model.pairs[0]
    nodes = InterfaceNodes(model, pair)
    us, um = nodes.gather(u[pair.slave].x.array, u[pair.master].x.array)
    g_n = np.sum((us - um) * nodes.normal, axis=1)
    return nodes.x, pair.spec.penalty * np.maximum(0.0, -g_n)


def _simpson(x: np.ndarray, p: np.ndarray) -> float:
    """∫ p dx over a straight line of P2 facets from nodal values (nodes sorted along x).

    Vertices are the even nodes, facet midpoints the odd ones; Simpson's rule is the
    3-point Gauss-Lobatto rule of the contact measure.
    """
    assert len(x) % 2 == 1
    L = x[2::2] - x[:-2:2]
    return float(np.sum(L / 6.0 * (p[:-2:2] + 4.0 * p[1::2] + p[2::2])))


def test_self_weight(folder: pathlib.Path) -> None:
    """A block resting on an elastic base under gravity (the paper's §5.4, Fig. 17)."""
    path = two_rectangles(folder / "self_weight.msh", COMM, a=(B_CAISSON, H_CAISSON),
                          b=(B_BASE, H_BASE), h=0.025)
    model = ContactModel(read_mesh(path, COMM),
                         [Body("a", CAISSON), Body("b", MOUND)],
                         [ContactPair("interface", "a", "b", PENALTY)],
                         [Fixed("b_bottom")], gravity=(0.0, -G))
    u, its = solve_static(model)  # raises ConvergenceError unless Newton converged
    assert 1 <= its <= NewtonOptions().max_it

    pair = model.pairs[0]
    # p = t·n with the model's own (frictionless) traction and contact quadrature.
    resultant = model.assemble(model.form(ufl.dot(model.traction(pair, u, None), pair.n)
                                          * pair.dS))
    # Reference: the block's weight per metre, ρ g b h (the block is a rectangle, so its
    # area is exact on the mesh); the mean pressure is ρ g h = 2314·9.81·0.202 = 4586 Pa
    # (the paper's §5.4).
    weight = CAISSON.density * G * B_CAISSON * H_CAISSON
    mean_ref = CAISSON.density * G * H_CAISSON
    mean = resultant / B_CAISSON
    err_weight = abs(resultant - weight) / weight
    err_mean = abs(mean - mean_ref) / mean_ref
    _say(f"\nself weight: Newton its {its}, resultant {resultant:.10g} N/m vs weight "
         f"{weight:.10g} N/m (rel. err {err_weight:.2e}); mean pressure {mean:.10g} Pa vs "
         f"ρgh {mean_ref:.10g} Pa (rel. err {err_mean:.2e})")
    # Tolerance 1e-8: the block's vertical equilibrium is the sum of its y-residual rows,
    # ∫p dS − W, and Newton stops at a residual of 1e-9 of the force scale (NewtonOptions);
    # its last step is quadratic, so the measured error is round-off (~1e-15).
    assert err_weight < 1e-8
    assert err_mean < 1e-8

    # Pressure shape from nodal displacements, independent of the contact quadrature.
    x, p = _nodal_pressure(model, u)
    x = x[:, 0]
    # The contact measure is nodal (Gauss-Lobatto): Simpson on the nodal pressures must
    # give the same resultant up to round-off (1e-10: the same products, summed apart).
    nodal_resultant = _simpson(x, p)
    _say(f"nodal-route resultant {nodal_resultant:.10g} N/m "
         f"(rel. diff {abs(nodal_resultant - resultant) / weight:.2e})")
    assert abs(nodal_resultant - resultant) < 1e-10 * weight
    # A stiff block on a soft base behaves as a rigid footing (the paper's §5.4): pressure maxima
    # at the edges, minimum near the centre.
    centre = int(np.argmin(np.abs(x)))
    _say(f"pressures: left edge {p[0]:.1f} Pa, centre {p[centre]:.1f} Pa, right edge "
         f"{p[-1]:.1f} Pa")
    assert abs(x[0] + B_CAISSON / 2) < 1e-12 and abs(x[-1] - B_CAISSON / 2) < 1e-12
    assert np.all(p > 0), "the whole base of the block must be in contact"
    assert p[0] > p[centre] and p[-1] > p[centre]
    assert p[0] == p.max() or p[-1] == p.max()
    assert np.all(p[1:-1] < min(p[0], p[-1]))  # both edges exceed every interior node
    assert abs(x[np.argmin(p)]) < 0.1 * B_CAISSON  # the minimum lies in the central 20%


@pytest.mark.parametrize("structured", [True, False], ids=["structured", "unstructured"])
def test_contact_patch(folder: pathlib.Path, structured: bool) -> None:
    """Uniform pressure through a contact interface: a homogeneous field is exact.

    Two blocks of the same width and material, a uniform pressure p0 on top, the lower
    block on rollers (u_y = 0 at the bottom, u_x = 0 on its left side), no gravity. The
    exact solution is uniaxial stress σ_yy = −p0, σ_xx = σ_xy = 0 in both blocks, with
    displacements linear in x and y (Poisson expansion the same in both, so no tangential
    jump on the interface) plus a uniform normal jump −p0/ε_n across it. It lies in the P2
    space, so the discrete solution must reproduce it to round-off. The upper block's
    horizontal rigid mode, free in frictionless contact, is settled by solve_static (its
    Jacobian holds a tangential spring, its residual does not); it changes neither the
    stresses nor the pressures.
    """
    p0 = 1e4
    path = two_rectangles(folder / f"patch_{structured}.msh", COMM, a=(0.2, 0.2),
                          b=(0.2, 0.15), h=0.05, structured=structured)
    model = ContactModel(read_mesh(path, COMM),
                         [Body("a", CAISSON), Body("b", CAISSON)],
                         [ContactPair("interface", "a", "b", PENALTY)],
                         [Fixed("b_bottom", (1,)), Fixed("b_left", (0,))],
                         [SurfaceLoad("a_top", (0.0, -p0), lambda t: 1.0)])
    u, its = solve_static(model)

    # The output stress (forms.stress_3d): plane strain adds σ_zz = λ tr ε = ν(σ_xx + σ_yy)
    # = −ν p0, so the von Mises stress is p0 sqrt(1 − ν + ν²).
    λ, μ = CAISSON.lame
    ν = CAISSON.poisson
    exact = np.diag([0.0, -p0, -ν * p0])
    exact_vm = p0 * np.sqrt(1.0 - ν + ν**2)
    errors = {}
    midpoint = np.array([[1.0 / 3.0, 1.0 / 3.0]])
    for body in model.bodies:
        σ3 = forms.stress_3d(u[body.index], λ, μ)
        components = [σ3[i, j] for i in range(3) for j in range(3)]
        expr = fem.Expression(ufl.as_vector([*components, forms.von_mises(σ3)]), midpoint)
        ncells = body.submesh.topology.index_map(body.submesh.topology.dim).size_local
        values = expr.eval(body.submesh, np.arange(ncells, dtype=np.int32)).reshape(-1, 10)
        σ, vm = values[:, :9].reshape(-1, 3, 3), values[:, 9]
        local = max(float(np.abs(σ - exact).max()), float(np.abs(vm - exact_vm).max())) / p0 \
            if ncells else 0.0
        errors[body.spec.name] = COMM.allreduce(local, op=MPI.MAX)

    _, p = _nodal_pressure(model, u)
    err_p = float(np.abs(p - p0).max()) / p0
    _say(f"\npatch ({'structured' if structured else 'unstructured'}): Newton its {its}; max "
         f"|σ − σ_exact|/p0 (3 × 3 and von Mises) at cell midpoints: a {errors['a']:.2e}, "
         f"b {errors['b']:.2e}; "
         f"max |p − p0|/p0 over {len(p)} interface nodes {err_p:.2e}")
    # Tolerance 1e-8 relative: the exact solution is in the discrete space, so only the
    # Newton stop (residual 1e-9 of the force scale; the problem is linear once every node
    # is active, so one step lands on it) and round-off (~1e-12 measured) remain.
    assert errors["a"] < 1e-8
    assert errors["b"] < 1e-8
    assert err_p < 1e-8
