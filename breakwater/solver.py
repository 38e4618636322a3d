"""Newton (PETSc SNES) on the blocked residual of a contact model, always checked."""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from .errors import ConvergenceError
from .model import ContactModel

_prefixes = itertools.count()


@dataclass(frozen=True)
class NewtonOptions:
    """Newton convergence settings.

    The residual of a penalty/friction problem with χ = 1e-10 has a round-off floor
    near ``μ p / χ`` times the cancellation in ``v_slave − v_master`` (about 1e-6 to
    1e-5 N/m in the Goda case), so the absolute tolerance is scaled by a force of the
    problem (its weight vector) rather than fixed.

    Attributes:
        rtol: Relative decrease of the residual norm.
        atol: Absolute residual tolerance, as a fraction of the force scale.
        stol: Relative Newton step tolerance (‖δx‖ < stol ‖x‖).
        max_it: Maximum Newton iterations.
        linear_solver: PETSc LU factorisation package.

    """

    rtol: float = 1e-9
    atol: float = 1e-9
    stol: float = 1e-12
    max_it: int = 40
    linear_solver: str = "mumps"


class NewtonSolver:
    """SNES Newton on ``F(x) = 0`` for one Function per body.

    Args:
        model: The contact model (for the entity maps and the boundary conditions).
        F: The residual (a single form with the model's test functions).
        x: The unknowns, one Function per body.
        name: Options prefix root; each solver gets its own ``petsc_options_prefix``.
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
            petsc_options_prefix=f"breakwater_{name}_{next(_prefixes)}_",
            petsc_options=petsc_options)
        self.snes: PETSc.SNES = self.problem.solver
        # The friction law makes the residual jump by orders of magnitude while the
        # stick/slip state settles: no divergence test on the growth of the residual.
        self.snes.setDivergenceTolerance(1e300)
        if precheck is not None:
            self.snes.setLineSearchPreCheck(precheck)
        self.name = name

    def solve(self) -> int:
        """Solve from the current values of ``x``; return the Newton iterations.

        Raises:
            ConvergenceError: SNES did not converge (the unknowns then hold the last
                iterate).

        """
        self.problem.solve()
        reason: int = self.snes.getConvergedReason()  # type: ignore[assignment]
        its = self.snes.getIterationNumber()
        if reason <= 0:
            raise ConvergenceError(
                f"{self.name}: Newton did not converge (SNES reason {reason}, "
                f"{its} iterations, residual {self.snes.getFunctionNorm():.3e})", reason, its)
        return its
