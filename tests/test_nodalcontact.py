"""The fast solver's nodal contact forces against the assembled UFL contact forms.

:class:`breakwater.contact.nodal.NodalContactForces` evaluates the contact law on the
interface nodes, which are the points of the interface forms' Gauss–Lobatto quadrature
on P2 facets, with the law's nodal derivatives, in compiled kernels
(:mod:`breakwater.contact.nodalkernels`). Its f_c and ∂f_c/∂y must be those of the UFL
forms assembled by dolfinx (:class:`breakwater.stepping.condensed.InterfaceAssembler`) to
round-off: the quadrature is the same and the basis functions are Kronecker deltas at
its points up to basix's points (1e-16 off the facet's ends). Checked at random states
with open and closed nodes, slipping and sticking nodes (|v_T| near χ), on the Goda
case and on the three stacked blocks (two pairs, a body in both), serially and on 2
ranks. Tolerance: 1e-12 of each array's largest entry (the sums run over a few terms
of both signs; measured 1e-15).
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
import ufl
from blocks import THREE_HEIGHTS, THREE_WIDTH, stacked_blocks, three_blocks
from mpi4py import MPI

import breakwater.stepping.gn22 as gn22_module
from breakwater.casefile.case import load_case
from breakwater.contact.coupling import COUPLING, BulkStiffness
from breakwater.contact.nodal import NodalContactForces, nodal_contact_applies
from breakwater.contact.nodalkernels import nodal_state, normal_forces
from breakwater.stepping.condensed import InterfaceAssembler
from breakwater.stepping.gn22 import GN22
from breakwater.stepping.interface import BodyGuard

COMM = MPI.COMM_WORLD


def _random_state(stepper: GN22, seed: int) -> None:
    """u of ±1e-6 m (the penalty gaps of both signs), v, a around χ and larger."""
    rng = np.random.default_rng(seed + COMM.rank)
    for fns, scale in ((stepper.u, 1e-6), (stepper.v, 1e-9), (stepper.a, 1e-6),
                       (stepper.da, 1e-4)):
        for f in fns:
            f.x.array[:] = scale * rng.standard_normal(len(f.x.array))
            f.x.scatter_forward()


def _compare(stepper: GN22) -> None:
    solver = stepper.fast
    assert solver is not None
    providers = solver.providers
    assert providers and all(isinstance(p, NodalContactForces) for p in providers)
    forms = InterfaceAssembler(stepper.model, solver.layout, ufl.extract_blocks(
        stepper.model.interface_residual(stepper.u1, stepper.v1)), stepper.da,
        solver.interface.positions, solver.I)
    for seed in range(3):
        _random_state(stepper, seed)
        # The providers read the state at begin() and take the iterate y = Δa_I.
        y = _interface_values(stepper)
        f = np.zeros(solver.n)
        for p in providers:
            p.begin()
            p.add_vector(y, f)
        J = sum(p.matrix(y) for p in providers)
        f_ref, J_ref = forms.vector(), forms.matrix()
        assert np.abs(f_ref).max() > 0 and np.abs(J_ref).max() > 0
        np.testing.assert_allclose(f, f_ref, rtol=0, atol=1e-12 * np.abs(f_ref).max())
        np.testing.assert_allclose(J, J_ref, rtol=0, atol=1e-12 * np.abs(J_ref).max())


def _interface_values(stepper: GN22) -> np.ndarray:
    """Δa at the interface unknowns, the same on every rank."""
    solver = stepper.fast
    assert solver is not None
    owned = np.concatenate([f.x.array[:n] for f, n in zip(stepper.da, solver.layout.sizes,
                                                          strict=True)])
    return solver.interface.gather(owned)[0]


def test_goda_nodal_equals_forms() -> None:
    model, *_ = load_case(None, ["mesh.refinement=0.7"]).build(COMM)
    assert nodal_contact_applies(model)
    stepper = GN22(model, 1e-4)
    try:
        _compare(stepper)
    finally:
        stepper.destroy()


def test_blocks_nodal_equals_forms(folder: pathlib.Path) -> None:
    path = stacked_blocks(folder / "three.msh", COMM, THREE_WIDTH, THREE_HEIGHTS, h=0.05)
    model = three_blocks(path, COMM, young_modulus=1e11, penalty=1e13)
    stepper = GN22(model, 1e-4)
    try:
        _compare(stepper)
    finally:
        stepper.destroy()


def test_left_product_is_the_dense_product() -> None:
    # X ∂f_c from the matrix's node structure equals the dense product (a random X).
    model, *_ = load_case(None, ["mesh.refinement=0.7"]).build(COMM)
    stepper = GN22(model, 1e-4)
    try:
        _random_state(stepper, 5)
        provider = stepper.solver.providers[0]
        n = provider.n
        provider.begin()
        y = _interface_values(stepper)
        X = np.random.default_rng(7).standard_normal((n + 3, n))
        expected = X @ provider.matrix(y)
        product = np.zeros_like(X)
        assert provider.add_left_product(y, X, product)
        np.testing.assert_allclose(product, expected, rtol=0,
                                   atol=1e-12 * np.abs(expected).max())
    finally:
        stepper.destroy()


def test_active_and_jump_jacobians_are_the_matrix_on_the_closed_nodes() -> None:
    # (act, A): the dense ∂f_c/∂y is A on act × act and zero elsewhere; act holds the
    # unknowns of the closed nodes only (the random state opens some: gaps of both signs).
    # (W, slave, master): ∂f_c/∂y = −Dᵀ W D, D the nodes' jumps (−1 on the slave
    # unknown, +1 on the master's; a Dirichlet side, −1, none), to round-off (each entry
    # one ± W term, as tangent_block scatters it).
    model, *_ = load_case(None, ["mesh.refinement=0.7"]).build(COMM)
    stepper = GN22(model, 1e-4)
    try:
        _random_state(stepper, 5)
        provider = stepper.solver.providers[0]
        provider.begin()
        y = _interface_values(stepper)
        act, A = provider.active_jacobian(y)
        dense = provider.matrix(y)
        inside = np.zeros_like(dense)
        inside[np.ix_(act, act)] = A
        # Exact: the same tangents W scattered, each entry one sum of ± W terms.
        np.testing.assert_allclose(inside, dense, rtol=0, atol=1e-14 * np.abs(dense).max())
        coupled = np.flatnonzero((dense != 0).any(axis=0) | (dense != 0).any(axis=1))
        np.testing.assert_array_equal(act, coupled)
        assert 0 < len(act) < provider.n
        W, slave, master = provider.jump_jacobian(y)
        n, gdim = provider.n, W.shape[1]
        D = np.zeros((len(W) * gdim, n))
        for r in range(len(W)):
            for i in range(gdim):
                for side, sign in ((slave, -1.0), (master, 1.0)):
                    if side[r, i] >= 0:
                        D[r * gdim + i, side[r, i]] = sign
        blocks = np.zeros((len(D), len(D)))
        for r in range(len(W)):
            blocks[r * gdim:(r + 1) * gdim, r * gdim:(r + 1) * gdim] = W[r]
        np.testing.assert_allclose(-D.T @ blocks @ D, dense, rtol=0,
                                   atol=1e-14 * np.abs(dense).max())
    finally:
        stepper.destroy()


def test_compiled_guard_equals_slip_guard() -> None:
    # The nodal providers' compiled slip guard cuts the same steps as SlipGuard on body
    # arrays (the assembled path's guard), at random velocities of both signs well
    # outside the band χ and steps that reverse about half of them.
    model, *_ = load_case(None, ["mesh.refinement=0.7"]).build(COMM)
    stepper = GN22(model, 1e-4)
    try:
        solver = stepper.fast
        assert solver is not None and solver.guard is not None
        rng = np.random.default_rng(11)  # the same on every rank: interface arrays
        n, dv_dx = solver.n, solver.beta1 * float(solver.dt.value)
        body_guard = BodyGuard(solver.guard, solver.interface, solver.layout, stepper.da)
        for p in solver.providers:
            p.begin()  # the law's χ for where the guard acts
        for trial in range(3):
            x = 1e-2 * rng.standard_normal(n)
            v_pred = 1e-6 * rng.standard_normal(n)
            step = 3e-2 * rng.standard_normal(n)
            expected = step.copy()
            cut_ref = body_guard(x, expected, v_pred, dv_dx)
            got = step.copy()
            cut = sum(p.precheck(x, got, v_pred, dv_dx) for p in solver.providers)
            assert cut == cut_ref > 0, trial
            assert not np.array_equal(got, step)
            np.testing.assert_allclose(got, expected, rtol=0,
                                       atol=1e-12 * np.abs(expected).max())
            # Where it acts (breakwater.contact.coupling): with a bulk of S = 0 at every
            # node, as without one; with S = 1e30 I (the bulk holds every slip) at none.
            acting = step.copy()
            cut_all = sum(p.precheck(x, acting, v_pred, dv_dx, BulkStiffness(np.zeros((n, n))))
                          for p in solver.providers)
            assert cut_all == cut
            np.testing.assert_array_equal(acting, got)
            held = step.copy()
            assert sum(p.precheck(x, held, v_pred, dv_dx, BulkStiffness(1e30 * np.eye(n)))
                       for p in solver.providers) == 0
            np.testing.assert_array_equal(held, step)
    finally:
        stepper.destroy()


def test_guard_reads_the_nodes_normal_forces() -> None:
    # The nodal guard's normal forces λ_k (nodalkernels.normal_forces, where the guard
    # acts: breakwater.contact.coupling) are f_c's: the Goda crest is flat, every
    # point's normal ±ŷ, and the friction is tangential, so λ_k = |f_c,y| at the slave
    # node's y unknown; to round-off (1e-12 of the largest). At random iterates about
    # half the nodes are closed; the guard's switch follows λ against S_yy (S = s I): it
    # acts where μλβ₁Δt/χ ≥ 0.1 s.
    model, *_ = load_case(None, ["mesh.refinement=0.7"]).build(COMM)
    stepper = GN22(model, 1e-4)
    try:
        solver = stepper.fast
        assert solver is not None
        (p,) = [q for q in solver.providers if isinstance(q, NodalContactForces)]
        p.begin()
        assert np.allclose(np.abs(p._normal[:, 1]), 1.0)
        rng = np.random.default_rng(5)
        y = 1e-1 * rng.standard_normal(p.n)
        fc = np.zeros(p.n)
        p.add_vector(y, fc)
        lam = np.empty(p.nodes.size)
        ε_n, g0, μ, χ2 = p._law
        nodal_state(y, p._pos, p._base, *p._coefficients, p._U, p._V)
        normal_forces(p._U, p._node, p._weight, p._normal, ε_n, g0, lam)
        ys = p._pos[0, :, 1]
        assert (ys >= 0).all() and 0 < (lam > 0).sum() < len(lam)
        np.testing.assert_allclose(lam, np.abs(fc[ys]), rtol=0, atol=1e-12 * lam.max())
        stick = μ * p._coefficients[1] / np.sqrt(χ2)
        s = np.median(stick * lam[lam > 0]) / COUPLING
        acts = p._guarded(y, BulkStiffness(s * np.eye(p.n)))
        np.testing.assert_array_equal(acts, stick * lam >= COUPLING * s)
        assert 0 < acts.sum() < len(acts)
    finally:
        stepper.destroy()


def test_assembled_provider_steps_as_the_nodal_one(monkeypatch: pytest.MonkeyPatch) -> None:
    # The fast path off the nodal kernels (UFL forms assembled over the contact facets,
    # the body-array slip guard: 3D or P1 models) takes the nodal path's steps: the
    # Goda case from rest under gravity and the pendulum's pulse, 30 steps of 1e-4 s.
    # Tolerance 1e-9 of the displacement's largest entry (measured 3e-11, the same
    # iterations step by step): the two differ by the
    # round-off of their sums, which the χ = 1e-10 stick tangent magnifies (as the
    # 2-rank runs' 1e-10 against serial, tests/test_mpi.py) and Newton's tolerance.
    def run(nodal: bool) -> tuple[list[int], np.ndarray]:
        monkeypatch.setattr(gn22_module, "nodal_contact_applies", lambda model: nodal)
        model, *_ = load_case(None, ["mesh.refinement=0.7"]).build(COMM)
        stepper = GN22(model, 1e-4)
        try:
            solver = stepper.fast
            assert solver is not None
            kinds = {type(p).__name__ for p in solver.providers}
            assert kinds == ({"NodalContactForces"} if nodal else {"StateForces"})
            stepper.initialise()
            its = [stepper.step() for _ in range(30)]
            return its, np.concatenate([f.x.array for f in stepper.u])
        finally:
            stepper.destroy()

    its_nodal, u_nodal = run(True)
    its_forms, u_forms = run(False)
    assert abs(sum(its_nodal) - sum(its_forms)) <= 2, (its_nodal, its_forms)
    np.testing.assert_allclose(u_forms, u_nodal, rtol=0, atol=1e-9 * np.abs(u_nodal).max())
