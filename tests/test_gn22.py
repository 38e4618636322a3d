"""Verification of the GN22 integrator (the paper's §4, eqs. 24-28) on a linear elastic oscillator.

The oscillator is a plane-strain cantilever (body ``a``, 1 m × 0.2 m, clamped on its left
side) without contact. Its semi-discrete equations M ü + K u = 0 are solved exactly by modal
decomposition of the M and K matrices assembled from the model's own forms; GN22 runs are
compared with that solution.

The model also holds a second, clamped body ``b`` that takes no part (no contact pair, zero
initial state): a model with one body cannot be stepped at present (see
:func:`test_single_body_model_steps`), and the decoupled second body leaves body ``a``'s
equations unchanged.
"""

from __future__ import annotations

import math
import pathlib
import sys
from dataclasses import dataclass

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc

from breakwater import forms  # type: ignore[attr-defined]
from breakwater.model.mesh import group_tag, read_mesh
from breakwater.model.model import Body, ContactModel, Fixed, Material
from breakwater.outputs.probes import PointProbe
from breakwater.stepping.gn22 import (
    GN22,
    GN22Parameters,
    gn22_kinematics,
    gn22_update,
    solve_static,
)

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from blocks import two_rectangles

COMM = MPI.COMM_WORLD
LENGTH, DEPTH = 1.0, 0.2
MATERIAL = Material(density=1000.0, poisson=0.25, shear_modulus=1e6)
TIP = (0.0, 0.0)  # lower corner of the free end of the cantilever


def _say(*args: object) -> None:
    if COMM.rank == 0:
        print(*args)


@dataclass
class Oscillator:
    """The cantilever model and its exact modal data (free dofs of body ``a``)."""

    model: ContactModel
    V: fem.FunctionSpace
    M: np.ndarray  # mass matrix on the free dofs
    K: np.ndarray  # stiffness matrix on the free dofs
    ω: np.ndarray  # natural frequencies, ascending (rad/s)
    Φ: np.ndarray  # M-orthonormal mode shapes (columns)
    free: np.ndarray  # mask of the free dofs in the global (PETSc) numbering
    start: int  # first global dof owned by this rank
    nlocal: int  # dofs owned by this rank

    def to_function(self, vec: np.ndarray, f: fem.Function) -> fem.Function:
        """Write a vector of free dofs into a Function of body ``a``."""
        full = np.zeros(len(self.free))
        full[self.free] = vec
        f.x.array[:] = 0.0
        f.x.array[: self.nlocal] = full[self.start:self.start + self.nlocal]
        f.x.scatter_forward()
        return f

    def from_function(self, f: fem.Function) -> np.ndarray:
        """The free dofs of a Function of body ``a``, on every rank."""
        return np.concatenate(COMM.allgather(f.x.array[: self.nlocal]))[self.free]

    def energy(self, u: fem.Function, v: fem.Function) -> float:
        """Total energy ½ v·Mv + ½ u·Ku of the semi-discrete system."""
        uu, vv = self.from_function(u), self.from_function(v)
        return float(0.5 * vv @ self.M @ vv + 0.5 * uu @ self.K @ uu)


def _dense(model: ContactModel, form: ufl.Form, bcs: list[fem.DirichletBC]) -> np.ndarray:
    """Assemble a bilinear form and return the global dense matrix on every rank."""
    A = fem_petsc.assemble_matrix(model.form(form), bcs=bcs)
    A.assemble()
    indptr, indices, values = A.getValuesCSR()
    r0, r1 = A.getOwnershipRange()
    rows = np.zeros((r1 - r0, A.getSize()[1]))
    for i in range(r1 - r0):
        rows[i, indices[indptr[i]:indptr[i + 1]]] = values[indptr[i]:indptr[i + 1]]
    A.destroy()
    return np.vstack(COMM.allgather(rows))


@pytest.fixture(scope="module")
def oscillator(folder: pathlib.Path) -> Oscillator:
    path = two_rectangles(folder / "cantilever.msh", COMM,
                          a=(LENGTH, DEPTH), b=(0.1, DEPTH), h=0.1, layout="side")
    data = read_mesh(path, COMM)
    model = ContactModel(data, [Body("a", MATERIAL), Body("b", MATERIAL)],
                         fixed=[Fixed("a_left"), Fixed("b_right")])
    body = model.body("a")
    V = body.V
    # The same clamped dofs as the model's Fixed("a_left"), for body a's own matrices.
    fdim = model.mesh.topology.dim - 1
    dofs = fem.locate_dofs_topological(V, fdim,
                                       body.facet_tags.find(group_tag(data, "a_left", fdim)))
    bcs = [fem.dirichletbc(np.zeros(model.gdim), dofs, V)]
    trial, test = ufl.TrialFunction(V), ufl.TestFunction(V)
    M = _dense(model, forms.inertia(body.ρ, trial, test, body.dx), bcs)
    K = _dense(model, forms.elastic_residual(trial, test, body.λ, body.μ, body.dx), bcs)
    bs = V.dofmap.index_map_bs
    nlocal = V.dofmap.index_map.size_local * bs
    start = V.dofmap.index_map.local_range[0] * bs
    marker = fem.Function(V)
    marker.x.array[:] = 1.0
    bcs[0].set(marker.x.array)
    free = np.concatenate(COMM.allgather(marker.x.array[:nlocal])) == 1.0
    Mf, Kf = M[np.ix_(free, free)], K[np.ix_(free, free)]
    # Generalised symmetric eigenproblem K φ = ω² M φ through the Cholesky factor of M.
    L_inv = np.linalg.inv(np.linalg.cholesky(Mf))
    ω2, Y = np.linalg.eigh(L_inv @ Kf @ L_inv.T)
    assert ω2[0] > 0
    osc = Oscillator(model, V, Mf, Kf, np.sqrt(ω2), L_inv.T @ Y, free, start, nlocal)
    _say(f"\ncantilever: {free.sum()} free dofs, ω1 = {osc.ω[0]:.4f} rad/s, "
         f"ω_max = {osc.ω[-1]:.1f} rad/s")
    return osc


def test_parameters_rejected() -> None:
    """GN22 is unconditionally stable only for β2 ≥ β1 ≥ ½ (Katona & Zienkiewicz 1985)."""
    for β1, β2 in ((0.6, 0.55), (0.5, 0.45), (0.45, 0.6), (0.4, 0.4)):
        with pytest.raises(ValueError, match=r"beta2 >= beta1 >= 0\.5"):
            GN22Parameters(β1, β2)
        p = GN22Parameters(β1, β2, allow_conditional=True)
        assert (p.beta1, p.beta2) == (β1, β2)
    for β1, β2 in ((0.5, 0.5), (0.6, 0.605), (0.5, 1.0)):
        GN22Parameters(β1, β2)


@pytest.mark.parametrize(("β1", "β2", "order"), [(0.5, 0.5, 2.0), (0.6, 0.605, 1.0)],
                         ids=["trapezoidal", "damped"])
def test_order_of_accuracy(oscillator: Oscillator, β1: float, β2: float, order: float) -> None:
    """Observed order of the tip displacement and of the energy-norm error at fixed T.

    Initial state: the first mode, u0 = φ1, v0 = 0, so the exact semi-discrete solution is
    u(t) = φ1 cos(ω1 t). GN22 is second order only for β1 = ½ (Katona & Zienkiewicz 1985;
    the Newmark γ = ½ condition): β1 > ½ adds an O(Δt) amplitude decay. T = 17/16 periods
    puts the tip where both the phase error (∝ sin ω1T) and the amplitude error
    (∝ cos ω1T) show; Δt = T/80, T/160, T/320 (ω1Δt ≤ 0.083).
    """
    osc = oscillator
    ω, φ = osc.ω[0], osc.Φ[:, 0]
    T = 17.0 / 16.0 * 2.0 * math.pi / ω
    probe = PointProbe(osc.model, "a", TIP)
    u0 = osc.to_function(φ, fem.Function(osc.V))
    exact_tip = probe.value(osc.to_function(φ * math.cos(ω * T), fem.Function(osc.V)))
    tip_errors, energy_errors = [], []
    for n in (80, 160, 320):
        stepper = GN22(osc.model, T / n, GN22Parameters(β1, β2))
        stepper.initialise([u0, None])
        for _ in range(n):
            stepper.step()
        assert math.isclose(float(stepper.t.value), T, rel_tol=1e-12)
        tip_errors.append(float(np.linalg.norm(probe.value(stepper.u) - exact_tip)))
        du = osc.from_function(stepper.u[0]) - φ * math.cos(ω * T)
        dv = osc.from_function(stepper.v[0]) + φ * ω * math.sin(ω * T)
        energy_errors.append(math.sqrt(du @ osc.K @ du + dv @ osc.M @ dv))
        assert not stepper.u[1].x.array.any()  # the idle body stays at rest
    tip_orders = np.log2(np.array(tip_errors[:-1]) / tip_errors[1:])
    energy_orders = np.log2(np.array(energy_errors[:-1]) / energy_errors[1:])
    _say(f"\nGN22 β1={β1}, β2={β2}: tip errors {np.array(tip_errors)} -> orders {tip_orders}; "
         f"energy-norm errors {np.array(energy_errors)} -> orders {energy_orders}")
    # ±0.2 around the theoretical order: the next term of the error expansion changes the
    # observed order by O(ω1Δt) ≈ 0.04-0.08 here (measured: 1.994/1.998 and 0.94/0.97 at the
    # tip for β1 = ½ and 0.6); an integrator of the wrong order misses by ≥ 0.8.
    assert np.all(np.abs(tip_orders - order) <= 0.2), tip_orders
    assert np.all(np.abs(energy_orders - order) <= 0.2), energy_orders


def _energy_history(osc: Oscillator, parameters: GN22Parameters, dt: float,
                    steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Energies E_n and Ê_n of a run from u0 = 0, v0 = Σ φ_k (every mode, unit velocity).

    Ê = E + ¼(β2 − β1)Δt² a·M a is the energy of Newmark's identity (see
    :func:`test_unconditional_stability`).
    """
    v0 = osc.to_function(osc.Φ.sum(axis=1), fem.Function(osc.V))
    stepper = GN22(osc.model, dt, parameters)
    stepper.initialise(None, [v0, None])
    c = 0.25 * (parameters.beta2 - parameters.beta1) * dt**2
    E, Ê = [], []
    for n in range(steps + 1):
        if n > 0:
            stepper.step()
        E.append(osc.energy(stepper.u[0], stepper.v[0]))
        a = osc.from_function(stepper.a[0])
        Ê.append(E[-1] + c * float(a @ osc.M @ a))
    return np.array(E), np.array(Ê)


@pytest.mark.parametrize(("β1", "β2"), [(0.5, 0.5), (0.6, 0.605), (0.5, 0.75)])
def test_unconditional_stability(oscillator: Oscillator, β1: float, β2: float) -> None:
    """At Δt = 100 × the explicit limit 2/ω_max, the total energy never grows.

    Newmark's energy identity (Hughes, The Finite Element Method, 1987, §9.3.3, with
    γ = β1, β = β2/2) for M a + K u = 0: Ê = E + ¼(β2 − β1)Δt² a·M a, where
    E = ½ v·Mv + ½ u·Ku, satisfies Ê_{n+1} − Ê_n = −(β1 − ½)(…) ≤ 0 for β2 ≥ β1 ≥ ½,
    with equality for β1 = ½. Starting from a0 = 0 (u0 = 0, no load), Ê_0 = E_0, hence
    E_n ≤ Ê_n ≤ E_0 at any Δt.
    """
    osc = oscillator
    dt = 100.0 * 2.0 / osc.ω[-1]
    steps = 100
    E, Ê = _energy_history(osc, GN22Parameters(β1, β2), dt, steps)
    growth = float(np.max(E[1:] / E[0] - 1.0))
    Ê_step = float(np.max(np.diff(Ê)) / E[0])
    _say(f"\nstability β1={β1}, β2={β2}: Δt ω_max = {dt * osc.ω[-1]:.0f}, {steps} steps, "
         f"max(E_n/E_0 − 1) = {growth:.2e}, max(Ê_n+1 − Ê_n)/E_0 = {Ê_step:.2e}, "
         f"|Ê_0/E_0 − 1| = {abs(Ê[0] / E[0] - 1):.1e}, E_end/E_0 = {E[-1] / E[0]:.3e}, "
         f"Ê_end/E_0 = {Ê[-1] / E[0]:.3e}")
    # Round-off allowance 1e-9 of E_0: each step solves a linear system of condition
    # ~(ω_max/ω1)² ≈ 4e5 (error ~1e-11 relative; measured drift ≤ 2e-11 over 200 steps for
    # β1 = β2 = ½), while an unstable scheme grows by orders of magnitude per step (see
    # the control test).
    assert abs(Ê[0] / E[0] - 1.0) <= 1e-12  # a0 = 0
    assert growth <= 1e-9
    assert Ê_step <= 1e-9
    if β1 == 0.5:
        assert np.all(np.abs(Ê / E[0] - 1.0) <= 1e-9)  # conserved (no numerical damping)
    else:
        assert Ê[-1] < 0.5 * E[0]  # numerical damping of the modes with ωΔt ≫ 1


def test_conditional_scheme_blows_up(oscillator: Oscillator) -> None:
    """Control: β2 < β1 (allowed only with allow_conditional) is unstable at this Δt.

    Newmark with γ = ½, β = 0.05 is stable only for ωΔt ≤ 1/sqrt(γ/2 − β) ≈ 2.2; here
    ω_max Δt = 200, so the energy check of the stability test must catch it.
    """
    osc = oscillator
    dt = 100.0 * 2.0 / osc.ω[-1]
    E, _ = _energy_history(osc, GN22Parameters(0.5, 0.1, allow_conditional=True), dt, 10)
    _say(f"\ncontrol β1=0.5, β2=0.1: E_10/E_0 = {E[-1] / E[0]:.2e}")
    assert E[-1] > 1e6 * E[0]


def test_single_body_model_steps(oscillator: Oscillator) -> None:
    """A model with one body (a one-block system) solves statically and steps."""
    data = oscillator.model.mesh_data
    model = ContactModel(data, [Body("a", MATERIAL)], fixed=[Fixed("a_left")],
                         gravity=(0.0, -9.81))
    u, its = solve_static(model)
    assert its >= 1 and COMM.allreduce(u[0].x.array.min(), op=MPI.MIN) < 0  # sags
    stepper = GN22(model, 1e-3)
    stepper.initialise()  # from rest and undeformed: a0 = g, then it falls
    assert stepper.step() >= 1
    assert COMM.allreduce(stepper.u[0].x.array[1::2].min(), op=MPI.MIN) < 0


def test_kinematics_written_once(oscillator: Oscillator) -> None:
    """The residual's UFL u₁, v₁, a₁ and the accepted state come from gn22_kinematics.

    On random states: the UFL expressions of the stepper equal the function on arrays
    to 1e-14 of their L2 norm (round-off of the compiled form), and ``update`` keeps
    the operation order u₀ + (Δt v₀ + ½Δt² a₀ + ½β₂Δt² Δa) bit for bit (checkpoints
    resume bit for bit).
    """
    model = oscillator.model
    p = GN22Parameters(0.6, 0.7)
    dt = 1e-2
    stepper = GN22(model, dt, p)
    rng = np.random.default_rng(1 + COMM.rank)
    for f in (*stepper.u, *stepper.v, *stepper.a, *stepper.da):
        f.x.array[:] = rng.standard_normal(f.x.array.size)
        f.x.scatter_forward()
    arrays = [[f.x.array.copy() for f in fs]
              for fs in (stepper.u, stepper.v, stepper.a, stepper.da)]
    expected = [gn22_kinematics(u, v, a, d, dt, p.beta1, p.beta2)
                for u, v, a, d in zip(*arrays, strict=True)]
    for k, ufl_values in enumerate((stepper.u1, stepper.v1, stepper.a1)):
        for i, body in enumerate(model.bodies):
            ref = fem.Function(body.V)
            ref.x.array[:] = expected[i][k]
            err = model.assemble(model.form(ufl.dot(ufl_values[i] - ref, ufl_values[i] - ref)
                                            * body.dx))
            norm = model.assemble(model.form(ufl.dot(ref, ref) * body.dx))
            assert norm > 0 and math.sqrt(err) <= 1e-14 * math.sqrt(norm)
    stepper.update()
    for i, (u, v, a, d) in enumerate(zip(*arrays, strict=True)):
        assert np.array_equal(stepper.u[i].x.array,
                              u + (dt * v + 0.5 * dt**2 * a + 0.5 * p.beta2 * dt**2 * d))
        assert np.array_equal(stepper.v[i].x.array, v + (dt * a + p.beta1 * dt * d))
        assert np.array_equal(stepper.a[i].x.array, a + d)
    assert float(stepper.t.value) == dt
    stepper.destroy()


def test_compiled_update_is_the_kinematics() -> None:
    # GN22.update's compiled in-place pass gives gn22_kinematics' numbers bit for bit
    # (the same operations in the same order), on values of mixed scales and signs.
    rng = np.random.default_rng(4)
    u, v, a, Δa = (s * rng.standard_normal(1000) for s in (1e-3, 1e-1, 1e2, 1e3))
    Δt, β1, β2 = 1.3e-4, 0.55, 0.605
    expected = gn22_kinematics(u, v, a, Δa, Δt, β1, β2)
    gn22_update(u, v, a, Δa, Δt, β1, β2)
    for got, want in zip((u, v, a), expected, strict=True):
        assert np.array_equal(got, want)


def test_probe_a_hair_outside_its_body(shared_dir: pathlib.Path) -> None:
    # A point typed to 7-10 digits on an interface lies 1e-11 to 1e-8 m off it, inside
    # the other body: it is taken in the nearest cell of its own body when within
    # pointprobe.TOUCH (1e-5) of that cell's size (here 2e-7 of h = 0.05), and a linear
    # field's value there is its value at the point (1e-12: round-off); a point 1 mm
    # off (2e-2 of h) is refused.
    from breakwater.common.errors import MeshError

    path = two_rectangles(shared_dir / "probe.msh", COMM, (0.2, 0.1), (0.4, 0.1), 0.05)
    mat = Material(2000.0, 0.25, young_modulus=1e9)
    model = ContactModel(read_mesh(path, COMM), [Body("a", mat), Body("b", mat)], [],
                         [Fixed("b_bottom")], [], gravity=(0.0, 0.0))
    field = fem.Function(model.body("b").V)
    field.interpolate(lambda x: x[:2])
    point = (0.0123, 0.1 + 1e-8)
    value = PointProbe(model, "b", point).value(field)
    assert np.allclose(value, point, rtol=0, atol=1e-12)
    with pytest.raises(MeshError, match=r"is not in body 'b'$"):
        PointProbe(model, "b", (0.0123, 0.101))
