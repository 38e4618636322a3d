"""The fast GN22 solver (``time.solver = "fast"``) against the reference Newton.

The fast path (:mod:`breakwater.stepping.condensed`) factorises A = M + β₁Δt C + ½β₂Δt² K once
per Δt and runs Newton on the contact-surface unknowns of the interface Schur
complement; the reference path runs Newton on the whole residual. Both solve the same
equations to the same tolerances, so their histories agree to the Newton tolerance
(1e-9 of the load norm): the issue asks for 1e-8 relative on the kinematics. Checked
on the Goda case through the impact and on three stacked blocks with two frictional
pairs (one sliding), serially and on 2 ranks; plus the Schur complement itself against
a dense elimination, and a model without contact (a linear step).
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
import ufl
from blocks import THREE_HEIGHTS, THREE_WIDTH, stacked_blocks, three_blocks, two_rectangles
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from breakwater.casefile.case import CaseError, load_case
from breakwater.common.files import read_history
from breakwater.config.runspec import OutputSpec, PairProbeSpec, TimeSpec
from breakwater.energy.ledger import FIELDS
from breakwater.model.layout import MonolithicLayout
from breakwater.model.mesh import read_mesh
from breakwater.model.model import (
    Body,
    ContactModel,
    ContactPair,
    Damping,
    Fixed,
    Material,
)
from breakwater.run import simulation
from breakwater.stepping import elimination
from breakwater.stepping.bulk import BulkOperators, interface_dofs, predictor_vectors
from breakwater.stepping.elimination import x_blocks
from breakwater.stepping.factorisations import Factorisation, Factorisations
from breakwater.stepping.gn22 import GN22, solve_static

COMM = MPI.COMM_WORLD
KINEMATICS = ("_ux", "_uy", "_slip", "_opening")
RTOL = 1e-8  # relative to the displacements' scale


def _same_kinematics(a: pathlib.Path, b: pathlib.Path) -> list[str]:
    """The kinematic columns compared (every one agrees to RTOL of its scale).

    The scale of a displacement column is its largest |value|; that of a slip or an
    opening (a difference of the two sides' displacements, 1e-10 m where a stiff penalty
    holds the interface closed) is the largest displacement of the two sides there.
    """
    ha, hb = read_history(a / "history.csv"), read_history(b / "history.csv")
    np.testing.assert_array_equal(ha["t"], hb["t"])
    compared = []
    for name in ha:
        if name.endswith(KINEMATICS):
            probe, kind = name.rsplit("_", 1)
            sides = [f"{probe}_{side}_u{c}" for side in ("slave", "master") for c in "xy"] \
                if kind in ("slip", "opening") else [name]
            scale = max(np.abs(hb[c]).max() for c in sides)
            assert scale > 0, name
            np.testing.assert_allclose(ha[name], hb[name], rtol=0, atol=RTOL * scale,
                                       err_msg=name)
            compared.append(name)
    return compared


def _same_forces(a: pathlib.Path, b: pathlib.Path) -> None:
    """The interface resultants agree too: 1e-7 of each column's scale.

    The tangential resultant is the friction law evaluated at the step's slip
    velocities, which in stick are of order χ = 1e-10 m/s: it is as sensitive as the
    law's stick tangent μp/χ makes it (measured 2.4e-8 on the Goda run, 5e-10 on the
    blocks).
    """
    ha, hb = read_history(a / "history.csv"), read_history(b / "history.csv")
    compared = [name for name in ha if name.endswith(("_normal_force", "_tangential_force"))]
    assert compared, list(ha)  # the runs' conforming pairs: <name>_normal_force, ...
    for name in compared:
        np.testing.assert_allclose(ha[name], hb[name], rtol=0,
                                   atol=1e-7 * np.abs(hb[name]).max(), err_msg=name)


def _same_ledger(a: pathlib.Path, b: pathlib.Path) -> None:
    """The energy ledgers agree to 1e-7 of the largest ledger entry, and both close.

    The numerical dissipation reads the solved step (Δa, the contact state), so it is as
    sensitive as the resultants (see :func:`_same_forces`); both balances close to the
    Newton tolerance (1e-8 of the external work, see test_numerical_dissipation.py).
    """
    ha, hb = read_history(a / "history.csv"), read_history(b / "history.csv")
    scale = max(np.abs(hb[k]).max() for k in FIELDS)
    for name in FIELDS:
        np.testing.assert_allclose(ha[name], hb[name], rtol=0, atol=1e-7 * scale,
                                   err_msg=name)
    for h in (ha, hb):
        assert np.abs(h["balance_error"]).max() < 1e-8 * h["external_work"][-1]
    assert abs(hb["numerical_dissipation"][-1]) > 1e-3 * scale  # compared where nonzero


def test_goda_fast_equals_reference(shared_dir: pathlib.Path) -> None:
    # 60 steps of 0.1 ms on a coarse mesh: the 2 ms pendulum pulse, the front corner
    # lifting and the interface sliding (the flip guard acts), frictional contact at
    # the paper's χ = 1e-10.
    summaries = {}
    for solver in ("fast", "reference"):
        case = load_case(None, ["mesh.refinement=0.7", "time.end_time=0.006",
                                f"time.solver={solver}", "output.figures=false",
                                "output.field_interval=0", "output.checkpoint_interval=0",
                                f"output.directory={(shared_dir / solver).as_posix()}"])
        built = case.build(COMM)
        model, spec, output, extra = built
        summaries[solver] = simulation.run(model, spec, output, extra_summary=extra,
                                           report=False)
    fast, ref = summaries["fast"], summaries["reference"]
    assert fast["solver"]["kind"] == "fast" and ref["solver"]["kind"] == "reference"
    # How the fast solver eliminated the bulk (this small mesh: X kept).
    assert fast["solver"]["elimination"]["X"] in ("kept", "second back-solve")
    assert 0 < fast["solver"]["elimination"]["memory_gb"] < 1
    assert "elimination" not in ref["solver"]
    assert fast["solver"]["newton_rescues"] == 0  # every solve converged at its first try
    compared = _same_kinematics(shared_dir / "fast", shared_dir / "reference")
    assert {"gauge_top_ux", "corner_front_slip", "corner_front_opening"} <= set(compared)
    _same_forces(shared_dir / "fast", shared_dir / "reference")
    _same_ledger(shared_dir / "fast", shared_dir / "reference")
    # The fast path's split of the time loop is recorded.
    loop = fast["solver"]["time_loop"]
    assert {"wall", "outputs", "factorisation", "back_solves", "interface_assembly"} <= \
        set(loop)
    assert loop["factorisation"] > 0 and loop["wall"] >= loop["back_solves"]


def test_blocks_fast_equals_reference(folder: pathlib.Path, shared_dir: pathlib.Path) -> None:
    # The three blocks of test_bodies.py, with Rayleigh damping: two pairs, the top
    # block sliding on joint1 under a pulse of 1.5 μ₁ W₂, joint0 sticking.
    path = stacked_blocks(folder / "three.msh", COMM, THREE_WIDTH, THREE_HEIGHTS, h=0.05)
    histories = {}
    for solver in ("fast", "reference"):
        model = three_blocks(path, COMM, young_modulus=1e11, penalty=1e13)
        y0, y1 = THREE_HEIGHTS[0], THREE_HEIGHTS[0] + THREE_HEIGHTS[1]
        output = OutputSpec(shared_dir / solver, field_interval=0, figures=False,
                            progress=False,
                            pair_probes=(PairProbeSpec("corner0", 0, (-THREE_WIDTH / 2, y0)),
                                         PairProbeSpec("corner1", 1, (-THREE_WIDTH / 2, y1))))
        summary = simulation.run(model, TimeSpec(dt=1e-4, end_time=6e-3, solver=solver),
                                 output, report=False)
        assert summary["finished"]
        histories[solver] = summary
    assert histories["fast"]["solver"]["slip_guard_corrections"] > 0  # the slip guard acted
    compared = _same_kinematics(shared_dir / "fast", shared_dir / "reference")
    assert {"corner0_slip", "corner1_slip", "corner1_opening"} <= set(compared)
    _same_forces(shared_dir / "fast", shared_dir / "reference")
    _same_ledger(shared_dir / "fast", shared_dir / "reference")
    h = read_history(shared_dir / "fast" / "history.csv")
    assert abs(h["corner1_slip"][-1] - h["corner1_slip"][0]) > 1e-6  # it slid


def _two_blocks(path: pathlib.Path, friction: float | None,
                fixed: tuple[str, ...] = ("b_bottom",), damping: Damping | None = None
                ) -> ContactModel:
    """Block ``a`` on block ``b`` under gravity; in frictional contact unless None."""
    pairs = [] if friction is None else [ContactPair("interface", "a", "b", 1e10,
                                                     friction=friction)]
    return ContactModel(read_mesh(path, COMM),
                        [Body("a", Material(2000.0, 0.25, young_modulus=1e8)),
                         Body("b", Material(1800.0, 0.3, young_modulus=5e7))],
                        pairs, [Fixed(group) for group in fixed], gravity=(0.0, -9.81),
                        damping=damping)


@pytest.mark.parametrize("package", ["default", "mumps"])
def test_schur_complement_and_linear_step(folder: pathlib.Path, package: str,
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    # S = (X_II)⁻¹ with X = A⁻¹ E is the Schur complement A_II − A_IB A_BB⁻¹ A_BI of
    # A: checked against a dense elimination of A (assembled by dolfinx, gathered).
    # With the default LU package (PETSc's own on one rank in 2D, lu_package; MUMPS
    # under MPI) and with MUMPS asked for by the PETSc option a user would give.
    path = two_rectangles(folder / "two.msh", COMM, (0.2, 0.1), (0.3, 0.1), h=0.05)
    model = _two_blocks(path, 0.5, damping=Damping(alpha=2.0, beta=1e-4))
    layout = MonolithicLayout(model)
    interface = interface_dofs(model, layout)
    dt, β1, β2 = 1e-3, 0.6, 0.605
    monkeypatch.setattr(model, "options_prefix", lambda name: f"fastpath_test_{name}_")
    bulk = BulkOperators(model, layout)
    factorisations = Factorisations(bulk, interface, β1, β2)
    option = "fastpath_test_bulk_pc_factor_mat_solver_type"
    options = PETSc.Options()
    if package == "mumps":
        options[option] = "mumps"
    try:
        fact = factorisations.factorisation(dt)
    finally:
        options.delValue(option)
    expected = "mumps" if package == "mumps" or COMM.size > 1 else "petsc"
    assert fact.ksp.getPC().getFactorSolverType() == expected
    # The whole A, dense, on every rank (the model is small).
    n = layout.vec.getSize()
    A = np.zeros((n, n))
    lo, hi = layout.vec.getOwnershipRange()
    rows = np.arange(lo, hi, dtype=np.int32)
    A[lo:hi] = fact.A.getValues(rows, np.arange(n, dtype=np.int32))
    COMM.Allreduce(MPI.IN_PLACE, A, op=MPI.SUM)
    # Against A assembled from the UFL bulk residual's derivative (the reference path's
    # operator): M + β₁Δt C + ½β₂Δt² K.
    trial = ufl.TrialFunctions(model.W)
    α, β = model.damping.alpha, model.damping.beta
    form = (1 + β1 * dt * α) * model.mass(trial) + (0.5 * β2 * dt**2 + β1 * dt * β) \
        * model.stiffness(trial)
    ref = fem_petsc.assemble_matrix(model.form(ufl.extract_blocks(form)), bcs=model.bcs,
                                    kind="mpi")
    ref.assemble()
    A_ref = np.zeros((n, n))
    A_ref[lo:hi] = ref.getValues(rows, np.arange(n, dtype=np.int32))
    COMM.Allreduce(MPI.IN_PLACE, A_ref, op=MPI.SUM)
    np.testing.assert_allclose(A, A_ref, rtol=0, atol=1e-12 * np.abs(A_ref).max())
    ref.destroy()
    B = np.setdiff1d(np.arange(n), interface)
    S = A[np.ix_(interface, interface)] - A[np.ix_(interface, B)] @ np.linalg.solve(
        A[np.ix_(B, B)], A[np.ix_(B, interface)])
    # MUMPS or PETSc's LU against numpy's dense LU: all backward stable, cond(A) ~ 1e6.
    np.testing.assert_allclose(fact.S, S, rtol=0, atol=1e-8 * np.abs(S).max())
    # X = A⁻¹ E is kept by block (by body, or one block): each against the dense X's
    # (owned rows), which is zero outside them.
    X = np.linalg.solve(A, np.eye(n)[:, interface])
    assert fact.X_blocks is not None  # the cost rule keeps X here
    _check_blocks(fact.X_blocks, X[lo:hi])
    # The step's Δa = z − X f_c from the blocks equals A⁻¹(r − E f_c), a second back-solve
    # (the other way of factorisations.keep_X), to round-off.
    rng = np.random.default_rng(7)
    fc = COMM.bcast(rng.standard_normal(len(interface)))
    r, z, e, da = (layout.vec.duplicate() for _ in range(4))
    r.array[:] = rng.standard_normal(hi - lo)
    factorisations.solve(fact, r, z)
    product = z.array.copy()
    fact.subtract_X(fc, product)
    e.array[:] = r.array
    mine = (interface >= lo) & (interface < hi)
    e.array[interface[mine] - lo] -= fc[mine]
    factorisations.solve(fact, e, da)
    scale = COMM.allreduce(np.abs(product).max(), op=MPI.MAX)
    assert COMM.allreduce(np.abs(product - da.array).max(), op=MPI.MAX) < 1e-12 * scale
    for v in (r, z, e, da):
        v.destroy()
    factorisations.destroy()
    bulk.destroy()

    # Without contact pairs a step is linear: the fast path is one back-solve and
    # gives the reference's state to round-off.
    linear = _two_blocks(path, None, fixed=("b_bottom", "a_top"))
    with pytest.raises(ValueError, match="solver must be one of fast, reference"):
        GN22(linear, dt, solver="slow")
    states = {}
    for solver in ("fast", "reference"):
        s = GN22(linear, dt, solver=solver)
        s.initialise()
        its = [s.step() for _ in range(5)]
        states[solver] = np.concatenate([f.x.array for f in s.u])
        if solver == "fast":
            assert its == [1] * 5
        s.destroy()
    scale = np.abs(states["reference"]).max()
    assert scale > 0
    np.testing.assert_allclose(states["fast"], states["reference"], rtol=0,
                               atol=1e-10 * scale)


def _check_blocks(blocks: list, X: np.ndarray) -> None:
    """X's blocks against X (owned rows, dense): they sum to it (overlapping at zeros)."""
    total = np.zeros(X.shape)
    for b in blocks:
        total[b.rows, b.cols[0]: b.cols[-1] + 1] += b.X
    np.testing.assert_allclose(total, X, rtol=0, atol=1e-8 * np.abs(X).max())
    assert not np.any(X[total == 0]), "X is nonzero outside its blocks"


def test_X_blocks_give_the_dense_product_bit_for_bit() -> None:
    # On the Goda case (serially: one block per body, each half of X's columns) the
    # blocks' product Δa = z − X f_c is the dense X's, bit for bit (the Newton counts
    # depend on its last bit); and on the blocks' rows X is zero outside them.
    case = load_case(None, ["mesh.refinement=1", "time.solver=fast"])
    model, spec, _, _ = case.build(COMM)
    layout = MonolithicLayout(model)
    bulk = BulkOperators(model, layout)
    interface = interface_dofs(model, layout)
    factorisations = Factorisations(bulk, interface, spec.beta1, spec.beta2)
    fact = factorisations.factorisation(spec.dt)
    assert fact.X_blocks is not None
    X = np.zeros((layout.offsets[-1], len(interface)), order="F")  # as MUMPS gives it
    for b in fact.X_blocks:
        X[b.rows, b.cols] += b.X
    if COMM.size == 1:
        assert len(fact.X_blocks) == 2
        assert all(len(b.cols) < 0.6 * len(interface) for b in fact.X_blocks)
    rng = np.random.default_rng(3)
    for _ in range(3):
        fc = COMM.bcast(rng.standard_normal(len(interface)))
        z = rng.standard_normal(layout.offsets[-1])
        da = z.copy()
        fact.subtract_X(fc, da)
        assert np.array_equal(da, z - X @ fc)
    factorisations.destroy()
    bulk.destroy()


def test_x_blocks_by_body_or_whole() -> None:
    # Two bodies' blocks (rows 0–49 meet columns 0–9, rows 50–119 columns 10–19): kept
    # by body, each product bit for bit the whole X's; a nonzero outside the blocks (A
    # coupling the bodies) keeps X whole.
    rng = np.random.default_rng(5)
    X = np.zeros((120, 20), order="F")
    X[:50, :10] = rng.standard_normal((50, 10))
    X[50:, 10:] = rng.standard_normal((70, 10))
    offsets, body = np.array([0, 50, 120]), np.repeat([0, 1], 10)
    blocks = x_blocks(X, offsets, body)
    assert len(blocks) == 2 and all(len(b.cols) < 20 for b in blocks)
    _check_blocks(blocks, X)
    fc, z = rng.standard_normal(20), rng.standard_normal(120)
    fact = Factorisation(None, None, blocks, np.zeros((20, 20)), np.zeros((20, 20)))  # type: ignore[arg-type]
    da = z.copy()
    fact.subtract_X(fc, da)
    assert np.array_equal(da, z - X @ fc)
    X[60, 3] = 1.0
    (whole,) = x_blocks(X, offsets, body)
    assert whole.rows == slice(0, 120) and len(whole.cols) == 20 and whole.X is X


def test_x_blocks_all_rows_window_leaves_X(monkeypatch: pytest.MonkeyPatch) -> None:
    # When no aligned window keeps the product's bits, a body's block is the window of
    # all rows and columns, with the neighbour's rows zeroed: in the block's own copy.
    # (It once zeroed X itself, through np.asfortranarray's view: X_II became zero and
    # singular, "LinAlgError: Singular matrix", on a Goda mesh written by hand whose
    # blocks needed the wide window.)
    monkeypatch.setattr(elimination, "ALIGNMENTS", ())
    rng = np.random.default_rng(6)
    X = np.zeros((120, 20), order="F")
    X[:50, :10] = rng.standard_normal((50, 10))
    X[50:, 10:] = rng.standard_normal((70, 10))
    before = X.copy()
    offsets, body = np.array([0, 50, 120]), np.repeat([0, 1], 10)
    blocks = x_blocks(X, offsets, body)
    assert np.array_equal(X, before)
    assert len(blocks) == 2 and all(b.rows == slice(0, 120) for b in blocks)
    _check_blocks(blocks, X)
    fc, z = rng.standard_normal(20), rng.standard_normal(120)
    fact = Factorisation(None, None, blocks, np.zeros((20, 20)), np.zeros((20, 20)))  # type: ignore[arg-type]
    da = z.copy()
    fact.subtract_X(fc, da)
    assert np.allclose(da, z - X @ fc, rtol=0, atol=1e-13)


def test_second_back_solve_equals_product_with_X(folder: pathlib.Path) -> None:
    # Δa = z − X f_c (X kept by body) and Δa = A⁻¹(r₀ − E f_c) (X not kept, a second
    # back-solve: Factorisations.keep_X on fine meshes) give the same frictional steps:
    # to round-off in the first, then to the Newton tolerance (the two round-offs make
    # Newton stop at iterates a tolerance apart). Measured over 8 steps (u, v, a, each
    # relative to its scale): 1.7e-9, 5.6e-9, 7.7e-9 serially (the same run twice: 0);
    # on 2 ranks 6e-10, 5e-9, 1.2e-8, and the same run twice differs as much (1e-9,
    # 2e-8, 1e-8) with a Newton count one apart (tests/test_mpi.py). Bounds: RTOL on u,
    # 1e-7 on v and a, counts within one. From rest, gravity sets the block on the base.
    path = two_rectangles(folder / "keep.msh", COMM, (0.2, 0.1), (0.3, 0.1), h=0.05)
    states = {}
    for keep in (True, False):
        model = _two_blocks(path, 0.5, damping=Damping(alpha=2.0, beta=1e-4))
        s = GN22(model, 1e-3)
        assert s.fast is not None
        s.fast.factorisations._keep_X = keep
        s.initialise()
        its = [s.step() for _ in range(8)]
        assert (s.fast.factorisations.factorisation(1e-3).X_blocks is not None) == keep
        states[keep] = (its, [np.concatenate([f.x.array for f in x]) for x in (s.u, s.v, s.a)])
        s.destroy()
    its_kept, its_solved = np.array(states[True][0]), np.array(states[False][0])
    assert np.all(np.abs(its_kept - its_solved) <= 1) and its_kept.sum() > 8
    for kept, solved, rtol in zip(states[True][1], states[False][1], (RTOL, 1e-7, 1e-7),
                                  strict=True):
        scale = COMM.allreduce(np.abs(kept).max(), op=MPI.MAX)
        assert scale > 0
        np.testing.assert_allclose(solved, kept, rtol=0, atol=rtol * scale)


def test_unknown_solver_is_refused() -> None:
    with pytest.raises(CaseError, match=r"time\.solver: must be one of"):
        load_case(None, ["time.solver=slow"])


def test_static_then_fast_step_is_at_rest(folder: pathlib.Path) -> None:
    # From the static equilibrium the first fast step stays at rest (no load change):
    # the condensed residual vanishes at Newton's start.
    path = two_rectangles(folder / "rest.msh", COMM, (0.2, 0.1), (0.3, 0.1), h=0.05)
    model = _two_blocks(path, 0.5)
    u0, _ = solve_static(model)
    s = GN22(model, 1e-3)
    s.initialise(u0)
    s.step()
    moved = max(np.abs(f.x.array - g.x.array).max() for f, g in zip(s.u, u0, strict=True))
    scale = max(np.abs(g.x.array).max() for g in u0)
    assert COMM.allreduce(moved, op=MPI.MAX) < 1e-6 * COMM.allreduce(scale, op=MPI.MAX)
    s.destroy()


def test_predictor_vectors_are_numpys_to_the_bit() -> None:
    # The predictor's vectors (a compiled loop) are the NumPy expressions they replace,
    # bit for bit: the step's state, and the serial-vs-MPI and resume tests, rest on it.
    rng = np.random.default_rng(3)
    u, v, a = (rng.standard_normal(1001) * s for s in (1e-3, 1e-1, 1e2))
    dt, α, β = 0.0123, 0.3, 1e-4
    ṽ = v + dt * a
    ma, ku = np.empty(1001), np.empty(1001)
    predictor_vectors(u, v, a, dt, α, β, ma, ku)
    assert np.array_equal(ma, a + α * ṽ)
    assert np.array_equal(ku, u + dt * v + 0.5 * dt**2 * a + β * ṽ)


def test_state_products_and_their_uses(folder: pathlib.Path) -> None:
    # One rank: P = [Mv, Ma, Ku, Kv, Ka] of the state in one compiled pass
    # (stepping.stateproducts), formed once per state, and the predictor's residual and
    # Newton's start residual A Δa − r₀ from it equal PETSc's products of the combined
    # vectors to round-off: each row within 40 ε Σ_j |A_ij||x_j| (40 ≥ the entries of a
    # row; the two sum in other orders and combine products of different vectors).
    path = two_rectangles(folder / "products.msh", COMM, (0.2, 0.1), (0.3, 0.1), h=0.05)
    model = _two_blocks(path, 0.5, damping=Damping(alpha=2.0, beta=1e-4))
    layout = MonolithicLayout(model)
    bulk = BulkOperators(model, layout)
    products = bulk.products
    assert products.on  # M and K share their pattern, on any number of ranks
    rng = np.random.default_rng(11 + COMM.rank)
    u, v, a, da, r0, out, ref, tmp = (layout.vec.duplicate() for _ in range(8))
    for x, s in ((u, 1e-3), (v, 1e-1), (a, 1e2)):
        x.array[:] = s * rng.standard_normal(x.getLocalSize())
        x.array[bulk.bc_rows] = 0.0
    P = products.of(u.array, v.array, a.array)
    assert products.passes == 1
    assert products.of(u.array.copy(), v.array, a.array) is P and products.passes == 1
    ptr, col, m_val, k_val = products.csr
    rows = np.repeat(np.arange(len(ptr) - 1), np.diff(ptr))

    def bound(values: np.ndarray, x: np.ndarray) -> np.ndarray:
        # (On several ranks the rows' columns reach the ghosts: x with theirs.)
        return 40 * np.finfo(float).eps * np.bincount(
            rows, np.abs(values) * np.abs(products.with_ghosts(x)[col]), minlength=len(x))

    for k, (A, x) in enumerate(((bulk.M, v), (bulk.M, a), (bulk.K, u), (bulk.K, v),
                                (bulk.K, a))):
        A.mult(x, tmp)
        assert np.all(np.abs(P[k] - tmp.array) <= bound(m_val if k < 2 else k_val, x.array))
    # The predictor from P against the two products of the combined vectors.
    dt, (α, β) = 1e-3, (model.damping.alpha, model.damping.beta)
    bulk.predictor_residual(u, v, a, dt, out)
    ma, ku = np.empty(len(P[0])), np.empty(len(P[0]))
    predictor_vectors(u.array, v.array, a.array, dt, α, β, ma, ku)
    bulk.load(ref)
    scale = np.zeros(len(ma))
    for A, x, values in ((bulk.M, ma, m_val), (bulk.K, ku, k_val)):
        tmp.array[:] = x
        A.mult(tmp, r0)
        ref.array[:] -= r0.array
        # (P's combination: each product's round-off, of |u| + Δt|v| + Δt²|a| at most)
        scale += bound(values, x) + bound(values, np.abs(u.array) + np.abs(v.array)
                                          + np.abs(a.array))
    ref.array[bulk.bc_rows] = 0.0
    assert np.all(out.array[bulk.bc_rows] == 0.0)
    assert np.all(np.abs(out.array - ref.array) <= scale)
    # Newton's start Δa = −a/β₁: A Δa − r₀ from P against the product with A.
    step_dt, β1, β2 = 1e-3, 0.6, 0.605
    factorisations = Factorisations(bulk, interface_dofs(model, layout), β1, β2)
    fact = factorisations.factorisation(step_dt)
    da.array[:] = -a.array / β1
    bulk.start_residual(u, v, a, da, out, step_dt, β1, β2, fact.A, r0)
    fact.A.mult(da, ref)
    ref.axpy(-1.0, out)
    c_m, c_k = 1 + β1 * step_dt * α, 0.5 * β2 * step_dt**2 + β1 * step_dt * β
    scale = (c_m * bound(m_val, da.array) + c_k * bound(k_val, da.array)) * 2
    assert np.all(np.abs(r0.array - ref.array) <= scale + 1e-300)
    assert products.passes == 1  # every use from the one pass
    # Another state: formed again.
    a.array[0] += 1.0
    products.of(u.array, v.array, a.array)
    assert products.passes == 2
    for x in (u, v, a, da, r0, out, ref, tmp):
        x.destroy()
    factorisations.destroy()
    bulk.destroy()
