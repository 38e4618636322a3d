"""Newton (PETSc SNES) on the blocked residual of a contact model, always checked."""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from breakwater.common.console import SlowPhase
from breakwater.common.errors import ConvergenceError
from breakwater.common.timings import Timings
from breakwater.model.model import ContactModel
from breakwater.stepping.factorisations import check_factorisation
from breakwater.stepping.snesassembly import ConstantBulk, HomogeneousLifting
from breakwater.stepping.stepsolver import PairMemory, StepSolver

log = logging.getLogger("breakwater.stepping.solver")


@dataclass(frozen=True)
class NewtonOptions:
    """Newton convergence settings.

    The residual of a penalty/friction problem with χ = 1e-10 has a round-off floor
    near ``μ p / χ`` times the cancellation in ``v_slave − v_master``, so the absolute
    tolerance is scaled by a force of the problem (its load vector) rather than fixed.
    The floor grows with the pressure at sticking nodes: when a body rocks on a corner
    with a stiff penalty it can exceed ``atol``. Measured on the Goda case with ε_n =
    2e9 (inside the range the contact-quality report suggests): without the stall test
    the step from t = 0.0683 s stays at ‖F‖ = 1.24e-7 against atol = 1.03e-7 for 40
    iterations, at every step size down to Δt/16, and the run fails; with it, 7 of the
    1500 steps are accepted at their floor and the run finishes. A solve whose
    residual has stopped decreasing below ``floor_atol`` is therefore accepted as
    converged to round-off (see :func:`convergence_reason`) and counted
    (:attr:`NewtonSolver.floor_accepts`, ``solver.round_off_accepts`` of a run).

    Attributes:
        rtol: Relative decrease of the residual norm.
        atol: Absolute residual tolerance, as a fraction of the force scale.
        stol: Relative Newton step tolerance (‖δx‖ < stol ‖x‖).
        max_it: Maximum Newton iterations.
        linear_solver: PETSc LU factorisation package.
        floor_atol: A residual below this fraction of the force scale that has not
            halved over ``stall_its`` iterations is round-off: converged. 1e-6 of the
            load vector is an out-of-balance force far below what any output resolves
            (the displacements it causes are 1e-6 of the loads' own, against a
            discretisation error of about 1e-2); 0 turns the test off.
        stall_its: Iterations without halving of the residual that make a stall.

    """

    rtol: float = 1e-9
    atol: float = 1e-9
    stol: float = 1e-12
    max_it: int = 40
    linear_solver: str = "mumps"
    floor_atol: float = 1e-6
    stall_its: int = 3


_R = PETSc.SNES.ConvergedReason


def convergence_reason(norms: Sequence[float], xnorm: float, ynorm: float, *, rtol: float,
                       atol: float, stol: float, max_it: int, floor: float,
                       stall_its: int) -> tuple[int, bool]:
    """The SNES convergence test of :class:`NewtonSolver`: PETSc's default, plus stalls.

    PETSc's tests, in its order: a non-finite residual diverges; ``‖F‖ < atol``,
    ``‖F‖ ≤ rtol ‖F₀‖`` and ``‖δx‖ < stol ‖x‖`` converge. Then the round-off floor:
    after at least ``stall_its`` iterations, a residual below ``floor`` that is more
    than half the residual of ``stall_its`` iterations before has stalled: converged.
    A quadratically converging Newton divides its residual by far more than 2 per
    iteration, and a stall above ``floor`` (a stick/slip cycle) is not accepted.

    Args:
        norms: Residual norms ‖F‖ of iterations 0, 1, ..., the current one last.
        xnorm: ‖x‖ of the current iterate.
        ynorm: ‖δx‖ of the last Newton step.
        rtol: Relative tolerance.
        atol: Absolute tolerance.
        stol: Step tolerance.
        max_it: Iterations allowed.
        floor: Largest residual accepted as a round-off floor (0: no stall test).
        stall_its: Iterations without halving that make a stall.

    Returns:
        ``(reason, stalled)``: the SNES converged reason (0 while iterating) and
        whether it was the stall test that converged.
    """
    it, f = len(norms) - 1, norms[-1]
    if not math.isfinite(f):
        return int(_R.DIVERGED_FUNCTION_NANORINF), False
    if f < atol:
        return int(_R.CONVERGED_FNORM_ABS), False
    if it > 0 and f <= rtol * norms[0]:
        return int(_R.CONVERGED_FNORM_RELATIVE), False
    if it > 0 and ynorm < stol * xnorm:
        return int(_R.CONVERGED_SNORM_RELATIVE), False
    if it >= stall_its > 0 and f < floor and f > 0.5 * norms[it - stall_its]:
        return int(_R.CONVERGED_FNORM_ABS), True
    if it >= max_it:
        return int(_R.DIVERGED_MAX_IT), False
    return int(_R.CONVERGED_ITERATING), False


def snes_reason(snes: PETSc.SNES, norms: Sequence[float], xnorm: float, ynorm: float,
                floor: float, stall_its: int) -> tuple[int, bool]:
    """:func:`convergence_reason` with the SNES's own tolerances (a convergence test)."""
    rtol, atol, stol, max_it = snes.getTolerances()
    return convergence_reason(norms, xnorm, ynorm, rtol=rtol, atol=atol, stol=stol,
                              max_it=max_it, floor=floor, stall_its=stall_its)


def converged_iterations(snes: PETSc.SNES, name: str) -> int:
    """The iterations of a solved SNES.

    Raises:
        ConvergenceError: It did not converge (its reason, iterations and residual).
    """
    reason: int = snes.getConvergedReason()  # type: ignore[assignment]
    its = snes.getIterationNumber()
    if reason <= 0:
        raise ConvergenceError(
            f"{name}: Newton did not converge (SNES reason {reason}, {its} iterations, "
            f"residual {snes.getFunctionNorm():.3e})", reason, its)
    return its


class NewtonTimings(Timings):
    """Wall time of the reference Newton: its SNES solves in total, under ``newton``."""

    def __init__(self) -> None:
        self.seconds = {"newton": 0.0}


def clear_options(prefix: str, options: Mapping[str, object]) -> None:
    """Remove a solver's options, read already, from PETSc's global options database.

    dolfinx's ``NonlinearProblem`` means to (``del opts[k]`` with the prefix pushed),
    but petsc4py's deletion ignores a pushed prefix: every solver's
    ``breakwater_<name>_<k>_snes_*`` options stayed in the database for the rest of
    the process (a notebook), read again by the next solver of that prefix.
    """
    database = PETSc.Options()
    for key in options:
        database.delValue(f"{prefix}{key}")


class NewtonSolver(StepSolver):
    """SNES Newton on ``F(x) = 0`` for one Function per body.

    The reference path's :class:`~breakwater.stepping.stepsolver.StepSolver` (F the
    whole residual of a GN22 step, x its Δa), and the Newton of the static problems.

    Args:
        model: The contact model (for the entity maps and the boundary conditions).
        F: The residual (a single form with the model's test functions).
        x: The unknowns, one Function per body.
        name: Options prefix root; each solver gets its own ``petsc_options_prefix``,
            ``breakwater_<name>_<k>_`` with k counted per model
            (:meth:`~breakwater.model.model.ContactModel.options_prefix`).
        options: Convergence settings.
        force_scale: Force norm that scales ``options.atol``.
        precheck: Optional line-search pre-check ``(x, y) -> None`` modifying the step.

    """

    def __init__(self, model: ContactModel, F: ufl.Form, x: Sequence[fem.Function], name: str,
                 options: NewtonOptions | None = None, force_scale: float = 1.0,
                 precheck: Callable[[PETSc.Vec, PETSc.Vec], None] | None = None,
                 jacobian_of: ufl.Form | None = None) -> None:
        self.options = o = options or NewtonOptions()
        self.x = list(x)
        petsc_options = {
            "snes_type": "newtonls",
            "snes_linesearch_type": "basic",
            "snes_rtol": o.rtol,
            "snes_atol": o.atol * force_scale,
            "snes_stol": o.stol,
            "snes_max_it": o.max_it,
            "snes_max_funcs": 10 * o.max_it,
            "ksp_type": "preonly",
            "pc_type": "lu",
            "pc_factor_mat_solver_type": o.linear_solver,
            "ksp_error_if_not_converged": True,
        }
        J = None
        if jacobian_of is not None:
            J = fem_petsc.derivative_block(ufl.extract_blocks(jacobian_of), self.x)
        self.problem = fem_petsc.NonlinearProblem(
            ufl.extract_blocks(F), self.x, bcs=model.bcs, J=J, kind="mpi",
            entity_maps=model.entity_maps,
            petsc_options_prefix=(prefix := model.options_prefix(name)),
            petsc_options=petsc_options)
        clear_options(prefix, petsc_options)
        self.snes: PETSc.SNES = self.problem.solver
        self.residual = HomogeneousLifting(self.problem, model.bcs)
        self.snes.setFunction(self.residual, self.problem.b)
        self.jacobian = ConstantBulk(self.problem, jacobian_of or F, self.x, model.bcs,
                                     model.entity_maps)
        self.snes.setJacobian(self.jacobian, self.problem.A, self.problem.P_mat)
        # The friction law makes the residual jump by orders of magnitude while the
        # stick/slip state settles: no divergence test on the growth of the residual.
        self.snes.setDivergenceTolerance(1e300)
        self.floor = o.floor_atol * force_scale
        self.floor_accepts = 0  # solves accepted at their round-off floor
        self.timings: Timings = NewtonTimings()
        self._norms: list[float] = []
        self.snes.setConvergenceTest(self._converged)
        if precheck is not None:
            self.snes.setLineSearchPreCheck(precheck)
        self.name = name
        # A solve that runs long (a 3D static state: minutes) reports its iterations.
        self._phase: SlowPhase | None = None
        self.snes.setMonitor(self._monitor)

    def _monitor(self, snes: PETSc.SNES, it: int, fnorm: float) -> None:
        if self._phase is not None:
            self._phase("iteration %d, residual %.3e", it, fnorm)

    def _converged(self, snes: PETSc.SNES, it: int, norms: tuple[float, float, float]
                   ) -> int:
        xnorm, ynorm, fnorm = norms
        if it == 0:
            self._norms = []
        self._norms.append(fnorm)
        reason, stalled = snes_reason(snes, self._norms, xnorm, ynorm, self.floor,
                                      self.options.stall_its)
        self.floor_accepts += stalled
        return reason

    def accept(self) -> None:
        """Nothing to keep: the step's state is all in the Functions."""

    def memory(self) -> list[PairMemory]:
        """Nothing beyond the state Functions (no general pairs on this path)."""
        return []

    def restore(self, memory: list[PairMemory]) -> None:
        """Nothing to set."""

    def destroy(self) -> None:
        """Free the solver's PETSc objects now (collective: on every rank at once).

        PETSc holds the SNES callbacks, bound to this solver, out of sight of Python's
        garbage collector, so a solver never destroyed keeps its PETSc objects, and
        their MPI communicators (MPICH has 2048 per process), until the process ends.
        Leaving them to the garbage collector instead would destroy them at a
        different moment on each rank, while the destruction of a parallel matrix and
        its MUMPS factorisation is collective: the ranks would deadlock.
        """
        p = self.problem
        for obj in (p.solver, p.A, p.b, p.x, p.P_mat):
            if obj is not None:
                obj.destroy()
        self.jacobian.destroy()

    def add_surface_forces(self, vec: PETSc.Vec, scale: float = 1.0) -> None:
        """Nothing to add: F holds every force (the reference path has no general pair)."""

    def solve(self) -> int:
        """Solve from the current values of ``x``; return the Newton iterations.

        Raises:
            ConvergenceError: SNES did not converge (the unknowns then hold the last
                iterate).

        """
        t0 = time.perf_counter()
        self._phase = SlowPhase(log, f"Newton of {self.name}")
        self.jacobian.new_solve()
        try:
            self.problem.solve()
        except PETSc.Error as e:
            if isinstance(e.__cause__, KeyboardInterrupt):  # raised in a callback (the
                # residual's assembly: a second interrupt in a notebook), which petsc4py
                # turns into PETSc error 101: the run said "failed", a crash
                raise e.__cause__ from None
            # A factorisation MUMPS could not complete: say so in one line.
            check_factorisation(self.snes.getKSP(), f"the Newton matrix of {self.name}")
            raise
        self.timings.seconds["newton"] += time.perf_counter() - t0
        return converged_iterations(self.snes, self.name)
