"""Typed run configuration shared by the case layer and the run layer.

The run layer (:mod:`breakwater.run.simulation`) never reads TOML: it receives
these frozen dataclasses, built by the case layer (:mod:`breakwater.casefile.case`).
:class:`TimeSpec` is also the case's ``[time]`` table, documented and checked once.
"""

from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass
from typing import Literal

from breakwater.config.fields import InvalidField, column_name, positive, setting
from breakwater.config.frozen import assignment_hint
from breakwater.config.typecheck import check_fields

__all__ = ["MAX_CUTBACKS", "InitialSpec", "OutputSpec", "PairProbeSpec", "ProbeSpec",
           "TimeSpec"]

MAX_CUTBACKS = 20
"""Largest ``time.max_cutbacks``: Δt·2⁻²⁰ ≈ 1e-6 Δt (each cut-back retries a failing
step with a full Newton solve; 2000 of them ran for hours on one step)."""
DEFAULT_LEVELS = 6
"""Adaptive steps: the halvings of dt without min_dt (dt / 64 the smallest step). The
error estimate also follows elastic modes that fixed steps leave to GN22's damping (a
stiff block sliding: its smallest steps throughout); the floor bounds what that costs."""
MAX_LEVELS = 20
"""Adaptive steps: the halvings of dt allowed at most (a factorisation each)."""


@assignment_hint("make another, dataclasses.replace(probe, {name}=...)")
@dataclass(frozen=True)
class ProbeSpec:
    """Displacement history of a material point of one body.

    Attributes:
        name: Probe name, used in the output column names (e.g. ``"gauge_top"``).
        body: Name of the body the point belongs to (e.g. ``"caisson"``).
        point: Coordinates of the point.
    """

    name: str
    body: str
    point: tuple[float, ...]

    def __post_init__(self) -> None:
        check_fields(self)
        column_name(self.name)


@assignment_hint("make another, dataclasses.replace(probe, {name}=...)")
@dataclass(frozen=True)
class PairProbeSpec:
    """Relative slip and opening at an interface point (slave minus master).

    Attributes:
        name: Probe name (e.g. ``"corner_front"``).
        pair: Index of the contact pair in ``model.pairs`` (a conforming pair), or the
            name of a general pair (``model.surface_pairs``).
        point: Coordinates of the interface point (on the slave surface of a general
            pair).
    """

    name: str
    pair: int | str
    point: tuple[float, ...]

    def __post_init__(self) -> None:
        check_fields(self)
        column_name(self.name)


MAX_NEWTON_IT = 10_000
"""The most Newton iterations per solve: PETSc counts them (and 10 times as many
function evaluations) in 32-bit integers, and a Newton solve that has not converged in
a few tens of iterations will not."""

Solver = Literal["auto", "fast", "reference"]
"""The GN22 step solvers (:class:`breakwater.stepping.gn22.GN22`'s ``solver``), or
``"auto"``: the fast one where its dense interface fits in memory
(:mod:`breakwater.stepping.solverchoice`)."""


@assignment_hint("make another, dataclasses.replace(time, {name}=...), and pass it to run")
@dataclass(frozen=True)
class TimeSpec:
    """``[time]``: GN22 time integration and Newton settings.

    The case's ``[time]`` table is this class (``breakwater.casefile.case.TimeCase``): each
    field carries its unit and meaning (:func:`breakwater.casefile.case.case_reference`), and
    the values are checked here, once, whether they come from a case file or from
    Python.

    Raises:
        InvalidField: A value out of range (a :class:`~breakwater.common.errors.CaseError`
            naming the field).

    """

    dt: float = setting(unit="s", doc="time step Δt")
    end_time: float = setting(unit="s", doc="final time")
    beta1: float = setting(0.6, doc="GN22 β₁ (Newmark γ)")
    beta2: float = setting(0.605, doc="GN22 β₂ (2 × Newmark β)")
    allow_conditional: bool = setting(False, doc="accept β₁ < ½ or β₂ < β₁ (not "
                                      "unconditionally stable)")
    max_cutbacks: int = setting(4, doc="a failing step is retried with Δt/2, up to this "
                                f"many times (at most {MAX_CUTBACKS})")
    min_dt: float | None = setting(None, unit="s", doc="floor on the step of a cut-back: "
                                   "a step that fails and whose half is below it fails "
                                   "the run (default: none beyond max_cutbacks halvings)")
    max_steps: int = setting(1_000_000, doc="refuse a case of more steps (end_time / dt); "
                             "a run that needs more (cut-backs) fails when it has taken "
                             "them")
    newton_rtol: float = setting(1e-9, doc="Newton relative residual tolerance, in (0, 1)")
    newton_atol: float = setting(1e-9, doc="Newton absolute tolerance, as a fraction of "
                                 "the load-vector norm")
    newton_max_it: int = setting(40, doc="Newton iterations per step (1 to 10000)")
    adaptive: bool = setting(False, doc="adaptive steps: dt / 2^k chosen by GN22's local "
                             "error estimate and the loads' breakpoints, dt the largest "
                             "and min_dt (default dt / 64) the smallest")
    tolerance: float = setting(1e-3, doc="adaptive steps: the local error allowed per step, "
                               "relative to the step's displacement increment (1e-3: the "
                               "Goda case within 0.2 % of dt = 1e-4 s)")
    solver: Solver = setting("auto", doc='"fast": the bulk factorised once per Δt, Newton '  # noqa: RUF009
                             'on the contact surfaces only (dense interface matrices on every '
                             'rank); "reference": Newton on the whole residual, refactorised '
                             "every iteration (the same results to round-off, 10-80× slower "
                             'per step, sparse only); "auto": "fast" where its dense interface '
                             'matrices fit in half the memory, else "reference"')

    def __post_init__(self) -> None:
        check_fields(self)
        positive(self.dt, "dt")
        positive(self.end_time, "end_time")
        if self.dt >= self.end_time:
            raise InvalidField("dt", f"must be smaller than end_time ({self.dt:g} >= "
                               f"{self.end_time:g})", others=("end_time",))
        positive(self.beta1, "beta1")
        positive(self.beta2, "beta2")
        if not self.allow_conditional:
            if self.beta1 < 0.5:
                raise InvalidField("beta1", f"beta1 = {self.beta1:g} < 0.5 is not "
                                   "unconditionally stable (set time.allow_conditional = "
                                   "true to insist)")
            if self.beta2 < self.beta1:
                raise InvalidField("beta2", f"beta2 = {self.beta2:g} < beta1 = "
                                   f"{self.beta1:g} is not unconditionally stable (set "
                                   "time.allow_conditional = true to insist)",
                                   others=("beta1",))
        positive(self.max_cutbacks, "max_cutbacks", strict=False)
        if self.max_cutbacks > MAX_CUTBACKS:
            raise InvalidField("max_cutbacks", f"must be <= {MAX_CUTBACKS} (got "
                               f"{self.max_cutbacks}): each cut-back retries the failing "
                               f"step with Δt/2 (set time.min_dt for a floor on Δt)")
        if self.min_dt is not None:
            positive(self.min_dt, "min_dt")
            if self.min_dt > self.dt:
                raise InvalidField("min_dt", f"must be <= dt ({self.min_dt:g} > "
                                   f"{self.dt:g})", others=("dt",))
        positive(self.tolerance, "tolerance")
        if self.min_dt is not None and self.adaptive and self.min_dt < self.dt / 2**MAX_LEVELS:
            raise InvalidField("min_dt", f"adaptive steps: at most {MAX_LEVELS} halvings "
                               f"of dt (min_dt >= dt / {2**MAX_LEVELS:g} = "
                               f"{self.dt / 2**MAX_LEVELS:.3g} s; got {self.min_dt:g})",
                               others=("dt", "adaptive"))
        positive(self.max_steps, "max_steps")
        if self.planned_steps > self.max_steps:
            raise InvalidField("end_time", f"end_time / dt = {self.end_time:g} / "
                               f"{self.dt:g} = {self.planned_steps:.4g} steps, above the "
                               f"limit time.max_steps = {self.max_steps} (raise "
                               "time.max_steps to run it)", others=("dt", "max_steps"))
        if not 0 < self.newton_rtol < 1:
            raise InvalidField("newton_rtol", f"must be in (0, 1): the residual must "
                               f"decrease (got {self.newton_rtol:g})")
        positive(self.newton_atol, "newton_atol")
        if not 1 <= self.newton_max_it <= MAX_NEWTON_IT:
            raise InvalidField("newton_max_it", f"must be in [1, {MAX_NEWTON_IT}] (got "
                               f"{self.newton_max_it})")

    @property
    def planned_steps(self) -> int:
        """The steps from 0 to ``end_time`` without cut-backs (the last one may be short)."""
        return math.ceil(self.end_time / self.dt * (1.0 - 1e-9))

    @property
    def levels(self) -> int:
        """Adaptive steps: the halvings of dt down to the smallest step (0: fixed steps)."""
        if not self.adaptive:
            return 0
        smallest = self.min_dt if self.min_dt is not None else self.dt / 2**DEFAULT_LEVELS
        return max(1, math.floor(math.log2(self.dt / smallest) + 1e-9))

    @property
    def smallest_dt(self) -> float:
        """The smallest step without a cut-back: dt, or dt / 2^levels (adaptive)."""
        return self.dt / 2**self.levels

    @property
    def dt_floor(self) -> float:
        """The smallest step a cut-back may take: ``min_dt``, else 0.

        Without ``min_dt`` the step is bounded by ``max_cutbacks`` halvings:
        ``dt·2^-max_cutbacks`` at least, but for a short last step.
        """
        return self.min_dt if self.min_dt is not None else 0.0


@assignment_hint("make another, dataclasses.replace(output, {name}=...), and pass it to "
                 "run")
@dataclass(frozen=True)
class OutputSpec:
    """What to write and where.

    Attributes:
        directory: Output directory (created if missing).
        field_interval: Write VTX fields every N steps (0: never).
        probes: Point displacement probes.
        pair_probes: Interface slip/opening probes.
        figures: Draw the figures at the end of the run.
        progress: Progress bar; ``None``: only when stderr is a TTY, or in a Jupyter
            kernel (one line updated in place); ``False``: none.
        case_name: Name of the case, used in reports.
        checkpoint_interval: Write a checkpoint every N steps (0: never); see
            :mod:`breakwater.outputs.checkpoint` and ``run(..., resume=True)``.
    """

    directory: pathlib.Path
    field_interval: int = 10
    probes: tuple[ProbeSpec, ...] = ()
    pair_probes: tuple[PairProbeSpec, ...] = ()
    figures: bool = True
    progress: bool | None = None
    case_name: str = "case"
    checkpoint_interval: int = 0

    def __post_init__(self) -> None:
        check_fields(self)
        positive(self.field_interval, "field_interval", strict=False)
        positive(self.checkpoint_interval, "checkpoint_interval", strict=False)
        # The history's columns are named by the probes: two of one name wrote the same
        # columns twice (from Python; a case file's tables cannot; found by a user).
        for names in ([p.name for p in self.probes], [q.name for q in self.pair_probes]):
            twice = next((n for k, n in enumerate(names) if n in names[:k]), None)
            if twice is not None:
                raise ValueError(f"output: two probes named '{twice}' (their history "
                                 "columns would be the same)")


@assignment_hint("model.initial = dataclasses.replace(model.initial, {name}=...)")
@dataclass(frozen=True)
class InitialSpec:
    """The initial state of a run (:mod:`breakwater.statics.initial`).

    Attributes:
        velocities: Uniform initial velocity (m/s) of the bodies that move at t = 0, as
            ``(body name, vector)`` pairs; the other bodies start at rest.
        loads: Indices (in ``model.loads``) of the loads in the static initial state,
            at their values at t = 0; None: every load. A load left out acts from
            t = 0 on a body that is in equilibrium without it.
        loading: ``"frictional"``: where a pair has friction, the loads are applied
            with friction active (no frictionless slide on the way);
            ``"frictionless"``: the frictionless equilibrium where one exists.
        tolerance: The static residual ‖f − K u − f_c(u)‖ as a fraction of ‖f‖.
        undeformed: Start from the undeformed state at rest (no static state).
    """

    velocities: tuple[tuple[str, tuple[float, ...]], ...] = ()
    loads: tuple[int, ...] | None = None
    loading: Literal["frictional", "frictionless"] = "frictional"
    tolerance: float = 1e-9
    undeformed: bool = False

    def __post_init__(self) -> None:
        check_fields(self)
        if not 0 < self.tolerance < 1:
            raise InvalidField("tolerance", f"must be in (0, 1) (got {self.tolerance:g})")

    def velocity(self, body: str) -> tuple[float, ...] | None:
        """The initial velocity of a body (None: at rest)."""
        return dict(self.velocities).get(body)
