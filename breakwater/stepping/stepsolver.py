"""What the GN22 stepper and the run ask of the solver of one step: :class:`StepSolver`.

Two classes implement it: :class:`~breakwater.stepping.solver.NewtonSolver` (the
reference path, PETSc SNES on the whole residual of the step) and
:class:`~breakwater.stepping.condensed.CondensedNewton` (the fast path, the bulk
eliminated and Newton on the contact-surface unknowns).
:class:`~breakwater.stepping.gn22.GN22` stages a step (Δa holds Newton's start),
calls :meth:`StepSolver.solve` and, on success, updates the state from Δa (and calls
:meth:`StepSolver.accept`); its initial
acceleration adds :meth:`StepSolver.add_surface_forces`; the run counts
:attr:`StepSolver.floor_accepts` (saved in checkpoints) and folds
:attr:`StepSolver.timings` into the time loop's split.
"""

from __future__ import annotations

from typing import Any, Protocol

from petsc4py import PETSc

from breakwater.common.timings import Timings

__all__ = ["PairMemory", "StepSolver"]

type PairMemory = dict[str, Any] | list[float | None] | None
"""A general pair's state beyond u, v, a in a checkpoint (JSON): ``{"slip": [...],
"facets": [...]}``; a bare list of slip velocities in checkpoints of before 2026-11-28."""


class StepSolver(Protocol):
    """The Newton of one GN22 step on the unknown Δa.

    Attributes:
        floor_accepts: Solves accepted at their round-off floor, over the run
            (:class:`~breakwater.stepping.solver.NewtonOptions`); a resumed run sets it
            from its checkpoint.
        timings: Wall time of the solver's parts (s), summed until the run loop folds
            and resets them.
    """

    floor_accepts: int
    timings: Timings

    def solve(self) -> int:
        """Solve the staged step from the current Δa (Newton's start); return the iterations.

        Raises:
            ConvergenceError: The step did not converge (PenetrationError: it was
                rejected); the state at t is untouched.
        """
        ...

    def accept(self) -> None:
        """The step just solved is accepted (GN22 updates the state from its Δa)."""
        ...

    def memory(self) -> list[PairMemory]:
        """What the next step depends on beyond the state Functions (a checkpoint's)."""
        ...

    def restore(self, memory: list[PairMemory]) -> None:
        """Set what :meth:`memory` returned, on resuming a run."""
        ...

    def add_surface_forces(self, vec: PETSc.Vec, scale: float = 1.0) -> None:
        """Add ``scale`` × the contact forces missing from the UFL residual to ``vec``.

        At the accepted state (u, v), into the owned entries of a stacked vector: the
        right-hand side of the initial acceleration a₀.
        """
        ...

    def destroy(self) -> None:
        """Free the PETSc objects now (collective: on every rank at once)."""
        ...
