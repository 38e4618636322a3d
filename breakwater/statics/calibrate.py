"""Calibration of a soil shear modulus to a structure's horizontal stiffness.

Stickle et al. (2011, §5.3) set the shear modulus G of the gravel mound so that the
caisson's horizontal stiffness equals the one of Goda's (1994) mass-spring model,
K_x ≈ 500 kN/m for the 0.205 m long block, i.e. K_x / 0.205 m in plane strain.

The model's stiffness is measured as in the mass-spring analogy, where the spring
carries the inertial force of the block:

- load: a uniform horizontal acceleration ``a`` of the structure only, i.e. the body
  force ``ρ a e_x`` (the inertial load of a rigid-body sway; the soil is the
  massless spring). Its resultant ``H = a ∫ρ`` acts at the centre of mass, where
  the mass-spring model puts it. A traction at the struck bolt would instead add a
  rocking moment that the measured sway stiffness does not contain.
- displacement: the mass-weighted mean horizontal displacement of the structure
  (its centre-of-mass displacement), the work-conjugate of that load: H ū = ∫ f·u.
- interface: bonded, the state of the contact at small amplitude. The caisson sits
  in compression under its weight, where the penalty law is linear with stiffness
  ε_n, and sticks, where the regularised Coulomb law with χ = 1e-10 m/s is a
  tangential viscosity μp/χ ~ 1e13 Pa s/m: no slip. The bonded interface is
  ``ε_n (δu·n)(δw·n) + k_t T(δu)·T(δw)`` with a stiff tangential spring
  ``k_t = tangential_penalty · ε_n`` (default 1000 ε_n) and a *bilateral* normal
  spring; the problem is then linear, K does not depend on the load magnitude and
  equals the tangent stiffness about the gravity-loaded, fully closed state.

K grows monotonically with the soil modulus (about linearly while the structure
and the interface springs are much stiffer than the soil), so G is found by secant
iterations on ``log K(log G)``; each K costs one linear solve (the forms compile once
and the moduli are Constants). The solves after the first reuse its factorisation:
K(G) = K(G₀) + (G/G₀ − 1) K_b(G₀), with K_b the calibrated body's stiffness (its λ and
μ scale with G at a fixed Poisson's ratio), is solved by conjugate gradients
preconditioned with the LU factors of K(G₀), whose preconditioned operator has its
eigenvalues between 1 and G/G₀ (K_b is positive semi-definite): within
:data:`REUSE_RATIO` of G₀, 33 iterations or fewer reach :data:`REUSE_RTOL`. A G
farther off, or CG not converging, factorises again. On ``goda3d`` at ``mesh.refinement
= 2`` (209 700 unknowns) a solve took 37–43 s with its factorisation and 20–23 s on a
kept one (5–14 CG iterations; the rest was the assembly of K(G), 18 s; 2026-11-28).
K(G) itself is no longer assembled after the first solve: :class:`ScaledStiffness`
forms it from K(G₀) and K_b (``goda3d``'s calibration: 20.9 → 13.3 s).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common.console import SlowPhase
from breakwater.common.errors import BreakwaterError, ConvergenceError
from breakwater.model.model import ContactModel
from breakwater.stepping.solver import NewtonOptions, NewtonSolver

#: A solve reuses the last factorisation where G is within this factor of its G₀: the
#: preconditioned operator's condition number is then at most 5, and CG divides the
#: error by 2.6 per iteration or more (33 iterations to 1e-13; a calibration from the
#: Goda cases' initial guess of 1e7 Pa steps to 2.87e6, then within 2 % of it).
REUSE_RATIO = 5.0
#: CG's relative tolerance in a reused factorisation's solve (a direct solve's
#: round-off is about 1e-12 of the load here: the bonded springs k_t = 1000 ε_n).
REUSE_RTOL = 1e-13
#: CG's iterations before it counts as failed (then the solve factorises again).
REUSE_MAX_IT = 100


class CalibrationError(BreakwaterError):
    """The calibration cannot reach its target (out of range, no convergence)."""


@dataclass(frozen=True)
class CalibrationResult:
    """Outcome of a stiffness calibration.

    Attributes:
        body: Body whose shear modulus was calibrated.
        structure: Body whose horizontal stiffness was matched.
        shear_modulus: Calibrated shear modulus G (Pa).
        stiffness: Horizontal stiffness of the model with that G (N/m per metre of
            length out of plane).
        target: Target stiffness (N/m per metre).
        relative_error: |stiffness − target| / target.
        iterations: Stiffness solves done.
        history: (G, K) of every solve, in order.

    """

    body: str
    structure: str
    shear_modulus: float
    stiffness: float
    target: float
    relative_error: float
    iterations: int
    history: tuple[tuple[float, float], ...]

    def summary(self) -> dict[str, object]:
        """A JSON-serialisable summary (for summary.json)."""
        return {"body": self.body, "structure": self.structure,
                "shear_modulus": self.shear_modulus, "stiffness": self.stiffness,
                "target": self.target, "relative_error": self.relative_error,
                "iterations": self.iterations,
                "history": [list(h) for h in self.history]}


class HorizontalStiffness:
    """The horizontal stiffness of a structure on bonded interfaces, as a function of G.

    Args:
        model: Contact model (its loads, gravity and damping are ignored; its fixed
            boundaries and contact pairs are used, the pairs as bonded interfaces).
        structure: Name of the body loaded and measured.
        tangential_penalty: k_t / ε_n of the bonded interfaces.
        direction: Horizontal unit vector of the load (default ``e_x``).

    """

    def __init__(self, model: ContactModel, structure: str, tangential_penalty: float = 1e3,
                 direction: Sequence[float] | None = None) -> None:
        if not tangential_penalty > 0:
            raise ValueError(f"tangential_penalty must be > 0 (got {tangential_penalty})")
        self.model = m = model
        self.structure = s = m.body(structure)
        e = np.zeros(m.gdim)
        e[0] = 1.0
        if direction is not None:
            e = np.asarray(direction, dtype=float)
            e /= np.linalg.norm(e)
        self.direction = e
        self.u = m.functions("calibration")
        acceleration = fem.Constant(m.mesh, np.asarray(e, dtype=float))
        F = m.stiffness(self.u) - forms.body_force(s.ρ, acceleration, m.w[s.index], s.dx)
        for p in m.pairs:
            jump = self.u[p.slave]("+") - self.u[p.master]("-")
            δ = m.w[p.slave]("+") - m.w[p.master]("-")
            k_t = tangential_penalty * p.ε_n
            F += (p.ε_n * ufl.dot(jump, p.n) * ufl.dot(δ, p.n)
                  + k_t * ufl.dot(forms.tangential_part(jump, p.n),
                                  forms.tangential_part(δ, p.n))) * p.dS
        # Unit acceleration: H = ∫ρ (per metre); force scale of the Newton check.
        self.force = m.assemble(m.form(s.ρ * s.dx))
        self._moment = m.form(s.ρ * ufl.dot(self.u[s.index], ufl.as_vector(e.tolist())) * s.dx)
        # A linear problem: one Newton step solves it to round-off (about 1e-11 of the
        # load with k_t = 1000 ε_n); the tolerances only check that step.
        options = NewtonOptions(rtol=1e-8, atol=1e-9, stol=0.0, max_it=5)
        self.solver = NewtonSolver(m, F, self.u, "calibration", options,
                                   force_scale=self.force)
        self.factorised_at: float | None = None  # the G of the factorisation kept
        self.reused = 0  # solves by CG on a kept factorisation
        #: K(G) without its assembly, from the first factorisation on.
        self.scaled: ScaledStiffness | None = None

    def _reuse(self, on: bool, G: float) -> None:
        """Solve by CG on the kept factorisation (on) or by a new one (off), K(G) scaled.

        A reused factorisation's solves take K(G) as their operator, apart from the
        matrix factorised (the SNES's preconditioner matrix, then unchanged: PETSc's
        PCSetUp keeps its LU factors). K(G) is :class:`ScaledStiffness`'s where it holds
        G, else dolfinx's assembly.
        """
        snes, A = self.solver.snes, self.solver.problem.A
        scaled = self.scaled
        if scaled is not None and scaled.holds(G):
            scaled.shear_modulus = G
            snes.setJacobian(scaled, scaled.operator if on else A, A)
        else:
            snes.setJacobian(self.solver.jacobian, A, A)
        ksp = snes.getKSP()
        if on:
            ksp.setType("cg")
            ksp.setTolerances(rtol=REUSE_RTOL, atol=0.0, max_it=REUSE_MAX_IT)
        else:
            ksp.setType("preonly")

    def set_shear_modulus(self, body: str, shear_modulus: float) -> None:
        """Change the shear modulus of a body, keeping its Poisson's ratio."""
        b = self.model.body(body)
        λ, μ = forms.lame_from_shear(shear_modulus, b.spec.material.poisson)
        b.λ.value = λ
        b.μ.value = μ

    def __call__(self) -> float:
        """Solve and return K = H / ū (N/m per metre) for the current moduli."""
        for f in self.u:
            f.x.array[:] = 0.0
        self.solver.solve()
        mean = self.model.assemble(self._moment) / self.force  # mass-weighted mean u·e
        if not mean > 0:
            raise CalibrationError(f"structure '{self.structure.spec.name}' does not move "
                                   "with the load (is it fixed?)")
        return self.force / mean

    def stiffness(self, body: str, shear_modulus: float) -> float:
        """K with the shear modulus of ``body`` set to ``shear_modulus``.

        By CG on the last factorisation where ``shear_modulus`` is within
        :data:`REUSE_RATIO` of its G (the module doc); else, or where CG fails, by a
        new factorisation, kept.
        """
        self.set_shear_modulus(body, shear_modulus)
        G0 = self.factorised_at
        if G0 is not None and abs(math.log(shear_modulus / G0)) <= math.log(REUSE_RATIO):
            self._reuse(True, shear_modulus)
            try:
                K = self()
            except (ConvergenceError, PETSc.Error):
                pass
            else:
                self.reused += 1
                return K
        self._reuse(False, shear_modulus)
        K = self()
        self.factorised_at = shear_modulus
        if self.scaled is None or not self.scaled.holds(shear_modulus):
            # The matrix just factorised is K(G): it and K_b(G) give K at other G.
            if self.scaled is not None:
                self.scaled.destroy()
            self.scaled = ScaledStiffness(self.solver, shear_modulus,
                                           lambda G: self.set_shear_modulus(body, G))
        return K

    def destroy(self) -> None:
        """Free the solver's PETSc objects (their MPI communicators are a finite resource)."""
        self.solver.destroy()
        if self.scaled is not None:
            self.scaled.destroy()


class ScaledStiffness:
    """K(G) = K(G₀) + (G/G₀ − 1) K_b(G₀): the calibration's matrix at any G, unassembled.

    The calibrated body's λ and μ are proportional to G at its fixed Poisson's ratio, so
    its cell integrals K_b scale with G; the other bodies' and the interfaces' springs do
    not depend on it. K_b(G₀) = K(G₀) − K(0), K(0) assembled once with that body's λ and
    μ at 0: the body's cell integrals alone (they couple only its own unknowns; the
    Dirichlet rows' unit diagonal cancels). Where its rows meet an interface's springs the
    difference carries their round-off (about 1e-16 of the spring). K(G) is then a copy
    and a sum of matrices of one pattern, in place of an assembly of every cell:
    ``goda3d``'s 27-node hexahedra took 8–9 s an assembly at ``mesh.refinement = 1.5``
    and 18 s at 2 (2026-11-28), most of a solve on a kept factorisation.

    Used as the SNES Jacobian callback ``(snes, x, J, P)``: K(G) into J.

    Args:
        solver: The calibration's Newton solver; its matrix holds K(G₀) (factorised).
        shear_modulus: G₀.
        set_shear_modulus: Sets the calibrated body's G (its λ, μ Constants).

    """

    #: G is taken within this factor of G₀ (the cancellation in K(G₀) − (1 − G/G₀) K_b
    #: costs a factor G₀/G of the round-off).
    RATIO = 100.0

    def __init__(self, solver: NewtonSolver, shear_modulus: float,
                 set_shear_modulus: Callable[[float], None]) -> None:
        A = solver.problem.A
        self.G0 = self.shear_modulus = shear_modulus
        self._K0 = A.copy()
        #: The operator of a reused factorisation's solves (A's pattern); K(0) first.
        self.operator = A.duplicate()
        self.operator.setLGMap(*A.getLGMap())
        set_shear_modulus(0.0)
        try:
            solver.jacobian.assemble_whole(self.operator)
        finally:
            set_shear_modulus(shear_modulus)
        self._Kb = A.copy()
        self._Kb.axpy(-1.0, self.operator, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)

    def holds(self, shear_modulus: float) -> bool:
        """Whether K at ``shear_modulus`` is taken from K(G₀) (within :attr:`RATIO`)."""
        return abs(math.log(shear_modulus / self.G0)) <= math.log(self.RATIO)

    def __call__(self, snes: PETSc.SNES, x: PETSc.Vec, J: PETSc.Mat, P: PETSc.Mat) -> None:
        """K at :attr:`shear_modulus` into J.

        J is :attr:`operator` in a reused factorisation's solves (P, the matrix
        factorised, is then left as it is), else the matrix to factorise.
        """
        same = PETSc.Mat.Structure.SAME_NONZERO_PATTERN
        self._K0.copy(J, structure=same)  # type: ignore[arg-type]
        J.axpy(self.shear_modulus / self.G0 - 1.0, self._Kb, structure=same)  # type: ignore[arg-type]

    def destroy(self) -> None:
        """Free the matrices."""
        for M in (self._K0, self._Kb, self.operator):
            M.destroy()


def calibrate_shear_modulus(model: ContactModel, body: str, structure: str, target: float,
                            tolerance: float = 1e-4, initial_guess: float | None = None,
                            tangential_penalty: float = 1e3,
                            max_iterations: int = 30) -> CalibrationResult:
    """Find the shear modulus of ``body`` giving ``structure`` the stiffness ``target``.

    Secant iterations on ``log K`` against ``log G``: K is about proportional to G, so
    the first step (scaling G by target/K) is already close and the secant
    converges superlinearly.

    Args:
        model: Contact model (see :class:`HorizontalStiffness`).
        body: Body whose shear modulus is sought (its Poisson's ratio is kept).
        structure: Body whose horizontal stiffness is matched.
        target: Target stiffness, N/m per metre out of plane (plane strain).
        tolerance: Relative tolerance on K.
        initial_guess: First G (Pa); the body's current modulus if None.
        tangential_penalty: k_t / ε_n of the bonded interfaces.
        max_iterations: Largest number of stiffness solves.

    Returns:
        The calibrated modulus and the stiffness check.

    Raises:
        CalibrationError: The target is out of reach or the iterations did not
            converge.

    """
    if not (target > 0 and math.isfinite(target)):
        raise CalibrationError(f"target stiffness must be > 0 (got {target})")
    if not tolerance > 0:
        raise CalibrationError(f"calibration tolerance must be > 0 (got {tolerance})")
    problem = HorizontalStiffness(model, structure, tangential_penalty)
    G = float(model.body(body).spec.material.G if initial_guess is None else initial_guess)
    history: list[tuple[float, float]] = []
    phase = SlowPhase(logging.getLogger("breakwater.statics.calibrate"),
                      f"calibrating the shear modulus of '{body}'")

    def solve(G: float) -> float:
        try:
            K = problem.stiffness(body, G)
        except ConvergenceError as e:
            raise CalibrationError(f"stiffness solve failed at G = {G:.4g} Pa: {e}") from e
        history.append((G, K))
        phase("solve %d, G = %.6g Pa: K = %.6g N/m (target %.6g)", len(history), G, K, target)
        return K

    try:
        K = solve(G)
        G_next = G * target / K
        for _ in range(max_iterations - 1):
            if abs(K - target) <= tolerance * target:
                break
            if not (math.isfinite(G_next) and G_next > 0):
                break
            G_prev, K_prev = G, K
            G, K = G_next, solve(G_next)
            dlogK = math.log(K) - math.log(K_prev)
            if abs(dlogK) < 1e-14:
                break  # K no longer depends on G: saturated
            slope = dlogK / (math.log(G) - math.log(G_prev))
            if slope <= 0.02:
                raise CalibrationError(
                    f"the stiffness of '{structure}' no longer grows with the shear modulus "
                    f"of '{body}' (K = {K:.4g} N/m at G = {G:.4g} Pa): target {target:.4g} "
                    "N/m is out of reach (structure or interface too soft)")
            # Bound the step: at most a factor 100 on G per iteration.
            step = min(max((math.log(target) - math.log(K)) / slope, -math.log(100.0)),
                       math.log(100.0))
            G_next = G * math.exp(step)
    finally:
        problem.destroy()
    error = abs(K - target) / target
    if error > tolerance:
        raise CalibrationError(f"calibration of '{body}' did not converge: K = {K:.6g} N/m "
                               f"at G = {G:.6g} Pa, target {target:.6g} N/m "
                               f"(relative error {error:.2e} > {tolerance:.1e})")
    return CalibrationResult(body, structure, G, K, target, error, len(history),
                             tuple(history))
