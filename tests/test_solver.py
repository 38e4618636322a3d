"""The SNES convergence test of :class:`breakwater.stepping.solver.NewtonSolver`.

PETSc's default tests plus one: a residual that has stalled at its round-off floor
(below ``floor_atol`` of the load norm, not halved over ``stall_its`` iterations) is
converged. The pure function is checked on residual histories written out here; a real
solve whose tolerances are all zero shows that the stall test, and only it, ends Newton
once the residual has reached round-off.
"""

from __future__ import annotations

import gc
import math
import pathlib
import sys
import weakref

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from breakwater.common.errors import ConvergenceError
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, ContactPair, Fixed, Material
from breakwater.stepping.gn22 import solve_static
from breakwater.stepping.solver import NewtonOptions, NewtonSolver, convergence_reason

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from blocks import two_rectangles

COMM = MPI.COMM_WORLD
R = PETSc.SNES.ConvergedReason
TOL = {"rtol": 1e-9, "atol": 1e-7, "stol": 1e-12, "max_it": 40, "floor": 1e-4, "stall_its": 3}


def _reason(norms: list[float], ynorm: float = 1.0, **changes: float) -> tuple[int, bool]:
    return convergence_reason(norms, 1.0, ynorm, **{**TOL, **changes})  # type: ignore[arg-type]



def _blocks(path: pathlib.Path, friction: float = 0.0, held_top: bool = False
            ) -> ContactModel:
    """Block ``a`` (stiff) on ``b`` (soft) under gravity, ``b_bottom`` fixed (and ``a_top``
    in x where ``held_top``), their conforming pair with the given friction."""
    mesh = two_rectangles(path, COMM, a=(0.2, 0.1), b=(0.4, 0.1), h=0.05)
    fixed = [Fixed("b_bottom")] + ([Fixed("a_top", (0,))] if held_top else [])
    return ContactModel(read_mesh(mesh, COMM),
                        [Body("a", Material(2314.0, 0.2, shear_modulus=2e9)),
                         Body("b", Material(2000.0, 0.25, shear_modulus=3e6))],
                        [ContactPair("interface", "a", "b", 5e8, friction=friction)],
                        fixed, gravity=(0.0, -9.81))

def test_petsc_default_tests() -> None:
    assert _reason([1.0]) == (R.CONVERGED_ITERATING, False)
    assert _reason([1.0, 1e-3]) == (R.CONVERGED_ITERATING, False)
    assert _reason([1.0, 1e-3, 5e-8]) == (R.CONVERGED_FNORM_ABS, False)
    assert _reason([1e3, 1e-7]) == (R.CONVERGED_FNORM_RELATIVE, False)  # 1e-10 relative
    assert _reason([1.0, 1e-3], ynorm=1e-13) == (R.CONVERGED_SNORM_RELATIVE, False)
    assert _reason([1.0, math.nan]) == (R.DIVERGED_FUNCTION_NANORINF, False)
    assert _reason([1.0, math.inf]) == (R.DIVERGED_FUNCTION_NANORINF, False)
    assert _reason([1.0] * 41) == (R.DIVERGED_MAX_IT, False)


def test_stall_below_the_floor_converges() -> None:
    # Quadratic convergence down to a round-off floor of ~1.3e-5 (above atol = 1e-7).
    norms = [1.0, 1e-2, 2e-5, 1.5e-5, 1.2e-5]
    assert _reason(norms[:4]) == (R.CONVERGED_ITERATING, False)  # 1.5e-5 < ½ × 1.0
    assert _reason(norms) == (R.CONVERGED_ITERATING, False)      # 1.2e-5 < ½ × 1e-2
    assert _reason([*norms, 1.3e-5]) == (R.CONVERGED_FNORM_ABS, True)  # > ½ × 2e-5
    # The same stall above the floor is not accepted.
    assert _reason([*norms, 1.3e-5], floor=1e-5) == (R.CONVERGED_ITERATING, False)


def test_no_stall_accepted_above_the_floor_or_while_decreasing() -> None:
    # A stick/slip 2-cycle at 1e-3 is above the floor (1e-4): never accepted.
    cycle = [1.0] + [1e-3, 2e-3] * 20
    assert all(_reason(cycle[:k])[0] == R.CONVERGED_ITERATING for k in range(1, 41))
    assert _reason(cycle) == (R.DIVERGED_MAX_IT, False)
    # Halving every iteration is 1/8 over three: still converging, not a stall.
    halving = [1e-5 * 0.5**k for k in range(7)]  # down to 1.6e-7 > atol
    assert all(_reason(halving[:k])[0] == R.CONVERGED_ITERATING for k in range(1, 8))
    # floor = 0 turns the test off.
    assert _reason([1.0, 1e-5, 1e-5, 1e-5, 1e-5], floor=0.0) == (R.CONVERGED_ITERATING, False)


def test_real_solve_ends_at_its_round_off_floor(folder: pathlib.Path) -> None:
    """Static solve of a block on a base with every PETSc tolerance set to zero.

    Newton then cannot converge by PETSc's tests; its residual falls to round-off
    (the static iteration converges linearly, see :func:`breakwater.stepping.gn22.solve_static`)
    and stays there, where the stall test accepts it. With the stall test off the
    same solve runs out of iterations. The accepted state equals the one of the
    default tolerances to 1e-8 of its largest displacement: the default solve stops
    at ‖F‖ < 1e-9 ‖f‖, so the two differ by that order (times the compliance), far
    below 1e-8.
    """
    model = _blocks(folder / "floor.msh")
    zero = NewtonOptions(rtol=0.0, atol=0.0, stol=0.0, max_it=40)
    u_floor, its = solve_static(model, options=zero)
    assert its < zero.max_it
    with pytest.raises(ConvergenceError):
        solve_static(model, options=NewtonOptions(rtol=0.0, atol=0.0, stol=0.0, max_it=40,
                                                  floor_atol=0.0))
    u_ref, its_ref = solve_static(model)
    assert its > its_ref
    for a, b in zip(u_floor, u_ref, strict=True):
        scale = COMM.allreduce(np.abs(b.x.array).max(), op=MPI.MAX)
        err = COMM.allreduce(np.abs(a.x.array - b.x.array).max(), op=MPI.MAX)
        assert err <= 1e-8 * scale


def test_each_solver_has_its_own_options_prefix(folder: pathlib.Path) -> None:
    """Solver prefixes are counted per model: distinct within a model, the same in every run."""
    path = two_rectangles(folder / "prefix.msh", COMM, a=(0.2, 0.1), b=(0.4, 0.1), h=0.05)
    data = read_mesh(path, COMM)
    bodies = [Body("a", Material(2314.0, 0.2, shear_modulus=2e9)),
              Body("b", Material(2000.0, 0.25, shear_modulus=3e6))]
    prefixes = []
    for _ in range(2):
        model = ContactModel(data, bodies, [ContactPair("interface", "a", "b", 5e8)],
                             [Fixed("b_bottom")], gravity=(0.0, -9.81))
        u = model.functions("u")
        solvers = [NewtonSolver(model, model.residual(u), u, name)
                   for name in ("static", "static", "gn22")]
        prefixes.append([solver.snes.getOptionsPrefix() for solver in solvers])
        for solver in solvers:
            solver.destroy()
    assert prefixes[0] == ["breakwater_static_0_", "breakwater_static_1_", "breakwater_gn22_2_"]
    assert prefixes[1] == prefixes[0]
    assert prefixes[0] == COMM.bcast(prefixes[0], root=0)  # the same on every rank


def test_solver_options_leave_petsc_options_database(folder: pathlib.Path) -> None:
    """A solver's options are read, then removed from PETSc's global options database.

    Before, every solver's ``breakwater_<name>_<k>_snes_*`` options (11 per prefix)
    stayed in the database for the rest of the process: a notebook that ran a case
    kept them, and the next solver of the same prefix read them again.
    """
    model = _blocks(folder / "options.msh")
    database = PETSc.Options()
    database["user_own_option"] = 3  # (a caller's own: left alone)
    u = model.functions("u")
    options = NewtonOptions(rtol=1e-7, max_it=17)
    solver = NewtonSolver(model, model.residual(u), u, "static", options)
    try:
        left = sorted(k for k in database.getAll() if k.startswith("breakwater_"))
        assert left == []
        assert database.getInt("user_own_option") == 3
        # ... after the solver has read them.
        rtol, _, _, max_it = solver.snes.getTolerances()
        assert (rtol, max_it) == (1e-7, 17)
        assert solver.snes.getKSP().getPC().getFactorSolverType() == options.linear_solver
    finally:
        solver.destroy()
        database.delValue("user_own_option")


def test_solver_interrupted_while_built_leaves_no_error(folder: pathlib.Path,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """A KeyboardInterrupt while the SNES problem is built is the only error shown.

    Before, dolfinx's ``NonlinearProblem.__del__`` then met a half-built problem:
    ``Exception ignored in ... AttributeError: ... '_snes'`` in the notebook's cell.
    """
    model = _blocks(folder / "halfbuilt.msh")
    u = model.functions("u")
    create_vector = fem_petsc.create_vector

    def interrupted(*args: object, **kwargs: object) -> PETSc.Vec:
        raise KeyboardInterrupt  # (after the matrix, before the SNES: every rank)

    unraisable: list[object] = []
    monkeypatch.setattr(sys, "unraisablehook", unraisable.append)
    with monkeypatch.context() as mp:
        mp.setattr(fem_petsc, "create_vector", interrupted)
        with pytest.raises(KeyboardInterrupt):
            NewtonSolver(model, model.residual(u), u, "static")
    gc.collect()
    assert [getattr(x, "exc_value", x) for x in unraisable] == []
    assert fem_petsc.create_vector is create_vector
    solver = NewtonSolver(model, model.residual(u), u, "static")  # and the next one works
    solver.destroy()


def test_destroyed_solver_is_freed(folder: pathlib.Path) -> None:
    """destroy() frees a solver's PETSc objects, and then Python can free the solver.

    Without it the SNES keeps the solver's bound callbacks where the garbage collector
    cannot see them: the solver, its PETSc objects and their MPI communicators live
    until the process ends.
    """
    model = _blocks(folder / "freed.msh")
    u = model.functions("u")
    kept, freed = (NewtonSolver(model, model.residual(u), u, "static") for _ in range(2))
    refs = [weakref.ref(kept), weakref.ref(freed)]
    freed.destroy()
    assert freed.snes.handle == 0 and kept.snes.handle != 0
    del kept, freed
    gc.collect()
    assert refs[1]() is None
    assert refs[0]() is not None  # the leak destroy() exists for
    refs[0]().destroy()  # type: ignore[union-attr]


def test_residual_without_the_zero_lifting_is_dolfinx_residual(folder: pathlib.Path) -> None:
    """The SNES residual skips the Dirichlet lifting exactly where it is zero.

    Where x vanishes at every constrained unknown (the conditions are homogeneous) the
    lifted term ``J (g − x)`` is zero: the residual without it equals dolfinx's
    (:func:`dolfinx.fem.petsc.assemble_residual`) bit for bit, and no lifting is done.
    Where x does not vanish there, the residual lifts, as dolfinx's, and differs from
    the residual assembled without the lifting (so the first comparison can fail).
    """
    from dolfinx import fem
    from dolfinx.fem import petsc as fem_petsc

    model = _blocks(folder / "lifting.msh", friction=0.6, held_top=True)
    u = model.functions("u")
    solver = NewtonSolver(model, model.residual(u), u, "static")
    residual, problem = solver.residual, solver.problem
    assert residual.homogeneous
    assert COMM.allreduce(int(residual._constrained.sum())) > 0
    blocks = problem.b.getAttr("_blocks")

    def vec() -> PETSc.Vec:
        v = problem.b.duplicate()
        v.setAttr("_blocks", blocks)
        return v

    def dolfinx_residual(x: PETSc.Vec) -> np.ndarray:
        b = vec()
        fem_petsc.assemble_residual(solver.snes, x, b, problem.u, problem.F, problem.J,
                                    model.bcs, _blocks=blocks)
        return b.getArray().copy()

    x = vec()
    rng = np.random.default_rng(COMM.rank)
    values = 1e-4 * rng.standard_normal(x.getLocalSize())
    values[residual._constrained] = 0.0
    x.setArray(values)
    x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    b = vec()
    residual(solver.snes, x, b)
    assert (residual.skipped, residual.lifted) == (1, 0)
    assert np.array_equal(b.getArray(), dolfinx_residual(x))

    values[residual._constrained] = 1e-4  # x no longer satisfies the conditions
    x.setArray(values)
    x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    residual(solver.snes, x, b)
    assert (residual.skipped, residual.lifted) == (1, 1)
    lifted = dolfinx_residual(x)
    assert np.array_equal(b.getArray(), lifted)
    # Here the lifting is not zero: the residual assembled without it differs.
    residual.lifting_is_zero = lambda x: True  # type: ignore[method-assign]
    residual(solver.snes, x, b)
    free = ~residual._constrained
    changed = np.abs(b.getArray()[free] - lifted[free]).max(initial=0.0)
    assert COMM.allreduce(changed, op=MPI.MAX) > 0.0
    solver.destroy()

    V = model.functions("g")[0].function_space
    one = fem.dirichletbc(np.float64(1.0), np.array([0], np.int32), V.sub(0))
    from breakwater.stepping.snesassembly import _zero_constant
    assert not _zero_constant(one)
    assert all(_zero_constant(bc) for bc in model.bcs)


def test_slow_phase_shows_its_lines_after_a_while() -> None:
    # A phase shows nothing for its first AFTER seconds, then one line every EVERY
    # seconds at most, with the time elapsed (a clock written here).
    import logging

    from breakwater.common.console import SlowPhase

    now = [0.0]
    shown: list[str] = []

    class Collect(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            shown.append(record.getMessage())

    logger = logging.getLogger("test_solver.slowphase")
    logger.setLevel(logging.INFO)
    logger.propagate = False
    handler = Collect()
    logger.addHandler(handler)
    try:
        phase = SlowPhase(logger, "static", clock=lambda: now[0])
        for t in (1.0, 9.9, 10.0, 15.0, 19.9, 20.0, 31.0):
            now[0] = t
            phase("iteration %d", int(t))
    finally:
        logger.removeHandler(handler)
    assert shown == ["static: iteration 10 (10 s)", "static: iteration 20 (20 s)",
                     "static: iteration 31 (31 s)"]


def test_jacobian_with_its_bulk_assembled_once_is_dolfinx_jacobian(folder: pathlib.Path
                                                                   ) -> None:
    """The SNES Jacobian: the bodies' cell part once per solve, the rest every iteration.

    At a state in contact, a solve's first Jacobian (the cell part and the rest assembled
    into it) and the next (the kept cell part and the rest) equal dolfinx's Jacobian: bit for bit on
    one rank (the same kernels, each entry summed in the same order); on several to
    1e-14 of its largest entry (PETSc adds the contributions to other ranks' rows at the
    end of each assembly, so the entries on the ranks' boundary are summed in another
    order: round-off, 1e-16 relative each). After a change of a body's modulus and a new
    solve, again; without the new solve the kept bulk part is stale and differs by
    O(1) of the changed entries (so the comparison can fail).
    """
    from dolfinx.fem import petsc as fem_petsc

    model = _blocks(folder / "jacobian.msh", friction=0.6)
    u, _ = solve_static(model)  # a state with the interface closed
    solver = NewtonSolver(model, model.residual(u), u, "static")
    jacobian, problem = solver.jacobian, solver.problem
    assert jacobian.split
    x = problem.x
    fem_petsc.assign(u, x)

    def dolfinx_jacobian() -> tuple[np.ndarray, ...]:
        A = fem_petsc.create_matrix(problem.J, kind="mpi")
        fem_petsc.assemble_jacobian(solver.snes, x, A, None, problem.u, problem.J, None,
                                    model.bcs)
        csr = A.getValuesCSR()
        A.destroy()
        return csr

    def ours() -> tuple[np.ndarray, ...]:
        jacobian(solver.snes, x, problem.A, None)
        return problem.A.getValuesCSR()

    def same(a: tuple[np.ndarray, ...], b: tuple[np.ndarray, ...]) -> bool:
        pattern = np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
        if COMM.size == 1:
            return pattern and np.array_equal(a[2], b[2])
        scale = COMM.allreduce(np.abs(b[2]).max(initial=0.0), op=MPI.MAX)
        close = pattern and np.abs(a[2] - b[2]).max(initial=0.0) <= 1e-14 * scale
        return bool(COMM.allreduce(close, op=MPI.LAND))

    jacobian.new_solve()
    assert same(ours(), dolfinx_jacobian())  # a solve's first: cell part, then the rest
    assert same(ours(), dolfinx_jacobian())  # the next: the kept cell part, then the rest
    b = model.body("b")
    b.μ.value *= 2.0
    b.λ.value *= 2.0
    assert not same(ours(), dolfinx_jacobian())  # the cell part kept from before
    jacobian.new_solve()
    assert same(ours(), dolfinx_jacobian())
    assert same(ours(), dolfinx_jacobian())
    solver.destroy()


def test_an_unchanged_jacobian_keeps_its_factorisation(folder: pathlib.Path,
                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    """A frictionless static solve: where the interface and load integrals are those of
    the last iteration (the closed points stay), the Jacobian is left as it is and its
    LU factors are kept (PETSc's MatLUFactorNum counted: one per Jacobian assembled).
    The state and the iterations are those of the solve that assembles and factorises
    every Jacobian: bit for bit on one rank (the same matrices, the same factors); on
    several, to 1e-13 of the largest displacement. There MUMPS's factorisation and
    solve of the same matrix and residual round off differently now and then: the
    solve that factorises every Jacobian differed from run to run in 5 of 260 two-rank
    runs, by 1e-19 m of 3.7e-5 m, the Jacobians, residuals and iterates before hashed
    equal, with one BLAS thread per rank too (2026-11-28). A Jacobian kept where it
    changed would converge to the solution only within Newton's tolerance (1e-10 and
    more of it) and in other iterations."""
    from breakwater.stepping import snesassembly

    PETSc.Log.begin()
    factorisations = PETSc.Log.Event("MatLUFactorNum")
    kept = []
    unchanged = snesassembly.ConstantBulk._unchanged

    def counted(self: snesassembly.ConstantBulk) -> bool:
        kept.append(unchanged(self))
        return kept[-1]

    def solve(model: ContactModel) -> tuple[np.ndarray, int, int]:
        before = factorisations.getPerfInfo()["count"]
        u, its = solve_static(model)
        state = np.concatenate([f.x.array for f in u])
        return state, its, factorisations.getPerfInfo()["count"] - before

    monkeypatch.setattr(snesassembly.ConstantBulk, "_unchanged", counted)
    state, its, factored = solve(_blocks(folder / "kept.msh"))
    monkeypatch.setattr(snesassembly.ConstantBulk, "_unchanged", lambda self: False)
    state_all, its_all, factored_all = solve(_blocks(folder / "kept.msh"))
    assert its == its_all
    if COMM.size == 1:
        assert np.array_equal(state, state_all)
    else:
        scale = COMM.allreduce(np.abs(state_all).max(), op=MPI.MAX)
        difference = COMM.allreduce(np.abs(state - state_all).max(), op=MPI.MAX)
        assert difference <= 1e-13 * scale
    assert sum(kept) >= 2 and factored_all == its  # every iteration factorised
    assert factored == its - sum(kept)
