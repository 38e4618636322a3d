"""The interface Newton's rescue: a solve that fails is done again with its overshooting
steps halved (:class:`breakwater.stepping.interfacenewton.InterfaceNewton`).

The contact here is a made-up one-unknown law whose full Newton steps overshoot by
orders of magnitude and diverge, as a stick/slip or contact change inside a step does
(the storm case in the module's docstring, where Newton cycled between 1e2 and 2e5 for 40
iterations): the equation is G(y) = y − z + X f_c(y) = 0 with X = 1, z = 0 and
G(y) = y^(1/3) for y > 0, −K |y|^(1/3) for y < 0 (K = 1000). Newton maps y to −2y: the
iterates grow and the residual jumps K times at every other step. Halved while the
residual would grow more than GROWTH = 10 times, a step from y > 0 is quartered and
stays on the soft side: y/4 per iteration, the residual 4^(1/3) smaller.
"""

from __future__ import annotations

import numpy as np
import pytest

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater.common.errors import ConvergenceError
from breakwater.common.timings import Timings
from breakwater.stepping import interfacenewton
from breakwater.stepping.factorisations import Factorisation
from breakwater.stepping.interface import ContactSum
from breakwater.stepping.interfacenewton import InterfaceNewton
from breakwater.stepping.solver import NewtonOptions

K = 1000.0
FORCE_SCALE = 1e6  # atol = 1e-9 × 1e6 = 1e-3: |G| < 1e-3 is y < 1e-9


class CubeRootLaw:
    """f_c(y) = G(y) − y for G above (one unknown, no slip guard)."""

    def __init__(self, soft: float = 1.0, stiff: float = K) -> None:
        self.soft, self.stiff = soft, stiff

    def g(self, y: float) -> float:
        return float(np.cbrt(y) * (self.soft if y > 0 else self.stiff))

    def dg(self, y: float) -> float:
        return float((self.soft if y > 0 else self.stiff) / (3.0 * np.cbrt(y) ** 2))

    def begin(self) -> None:
        pass

    def end(self) -> None:
        pass

    def add_vector(self, y: np.ndarray, out: np.ndarray) -> None:
        out[0] += self.g(y[0]) - y[0]

    def add_left_product(self, y: np.ndarray, X: np.ndarray, out: np.ndarray) -> bool:
        return False

    def matrix(self, y: np.ndarray) -> np.ndarray:
        return np.array([[self.dg(y[0]) - 1.0]])

    def resolution(self, y: np.ndarray) -> float:
        return 0.0

    def active_jacobian(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        return None

    def precheck(self, x: np.ndarray, step: np.ndarray, v_pred: np.ndarray,
                 dv_dx: float, bulk: object = None) -> int:
        return 0

    def true_law(self, crawl: bool = True) -> bool:
        return False

    def regularise(self, stretch: float) -> bool:
        return False


def _newton(law: CubeRootLaw) -> InterfaceNewton:
    timings = Timings()
    return InterfaceNewton(1, ContactSum(1, [law], timings), "test", NewtonOptions(),
                           FORCE_SCALE, timings)


def _solve(newton: InterfaceNewton, y0: float) -> int:
    one = np.ones((1, 1))
    fact = Factorisation(None, None, None, one, one)  # type: ignore[arg-type]
    zero = np.zeros(1)
    return newton.solve(fact, zero, np.array([y0]), zero, 0.0, zero, 1.0)


def test_a_diverging_newton_is_rescued_by_halving() -> None:
    newton = _newton(CubeRootLaw())
    its = _solve(newton, 1.0)
    # The first try fails at max_it (40 iterations), the rescue converges: |y| < 1e-9
    # (|G| < atol) after log(1e9)/log(4) = 15 iterations, each step halved twice.
    assert newton.rescues == 1
    assert its > NewtonOptions().max_it
    rescue = its - NewtonOptions().max_it
    assert 14 <= rescue <= 16 and newton.halvings == 2 * rescue
    assert 0 < newton.y[0] < 1e-9
    assert abs(CubeRootLaw().g(newton.y[0])) < NewtonOptions().atol * FORCE_SCALE


def test_a_converging_newton_takes_full_steps() -> None:
    # Equal sides (K = 1: G = y^(1/3)) would still diverge; a linear law converges in
    # one full step, and nothing is halved or done again.
    class Linear(CubeRootLaw):
        def g(self, y: float) -> float:
            return 3.0 * y

        def dg(self, y: float) -> float:
            return 3.0

    newton = _newton(Linear())
    assert _solve(newton, 1.0) == 1
    assert newton.rescues == 0 and newton.halvings == 0 and newton.y[0] == 0.0


def test_a_solve_converged_on_tangent_lines_is_tested_on_the_law() -> None:
    # A provider whose guard, twice, sets a tangent line that is not the
    # law (a general pair's crawl point far from the solution, guardkernels): with it
    # G = 3y − 1, zero at y = 1/3; the law's G = 3y − 2, zero at y = 2/3. The solve
    # converges on the line in one step; tested again on the law it is not converged,
    # and one more step reaches the law's root.
    class Line(CubeRootLaw):
        def __init__(self) -> None:
            super().__init__()
            self.lin, self.guarded, self.dropped = False, 0, 0

        def g(self, y: float) -> float:
            return 3.0 * y - (1.0 if self.lin else 2.0)

        def dg(self, y: float) -> float:
            return 3.0

        def precheck(self, x: np.ndarray, step: np.ndarray, v_pred: np.ndarray,
                     dv_dx: float, bulk: object = None) -> int:
            self.guarded += 1
            self.lin = self.guarded <= 2  # for the next two iterates
            return 0

        def true_law(self, crawl: bool = True) -> bool:
            was, self.lin = self.lin, False
            self.dropped += was
            return was

    law = Line()
    newton = _newton(law)
    # Iterates: 0 → 2/3 (the law's root, the line's residual 1) → 1/3 (the line's root)
    # → 2/3 on the law.
    assert _solve(newton, 0.0) == 3
    assert law.dropped == 1 and not law.lin
    assert abs(newton.y[0] - 2.0 / 3.0) < 1e-15
    assert abs(law.g(newton.y[0])) < NewtonOptions().atol * FORCE_SCALE


def test_a_residual_at_its_round_off_is_converged() -> None:
    # F = S G with S = 2e7, X_II = 1/S (an interface stiff against the step's mass, as
    # in the static relaxation's long pseudo steps) and G = y − z + X f_c, where
    # z ≈ 1.5e6 and X f_c = z + y* − 2y nearly cancel (root y* < 1): G is known to one
    # unit in the last place of 1.5e6, 2.3e-10, and F to 0.005 — 5 × atol (1e-3), with
    # the floor at atol (the relaxation's). The test compares the residual with
    # ε ‖|S| (|y| + |z| + |X| |f_c|)‖ (InterfaceNewton._round_off): every one of 40
    # such solves converges in one iteration; without the comparison, 9 of them iterate
    # on round-off to max_it and fail (measured), others converge when round-off
    # happens to give F = 0.
    class Stiff(CubeRootLaw):
        def __init__(self, a: float) -> None:
            super().__init__()
            self.a = a

        def add_vector(self, y: np.ndarray, out: np.ndarray) -> None:
            out[0] += self.a - 4e7 * y[0]

        def matrix(self, y: np.ndarray) -> np.ndarray:
            return np.array([[-4e7]])

    options = NewtonOptions(floor_atol=NewtonOptions().atol)
    fact = Factorisation(None, None, None, np.full((1, 1), 5e-8),  # type: ignore[arg-type]
                         np.full((1, 1), 2e7))
    rng = np.random.default_rng(0)
    at_round_off = 0
    for _ in range(40):
        z, root = 1e6 * (1 + rng.random()), rng.random()
        law = Stiff((z + root) / 5e-8)
        timings = Timings()
        newton = InterfaceNewton(1, ContactSum(1, [law], timings), "test", options,
                                 FORCE_SCALE, timings)
        y0 = root + 0.01
        fc0 = law.a - 4e7 * y0  # the bulk rows balanced at the start: ‖F₀‖ = S |G(y0)|
        its = newton.solve(fact, np.array([z]), np.array([y0]), np.array([-fc0]), fc0 * fc0,
                           np.zeros(1), 1.0)
        assert its == 1 and newton.floor_accepts == 0
        assert abs(newton.y[0] - root) < 1e-9
        at_round_off += abs(newton.F[0]) >= options.atol * FORCE_SCALE
    assert at_round_off >= 5  # accepted above atol, at round-off


def test_a_failed_rescue_reports_both_tries(monkeypatch: pytest.MonkeyPatch) -> None:
    newton = _newton(CubeRootLaw())
    monkeypatch.setattr(interfacenewton, "HALVINGS", 0)  # the rescue: the plain Newton again
    with pytest.raises(ConvergenceError, match=r"test: Newton did not converge \(SNES reason "
                       r"-?\d+, \d+ iterations, residual .*\); again with its overshooting "
                       r"steps halved: \d+ iterations, residual"):
        _solve(newton, 1.0)
    # The summary's newton_rescues counts the solves that converged only when done
    # again: this one did not (it counted the retry; the report then said one solve
    # converged so, of a run that failed).
    assert newton.rescues == 0


def test_the_report_says_what_the_solver_did() -> None:
    # The run's report (outputs.summary.format_report) names the rescues and an X that
    # did not fit in memory, from the summary's solver entry; silent when neither happened.
    from breakwater.outputs.summary import format_report

    solver = {"kind": "fast", "steps": 10, "newton_iterations": 30, "cutbacks": 0,
              "wall_time": 1.0, "time_loop": {"wall": 0.5}, "newton_rescues": 2,
              "newton_halvings": 7, "elimination": {"X": "interface rows only", "chunks": 39}}
    text = format_report({"solver": solver}, "out")
    assert "2 Newton solves converged only when done again with their overshooting " \
           "steps halved (7 halvings)" in text
    assert "its interface rows built in 39 chunks, a second back-solve per step" in text
    quiet = format_report({"solver": {**solver, "newton_rescues": 0,
                                      "elimination": {"X": "kept", "chunks": 0}}}, "out")
    assert "halved" not in quiet and "chunks" not in quiet


class SignLaw(CubeRootLaw):
    """A stick/slip law: G(y) = y + a φ(y) − b, φ(y) = y / sqrt(y² + χ²), a > b > 0.

    A spring against a regularised friction force of a = 1 pulled by b = 0.5: it sticks,
    at y* = χ b / sqrt(a² − b²) (φ(y*) = b/a). From y₀ = 1 ≫ χ, φ' ≈ 0 and Newton maps y
    to b − a sign(y): the iterates go round −0.5, 1.5, −0.5, ... (|G| = 2, 2, ...), a cycle
    of two, as a stick/slip boundary's nodes do on a general pair
    (:mod:`breakwater.stepping.continuation`).
    """

    a, b, chi = 1.0, 0.5, 1e-3

    def __init__(self) -> None:
        super().__init__()
        self.stretch = 1.0
        self.stretches: list[float] = []

    def _chi(self) -> float:
        return self.chi * self.stretch

    def g(self, y: float) -> float:
        return y + self.a * y / np.hypot(y, self._chi()) - self.b

    def dg(self, y: float) -> float:
        return 1.0 + self.a * self._chi() ** 2 / np.hypot(y, self._chi()) ** 3

    def regularise(self, stretch: float) -> bool:
        self.stretch = stretch
        self.stretches.append(stretch)
        return True


def test_a_cycling_newton_is_stopped_and_continued_in_chi() -> None:
    from breakwater.stepping import continuation

    law = SignLaw()
    newton = _newton(law)  # type: ignore[arg-type]
    its = _solve(newton, 1.0)
    # The first try goes round the cycle of two, and stops after three repeats
    # (CYCLE_REPEATS) instead of at max_it.
    assert newton.continuations == 1 and newton.rescues == 0
    y_star = law.chi * law.b / np.sqrt(law.a**2 - law.b**2)
    # Converged on the law's own χ (stretch 1): |G| < atol = 1e-9 × FORCE_SCALE, and with
    # G' = 1 + (a/χ)(1 − (b/a)²)^1.5 ≈ 650 at y*, y within atol/G' of y* (2.7e-3 of y*).
    atol = NewtonOptions().atol * FORCE_SCALE
    assert abs(law.g(newton.y[0])) < atol
    assert abs(newton.y[0] - y_star) <= atol / law.dg(y_star)
    assert law.stretch == 1.0 and law.stretches[-1] == 1.0
    # From TOP χ (1e3: smooth at y ~ 1), down to 1 by stages ten times apart at most.
    tried = [s for s in law.stretches[1:-1] if s != 1.0]
    assert tried[0] == continuation.TOP and min(law.stretches) == 1.0
    ratios = np.array(tried[:-1]) / np.array(tried[1:])
    assert np.all(ratios <= continuation.DECADE * (1 + 1e-12))
    assert its < NewtonOptions().max_it + 30 * continuation.MAX_STAGES


def test_a_cycle_is_a_failure_named_so(monkeypatch: pytest.MonkeyPatch) -> None:
    from breakwater.stepping import continuation

    monkeypatch.setattr(continuation, "MAX_STAGES", 1)  # the continuation gives up
    monkeypatch.setattr(interfacenewton, "HALVINGS", 0)  # so does the halving
    newton = _newton(SignLaw())  # type: ignore[arg-type]
    with pytest.raises(ConvergenceError, match=r"test: Newton did not converge \(SNES reason "
                       r"-5, \d+ iterations, residual 2.000e\+00, in a cycle of 2 iterates\); "
                       r"again by a continuation in the friction's regularisation: "
                       r"1 stage from 1e\+04 χ "):
        _solve(newton, 1.0)
    assert newton.continuations == 0
    assert [interfacenewton.cycle([9.0, *x], 0.0) for x in (
        [2.0, 1.0] * 3, [2.0, 1.0] * 2, [3.0, 2.0, 1.0] * 3, [2.0, 1.0, 0.5, 0.25, 2.0, 1.0],
            [4.0, 2.0, 1.0, 0.5, 0.25, 0.125])] == [2, 0, 3, 0, 0]
    assert interfacenewton.cycle([9.0, *[2.0, 1.0] * 3], 1.5) == 0  # at the floor: stall test


def test_an_overflowing_residual_fails_without_numpy_warnings() -> None:
    # A general pair with μ = 1e300 (or ε_n = 1e300): f_c ~ 1e300, whose square
    # overflows in the residual's norm. The solve fails as a Newton that did not converge
    # (residual inf: one line); numpy's RuntimeWarnings ("overflow encountered in dot",
    # four lines on each rank under mpiexec) were printed before it.
    import warnings

    class Huge(CubeRootLaw):
        def g(self, y: float) -> float:
            return 1e300 * (1.0 + y * y)

        def dg(self, y: float) -> float:
            return 2e300 * y

    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        with pytest.raises(ConvergenceError, match=r"residual (inf|nan)"):
            _solve(_newton(Huge()), 1.0)
