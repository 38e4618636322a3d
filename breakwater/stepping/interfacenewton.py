"""The Newton of a fast GN22 step on the contact-surface unknowns.

With the bulk eliminated (:mod:`breakwater.stepping.condensed`), the step's residual on
the interface unknowns y = Δa_I is ``F(y) = S (y − z_I) + f_c(y)``. The Newton solves
the equivalent ``G(y) = X_II F = y − z_I + X_II f_c(y) = 0`` (Jacobian
``1 + X_II ∂f_c/∂y``) and its convergence test reads the force ‖F‖ = ‖S G‖, with the
tests and the round-off floor of the reference Newton
(:func:`~breakwater.stepping.solver.convergence_reason`).

It is the iteration of the reference path's PETSc SNES (``newtonls`` with the ``basic``
line search and the slip guards as its pre-check) written out, so that a step makes no
Python callback per iteration from PETSc: per iteration, the contact forces and their
Jacobian from the providers (compiled kernels for the conforming pairs,
:mod:`breakwater.contact.nodalkernels`), a dense LU solve (LAPACK: of the conforming
pairs' closed nodes' jumps, :mod:`breakwater.stepping.jumpsystem`; of the unknowns the
contact couples, or of all n_I) and the guards. Every rank solves the same small system
from the same data, so every rank takes the same decisions; there is no communication
inside the iteration unless a provider needs it (the general pairs' state).

Two rescues the SNES does not have. Where a general pair has friction, a solve that does
not converge is done again by stages of a larger regularisation χ down to the law's own
(:mod:`breakwater.stepping.continuation`): a stick/slip boundary on a slave surface finer
than its master made Newton cycle. If that fails too, or without friction, it is done
again from its start with every step that would multiply the residual by more than
:data:`GROWTH` halved, up to :data:`HALVINGS` times
(:func:`damped_step`), before the step is cut back. A contact or stick/slip
change inside a step makes the full step overshoot by orders of magnitude: on a caisson
meshed apart from its mound, sliding under a storm wave with adaptive steps, Newton
cycled between such overshoots for 40 iterations at every step size down to the smallest
and the run failed (2.2e3 → 1.2e5 → ... → 24 after 40 iterations; since the slip guard
lands slips on the friction law's curve, :mod:`breakwater.contact.guardkernels`, that
step converges without the rescue). The halving is not the
first try: a penalty's first step into contact raises the residual by ε_n times the
compliance, and halving it creeps towards the contact instead of the two iterations a
full step takes; as a rescue it leaves every solve that converges as it was.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np
from petsc4py import PETSc

from breakwater.common.arrays import read_only
from breakwater.common.errors import ConvergenceError
from breakwater.common.jit import kernel
from breakwater.common.timings import Timings
from breakwater.contact.coupling import BulkStiffness
from breakwater.stepping import continuation
from breakwater.stepping.factorisations import Factorisation
from breakwater.stepping.interface import ContactSum
from breakwater.stepping.jumpsystem import JumpSystem
from breakwater.stepping.reach import NearFactors, Reach
from breakwater.stepping.solver import NewtonOptions, convergence_reason

__all__ = ["CYCLE_MAX", "CYCLE_REPEATS", "CYCLE_RTOL", "GROWTH", "HALVINGS", "RESOLVED",
           "Columns", "InterfaceNewton", "RoundOff", "active_step", "active_system", "cycle",
           "damped_step", "kept_columns", "primal_system", "transposed_rows"]

_R = PETSc.SNES.ConvergedReason

#: In a rescue, a step whose residual ‖F‖ would exceed this multiple of the last is
#: halved. Not 1 (a monotone search): the guards' landings and the friction law's
#: stick tangent raise ‖F‖ by a few times on the way to convergence, and a monotone
#: search stalled on the storm above (halving every step, the residual creeping up)
#: where 10 and 100 converge.
GROWTH = 10.0
#: At most this many halvings per step; the last is taken whatever its residual.
HALVINGS = 5
#: Newton's residuals that repeat to this relative difference...
CYCLE_RTOL = 1e-6
#: ... this many in a row, with a period of at most
CYCLE_MAX = 16
#: iterations, are a cycle (:func:`cycle`): the solve has failed.
CYCLE_REPEATS = 3
#: A residual below this multiple of ``atol`` (or below the floor) is compared with its
#: round-off (:meth:`InterfaceNewton._test`, :class:`RoundOff`).
RESOLVED = 10.0


class InterfaceNewton:
    """Newton on the n_I interface unknowns of a step.

    Args:
        n: Number of interface unknowns.
        contact: f_c, its Jacobian and the slip guards on them.
        name: Names the solver in its errors.
        options: Convergence settings.
        force_scale: Force norm that scales ``options.atol``.
        timings: Where the Newton is timed (``newton``: all but the contact
            evaluations, timed by ``contact`` under ``interface_assembly``).
        guarded: Whether the providers' slip guards cut Newton's steps.

    Attributes:
        floor_accepts: Solves accepted at their round-off floor.
        continuations: Solves that converged only by a continuation in the friction's
            regularisation (:mod:`breakwater.stepping.continuation`), the first rescue.
        rescues: Solves done again with the overshooting steps halved (the second).
        halvings: Newton steps halved in them (:data:`GROWTH`).
        flips: Nodes whose slip reversal the guards cut, over the solves.
        y: The converged iterate after :meth:`solve`.
        fc: f_c at the last residual evaluation (at the solution after :meth:`solve`).
        F: The residual force ``S G`` there (its norm is the one the test read).
        reach: The solves on the unknowns the contact may reach.
        support: The unknowns outside which the last solve's f_c and F are zero (None:
            any).
    """

    def __init__(self, n: int, contact: ContactSum, name: str, options: NewtonOptions,
                 force_scale: float, timings: Timings, guarded: bool = True) -> None:
        self.options = options
        self.contact, self.name, self.timings = contact, name, timings
        self.atol = options.atol * force_scale
        self.floor = options.floor_atol * force_scale
        self.guarded = guarded
        self.floor_accepts = self.rescues = self.halvings = self.flips = self.continuations = 0
        self.y, self.fc, self.F = np.zeros(n), np.zeros(n), np.zeros(n)
        self._columns_of: Columns | None = None
        self._jumps = JumpSystem()
        # The last evaluation (X_II, S, z_I, y, f_c(y)), for its round-off.
        self._last: tuple[np.ndarray, ...] | None = None
        self.round_off = RoundOff()
        self.reach = Reach()
        self.support: np.ndarray | None = None

    def solve(self, fact: Factorisation, z_I: np.ndarray, y0: np.ndarray, w_I: np.ndarray,
              w_norm2: float, v_pred: np.ndarray, dv_dx: float) -> int:
        """Solve ``G(y) = 0`` from y0; return the iterations.

        Args:
            fact: The step size's factorisation (X_II and S).
            z_I: z = A⁻¹ r₀ at the interface unknowns.
            y0: Newton's start.
            w_I: The bulk rows' residual at Newton's start, w = A Δa₀ − r₀, at the
                interface unknowns.
            w_norm2: ‖w‖² (for ‖F₀‖ of the relative test).
            v_pred: The predictor's velocities ṽ at the interface unknowns (the
                iterate's are ``ṽ + dv_dx y``: the guards').
            dv_dx: β₁Δt.

        Where the providers say which unknowns the step's contact may touch
        (:meth:`ContactSum.reach`), it is solved on those (:mod:`breakwater.stepping.reach`),
        and on all of them if it touches another.

        Raises:
            ConvergenceError: Newton did not converge (its reason, iterations and ‖F‖).
        """
        near = self.contact.reach()
        if near is not None and len(near) < len(y0):
            its = self.reach.solve(self, fact, near, z_I, y0, w_I, w_norm2, v_pred, dv_dx)
            if its is not None:
                return its
        self.support = None
        return self._solve(fact, z_I, y0, w_I, w_norm2, v_pred, dv_dx)

    def _solve(self, fact: Factorisation | NearFactors, z_I: np.ndarray, y0: np.ndarray,
               w_I: np.ndarray, w_norm2: float, v_pred: np.ndarray, dv_dx: float) -> int:
        """:meth:`solve` on the unknowns of ``fact`` (its X_II and S)."""
        T = self.timings
        assembly = T.seconds["interface_assembly"]
        t0 = time.perf_counter()
        try:
            def iterate(y: np.ndarray, damped: bool = False
                        ) -> tuple[int, list[float], tuple[np.ndarray, ...]]:
                return self._iterate(fact, z_I, y, w_I, w_norm2, v_pred, dv_dx, damped)

            reason, state, its, failure = _rescued(self, iterate, y0)
        finally:
            T.seconds["newton"] += time.perf_counter() - t0 - (
                T.seconds["interface_assembly"] - assembly)
        if reason <= 0:
            raise ConvergenceError(failure, reason, its)
        self.y, self.fc, self.F = state
        return its

    def _iterate(self, fact: Factorisation | NearFactors, z_I: np.ndarray, y0: np.ndarray,
                 w_I: np.ndarray, w_norm2: float, v_pred: np.ndarray, dv_dx: float,
                 damped: bool) -> tuple[int, list[float], tuple[np.ndarray, ...]]:
        """Newton's iterations from y0 (the arguments of :meth:`solve`).

        ``damped``: halve the overshooting steps (:func:`damped_step`).

        Returns:
            The convergence reason, the residual norms, and (y, f_c, F) at the last iterate.
        """
        X_II, S = fact.X_II, fact.S
        self.contact.true_law(crawl=not damped)  # the rescue: Newton without crawl points
        x = read_only(np.array(y0, dtype=float))  # each iterate read-only: its evaluations'
        fc, G, F = self._residual(x, X_II, S, z_I)  # caches know it by identity
        with np.errstate(over="ignore", invalid="ignore"):  # μ = 1e300: inf, a failure
            fnorm = float(np.linalg.norm(F))  # (not numpy's warnings, 4 lines per rank)
            # ‖F₀‖ of the relative test: the whole residual at Newton's start (as the
            # reference Newton's): ‖w‖² − ‖w_I‖² + ‖w_I + f_c(y₀)‖², w = A Δa₀ − r₀.
            whole = w_norm2 - w_I @ w_I + np.sum((w_I + fc) ** 2)
        norms = [math.sqrt(max(float(whole), fnorm**2))]
        reason, stalled = self._test(norms, 0.0, 0.0, x)
        while reason == _R.CONVERGED_ITERATING:
            try:
                δ = self._step(x, X_II, G)
            except np.linalg.LinAlgError:
                reason = int(_R.DIVERGED_LINEAR_SOLVE)
                break
            if self.guarded:
                self.flips += self.contact.precheck(x, δ, v_pred, dv_dx, BulkStiffness(S))
            x, δ, (fc, G, F), fnorm, halved = damped_step(
                lambda y: self._residual(y, X_II, S, z_I), x, δ,
                fnorm if damped else math.inf)
            self.halvings += halved
            norms.append(fnorm)
            reason, stalled = self._test(norms, float(np.linalg.norm(x)),
                                         float(np.linalg.norm(δ)), x)
            if reason == _R.CONVERGED_ITERATING and cycle(
                    norms, max(self.floor, RESOLVED * self.atol)):
                reason = int(_R.DIVERGED_MAX_IT)  # going round: the rest would too
            if reason > 0 and self.contact.true_law(not damped):  # on tangent lines: the law
                fc, G, F = self._residual(x, X_II, S, z_I)
                norms[-1] = fnorm = float(np.linalg.norm(F))
                reason, stalled = self._test(norms, float(np.linalg.norm(x)),
                                             float(np.linalg.norm(δ)), x)
        self.floor_accepts += stalled
        return reason, norms, (x, fc, F)

    def _step(self, x: np.ndarray, X_II: np.ndarray, G: np.ndarray) -> np.ndarray:
        """Newton's step δ: ``(1 + X_II ∂f_c/∂y) δ = G``.

        On the conforming pairs' jumps (:mod:`~breakwater.stepping.jumpsystem`), else on
        the unknowns ∂f_c/∂y couples (:func:`active_step`), else the whole matrix.

        Raises:
            np.linalg.LinAlgError: A singular system.
        """
        jumps = self.contact.jump_jacobian(x)
        if jumps is not None:
            return self._jumps.step(X_II, G, *jumps)
        active = self.contact.active_jacobian(x)
        if active is None:
            J = self.contact.left_jacobian(x, X_II)
            J.flat[:: len(J) + 1] += 1.0
            return np.linalg.solve(J, G)
        act, B = active
        if not len(act):
            return G.copy()
        primal = self.contact.primal
        self._columns_of = key = kept_columns(self._columns_of, X_II, act, primal)
        return active_step(act, B, key[2], G, primal, key[3])

    def _residual(self, y: np.ndarray, X_II: np.ndarray, S: np.ndarray, z_I: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """f_c(y), G(y) = y − z_I + X_II f_c(y) and the force F = S G.

        G has the root of F = S (y − z_I) + f_c without S's large entries of both
        signs, whose products carry n_I · |S| |y| of round-off into F and stalled
        Newton above its tolerance (35 of the 1500 Goda steps were accepted at the
        round-off floor, none with G).
        """
        fc = self.contact.vector(y)
        G = y - z_I + X_II @ fc
        self._last = (X_II, S, z_I, y, fc)
        return fc, G, S @ G

    def _test(self, norms: list[float], xnorm: float, ynorm: float, x: np.ndarray
              ) -> tuple[int, bool]:
        """The reference Newton's test, its absolute tolerance raised to F's round-off.

        A residual below ``floor`` (or :data:`RESOLVED` atol) is compared with the
        providers' round-off of f_c at x (:meth:`ContactSum.resolution`: 1e-5 N/m on the
        separately meshed Goda caisson rocking on its corner, where ``atol`` is 7e-8),
        then with that of forming F = S G (:class:`RoundOff`): below them it carries no
        more information and the step converged, by the test.
        """
        o = self.options
        atol = self.atol
        if self.atol <= norms[-1] < max(self.floor, RESOLVED * self.atol):
            atol = max(atol, self.contact.resolution(x))
            last = self._last
            if atol <= norms[-1] and last is not None and last[3] is x:
                atol = max(atol, self.round_off(*last))
        return convergence_reason(norms, xnorm, ynorm, rtol=o.rtol, atol=atol,
                                  stol=o.stol, max_it=o.max_it, floor=self.floor,
                                  stall_its=o.stall_its)


def _rescued(newton: InterfaceNewton, iterate: Callable[..., tuple[int, list[float], tuple[
        np.ndarray, ...]]], y0: np.ndarray
             ) -> tuple[int, tuple[np.ndarray, ...], int, str]:
    """:meth:`InterfaceNewton._solve`'s tries: Newton, then its two rescues (module doc).

    Args:
        newton: Its counters (``continuations``, ``rescues``) are updated.
        iterate: Newton from a start (``damped``: its overshooting steps halved).
        y0: The start.

    Returns:
        The last try's reason and (y, f_c, F), the iterations of all tries, and
        what each try did (the error's message where none converged).
    """
    reason, norms, state = iterate(y0)
    its = len(norms) - 1
    period = cycle(norms, 0.0)
    failure = (f"{newton.name}: Newton did not converge (SNES reason {reason}, {its} "
               f"iterations, residual {norms[-1]:.3e}"
               + (f", in a cycle of {period} iterates)" if period else ")"))
    if reason <= 0 and newton.contact.regularise(1.0):  # by stages of larger χ
        reason, norms, state, stages = continuation.solve(iterate, newton.contact, y0)
        newton.continuations += reason > 0
        its += stages.iterations
        failure += (f"; again by a continuation in the friction's regularisation: "
                    f"{stages.describe()}, residual {norms[-1]:.3e}")
    if reason <= 0:  # again from y0, its overshooting steps halved
        reason, norms, state = iterate(y0, True)
        newton.rescues += reason > 0  # the solves that converged only so
        its += len(norms) - 1
        failure += (f"; again with its overshooting steps halved: {len(norms) - 1} "
                    f"iterations, residual {norms[-1]:.3e}")
    return reason, state, its, failure


def cycle(norms: list[float], floor: float) -> int:
    """The period of a cycle that Newton's last residuals go round (0: none).

    The last :data:`CYCLE_REPEATS` residuals each equal to the one p iterations before to
    :data:`CYCLE_RTOL` (p from 2 to :data:`CYCLE_MAX`), above ``floor`` (near the
    round-off floor residuals repeat without a cycle, and the stall test decides). The
    iterates of a Newton with the slip guards are a function of the last one: a
    residual that repeats so is the same iterate, and the iterations to ``max_it``
    would go round again (a stick/slip cycle of ten iterates, 40 iterations,
    :mod:`breakwater.stepping.continuation`).

    Args:
        norms: The residual norms, iteration 0 first (its ‖F₀‖ is the whole residual's,
            not compared).
        floor: Residuals below this are not tested.
    """
    n = len(norms) - 1
    if not n or norms[-1] < floor:
        return 0
    for p in range(2, min(CYCLE_MAX, n - CYCLE_REPEATS) + 1):
        if all(abs(norms[-1 - i] - norms[-1 - i - p]) <= CYCLE_RTOL * norms[-1 - i]
               for i in range(CYCLE_REPEATS)):
            return p
    return 0


class RoundOff:
    """The round-off of the interface Newton's residual F = S G.

    Each term of ``G = y − z_I + X_II f_c`` carries ε of its magnitude, and S multiplies
    them: ``ε ‖ |S| (|y| + |z_I| + |X_II| |f_c|) ‖``. S holds large entries of both signs
    where the interface is stiff against the step's mass: in the static relaxation's
    long pseudo steps (whose floor is atol itself) 4.4e-7 N/m against an atol of 6.9e-8
    on the separately meshed Goda caisson, whose first frictionless step hovered between
    6e-8 and 1e-7 N/m for nine iterations until round-off fell below atol by chance (on
    a mesh where it did not, the stage would have failed); in a time step, 1e-9 N/m.
    """

    def __init__(self) -> None:
        self._magnitudes: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def __call__(self, *last: np.ndarray) -> float:
        """The estimate at an evaluation ``(X_II, S, z_I, y, f_c(y))``."""
        X_II, S, z_I, y, fc = last
        m = self._magnitudes
        if m is None or m[0] is not X_II:  # |X_II|, |S| kept while the system stays
            self._magnitudes = m = (X_II, np.abs(X_II), np.abs(S))
        eps = float(np.finfo(float).eps)
        return eps * float(np.linalg.norm(m[2] @ (np.abs(y) + np.abs(z_I) + m[1] @ np.abs(fc))))


Columns = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]
"""X_II, act, X_II's columns act and, for the primal system, their rows act transposed."""


def kept_columns(kept: Columns | None, X_II: np.ndarray, act: np.ndarray, primal: bool
                 ) -> Columns:
    """:data:`Columns` of X_II and act: ``kept`` while they stay (a step's iterations)."""
    if kept is not None and kept[0] is X_II and np.array_equal(kept[1], act):
        return kept
    X_act = np.ascontiguousarray(X_II[:, act])
    return X_II, act, X_act, transposed_rows(X_act, act) if primal else None


def active_step(act: np.ndarray, B: np.ndarray, X_act: np.ndarray, G: np.ndarray,
                primal: bool, X_aa_t: np.ndarray | None = None) -> np.ndarray:
    """Newton's step where ∂f_c/∂y is B on the rows and columns ``act`` alone.

    ``act``: a conforming pair's closed nodes; a general pair's points in contact and
    their master facets, a fraction of a master surface that may be long; of them,
    those B couples (:func:`~breakwater.stepping.interface.coupled`). The system is solved
    on them alone, a dense solve of size |act| instead of n_I: for δ_act itself where
    every provider is a conforming pair (``primal``, :func:`primal_system`), else for
    the forces w = B δ_act: ``(1 + B X_act,act) w = B G_act`` and
    ``δ = G − X_II[:, act] w``.

    Args:
        act: The unknowns.
        B: ∂f_c/∂y there.
        X_act: X_II's columns act.
        G: The Newton's residual.
        primal: Solve for δ_act.
        X_aa_t: For ``primal``, X_act's rows act transposed (:func:`transposed_rows`;
            None: formed here).
    """
    if primal:
        # (1 + X_II ∂f_c/∂y) δ = G itself (the conforming pairs' Newton), whose columns
        # outside act are the identity's: (1 + X_act,act B) δ_act = G_act, and the other
        # rows by substitution.
        if X_aa_t is None:
            X_aa_t = transposed_rows(X_act, act)
        δ_act = np.linalg.solve(primal_system(B, X_aa_t).T, G[act])
        δ = G - X_act @ (B @ δ_act)
        δ[act] = δ_act
        return δ
    # For the forces (solving for δ_act and forming B δ_act instead multiplies its
    # round-off by B's stick and penalty tangents, 1e12: an impact's Newton diverged).
    return G - X_act @ np.linalg.solve(active_system(B, X_act, act), B @ G[act])


@kernel
def primal_system(B, X_aa_t):  # type: ignore[no-untyped-def]
    """``1 + X_act[act] B``, transposed, from B's nonzero entries (compiled).

    The primal system of :meth:`InterfaceNewton._step` (the conforming pairs): the
    restriction to the closed nodes of ``1 + X_II ∂f_c/∂y``, which the Newton solved
    whole before (the same iterations to 0.3 %: 5181 against 5175 on the default Goda
    case; the force form of :func:`active_system` took 1.5 % more). Formed transposed
    from X_act[act]'s transpose ``X_aa_t`` (:func:`transposed_rows`), so that every
    loop runs along rows: each entry is the same sum in the same order as the product
    formed directly, whose column-wise reads of X took 0.24 s per Newton iteration on
    the 3108 closed unknowns of ``goda3d`` at ``mesh.refinement = 2`` (2026-11-28).

    Args:
        B: ∂f_c/∂y on the unknowns act, shape (m, m).
        X_aa_t: ``X_act[act].T``, shape (m, m).

    Returns:
        The system's transpose.
    """
    m = B.shape[0]
    JT = np.zeros((m, m))
    for k in range(m):
        for j in range(m):
            b = B[k, j]
            if b != 0.0:
                for i in range(m):
                    JT[j, i] += X_aa_t[k, i] * b
    for i in range(m):
        JT[i, i] += 1.0
    return JT


@kernel
def transposed_rows(X_act, act):  # type: ignore[no-untyped-def]
    """``X_act[act].T`` (compiled, by tiles of 64 × 64: 90 ms for 3108² against 0.7 s)."""
    m = len(act)
    out = np.empty((m, m))
    for i0 in range(0, m, 64):
        for k0 in range(0, m, 64):
            for i in range(i0, min(i0 + 64, m)):
                row = act[i]
                for k in range(k0, min(k0 + 64, m)):
                    out[k, i] = X_act[row, k]
    return out


@kernel
def active_system(B, X_act, act):  # type: ignore[no-untyped-def]
    """``1 + B X_act[act]`` from B's nonzero entries (compiled).

    B, a general pair's Jacobian on the unknowns it couples, has about a dozen nonzero
    entries in a row of 140 on the separately meshed Goda case (each point couples its
    slave facet's and master facet's nodes): the product visits those alone, a tenth of
    the dense product's work, which took half of that case's Newton time.

    Args:
        B: ∂f_c/∂y on ``act``, shape (m, m).
        X_act: X_II's columns ``act``, shape (n_I, m).
        act: The unknowns B couples.
    """
    m = len(act)
    J = np.zeros((m, m))
    for i in range(m):
        for k in range(m):
            b = B[i, k]
            if b != 0.0:
                row = act[k]
                for j in range(m):
                    J[i, j] += b * X_act[row, j]
        J[i, i] += 1.0
    return J


def damped_step(residual: Callable[[np.ndarray], tuple[np.ndarray, ...]], x: np.ndarray,
                δ: np.ndarray, last: float
                ) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, ...], float, int]:
    """The next iterate ``x − δ``, δ halved while ‖F‖ would exceed GROWTH × ``last``.

    Args:
        residual: (f_c, G, F) at an iterate.
        x: The iterate.
        δ: Newton's step.
        last: ‖F‖ at x (infinite: the full step).

    Returns:
        The next iterate, the step taken, (f_c, G, F) there, ‖F‖ and the halvings.
    """
    halvings = 0
    while True:
        trial = read_only(x - δ)
        r = residual(trial)
        fnorm = float(np.linalg.norm(r[2]))
        if fnorm <= GROWTH * last or halvings == HALVINGS:
            return trial, δ, r, fnorm, halvings
        δ = 0.5 * δ
        halvings += 1
