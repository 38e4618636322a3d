"""The Newton of a fast GN22 step on the contact-surface unknowns (a PETSc SNES).

With the bulk eliminated (:mod:`breakwater.stepping.condensed`), the step's residual on
the interface unknowns y = Δa_I is ``F(y) = S (y − z_I) + f_c(y)``. The SNES solves the
equivalent ``G(y) = X_II F = y − z_I + X_II f_c(y) = 0`` (Jacobian ``1 + X_II ∂f_c/∂y``)
and its convergence test reads the force ‖F‖ = ‖S G‖, with the tests and the round-off
floor of the reference Newton (:func:`~breakwater.stepping.solver.snes_reason`). Every
rank solves the same small dense system, so every rank takes the same decisions.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np
from petsc4py import PETSc

from breakwater.common.timings import Timings
from breakwater.stepping.factorisations import Factorisation
from breakwater.stepping.interface import ContactSum
from breakwater.stepping.solver import NewtonOptions, converged_iterations, snes_reason

__all__ = ["InterfaceNewton"]


class InterfaceNewton:
    """SNES Newton on the n_I interface unknowns of a step.

    Args:
        n: Number of interface unknowns.
        contact: f_c and its Jacobian on them.
        prefix: The SNES's options prefix.
        name: Names the solver in its errors.
        options: Convergence settings.
        force_scale: Force norm that scales ``options.atol``.
        timings: Where the Newton is timed (``newton``: the SNES but for the contact
            evaluations, timed by ``contact`` under ``interface_assembly``).
        precheck: Optional line-search pre-check ``(x, y) -> None`` modifying the step
            (the slip guards).

    Attributes:
        floor_accepts: Solves accepted at their round-off floor.
        fc: f_c at the last residual evaluation (at the solution after :meth:`solve`).
    """

    def __init__(self, n: int, contact: ContactSum, prefix: str, name: str,
                 options: NewtonOptions, force_scale: float, timings: Timings,
                 precheck: Callable[[PETSc.Vec, PETSc.Vec], None] | None = None) -> None:
        o = self.options = options
        self.contact, self.name, self.timings = contact, name, timings
        self.floor = o.floor_atol * force_scale
        self.floor_accepts = 0
        self._norms: list[float] = []
        self._fact: Factorisation | None = None
        self._z_I = np.zeros(n)
        self.fc = np.zeros(n)
        self._w_I = np.zeros(n)
        self._w_norm2 = 0.0
        self._force_norm = 0.0
        # The SNES on the interface unknowns: the same small system on every rank.
        self.snes = snes = PETSc.SNES().create(PETSc.COMM_SELF)
        snes.setOptionsPrefix(prefix)
        self._x = PETSc.Vec().createSeq(n, comm=PETSc.COMM_SELF)
        self._r = self._x.duplicate()
        self._Jac = PETSc.Mat().createDense((n, n), comm=PETSc.COMM_SELF)
        self._Jac.setUp()
        snes.setFunction(self._residual, self._r)
        snes.setJacobian(self._jacobian, self._Jac)
        snes.setType("newtonls")
        snes.getLineSearch().setType("basic")
        snes.setTolerances(rtol=o.rtol, atol=o.atol * force_scale, stol=o.stol,
                           max_it=o.max_it)
        snes.setMaxFunctionEvaluations(10 * o.max_it)
        # As in NewtonSolver: the friction law makes the residual jump while the
        # stick/slip state settles, so no divergence test on its growth.
        snes.setDivergenceTolerance(1e300)
        ksp = snes.getKSP()
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        snes.setConvergenceTest(self._converged)
        if precheck is not None:
            snes.setLineSearchPreCheck(precheck)
        snes.setFromOptions()

    def destroy(self) -> None:
        """Free the PETSc objects now."""
        for obj in (self.snes, self._x, self._r, self._Jac):
            obj.destroy()

    @property
    def y(self) -> np.ndarray:
        """The iterate (the converged y after :meth:`solve`), read-only."""
        return self._x.getArray(readonly=True)

    def solve(self, fact: Factorisation, z_I: np.ndarray, y0: np.ndarray, w_I: np.ndarray,
              w_norm2: float) -> int:
        """Solve ``G(y) = 0`` from y0; return the iterations.

        Args:
            fact: The step size's factorisation (X_II and S).
            z_I: z = A⁻¹ r₀ at the interface unknowns.
            y0: Newton's start.
            w_I: The bulk rows' residual at Newton's start, w = A Δa₀ − r₀, at the
                interface unknowns.
            w_norm2: ‖w‖² (for ‖F₀‖ of the relative test: see :meth:`_converged`).

        Raises:
            ConvergenceError: The SNES did not converge.
        """
        self._fact, self._z_I, self._w_I, self._w_norm2 = fact, z_I, w_I, w_norm2
        self._x.array[:] = y0
        T = self.timings
        assembly = T.seconds["interface_assembly"]
        t0 = time.perf_counter()
        self.snes.solve(None, self._x)
        T.seconds["newton"] += time.perf_counter() - t0 - (
            T.seconds["interface_assembly"] - assembly)
        return converged_iterations(self.snes, self.name)

    def _residual(self, snes: PETSc.SNES, x: PETSc.Vec, r: PETSc.Vec) -> None:
        assert self._fact is not None
        y = x.getArray(readonly=True)
        self.fc = self.contact.vector(y)
        # G = X_II F = y − z_I + X_II f_c(y): the same root as F = S (y − z_I) + f_c, but
        # without S's large entries of both signs, whose products carry n_I · |S| |y| of
        # round-off into F and stalled Newton above its tolerance (35 of the 1500 Goda
        # steps were accepted at the round-off floor, none now). The convergence test
        # reads the force ‖F‖ = ‖S G‖ (see _converged).
        G = y - self._z_I + self._fact.X_II @ self.fc
        r.array[:] = G
        self._force_norm = float(np.linalg.norm(self._fact.S @ G))

    def _jacobian(self, snes: PETSc.SNES, x: PETSc.Vec, J: PETSc.Mat, P: PETSc.Mat) -> None:
        assert self._fact is not None
        y = x.getArray(readonly=True)
        dense = self.contact.left_jacobian(y, self._fact.X_II)
        dense[np.diag_indices_from(dense)] += 1.0
        P.getDenseArray()[:] = dense
        P.assemble()

    def _converged(self, snes: PETSc.SNES, it: int, norms: tuple[float, float, float]) -> int:
        xnorm, ynorm, _ = norms
        fnorm = self._force_norm  # ‖F‖ = ‖S G‖, a force, as in the reference Newton
        if it == 0:
            # ‖F₀‖ of the relative test is the whole residual at Newton's start, bulk
            # rows included, as for the reference Newton: ‖R(Δa₀)‖² = ‖w‖² − ‖w_I‖² +
            # ‖w_I + f_c(y₀)‖² with w = A Δa₀ − r₀ (the bulk rows' residual).
            w_I = self._w_I
            whole = self._w_norm2 - w_I @ w_I + np.sum((w_I + self.fc) ** 2)
            self._norms = [math.sqrt(max(float(whole), fnorm**2))]
        else:
            self._norms.append(fnorm)
        reason, stalled = snes_reason(snes, self._norms, xnorm, ynorm, self.floor,
                                      self.options.stall_its)
        self.floor_accepts += stalled
        return reason
