"""Loads that would not act as asked: checks before a run, on the case and on the mesh.

- :func:`pulse_warning`: a pulse the nominal steps sample badly (under-resolved, or
  ending after the end time), from :func:`sampled_pulse`, what GN22 makes of a pulse
  at the step ends; a pulse not longer than Δt, and a load that starts after the end
  time, are refused by :meth:`LoadCase.check_time <breakwater.casefile.loads.LoadCase.check_time>`;
- :func:`start_warning`: a load non-zero at t = 0 left out of the initial state (it
  jumps at t = 0, applied over the first step);
- :func:`table_warning`, :func:`late_peak_warning`: a table whose peak the steps miss, or
  that comes after the end time (times in ms read as seconds);
- :func:`storm_warning`: a storm whose shortest impulse the steps do not resolve;
- :func:`face_problems`: a pressure profile (or Goda's pressure) that is zero on all of
  its loaded facets (refused), or a ``[profile]`` that only partly lies on them
  (warned), integrated on the mesh.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from breakwater.casefile.loads import RESOLVED_STEPS
from breakwater.loads.fields import PressureProfile
from breakwater.loads.signals import Pulse, Table
from breakwater.storms.waveforce import PulseHistory

if TYPE_CHECKING:
    from breakwater.casefile import loads as loadcase
    from breakwater.model.model import ContactModel
    from breakwater.storms.waves import WaveLoad

__all__ = ["SAMPLING_TOLERANCE", "face_problems", "landing_problems", "late_peak_warning",
           "profile_area", "pulling_warning", "pulse_warning", "sampled_pulse",
           "start_warning", "storm_warning"]


SAMPLING_TOLERANCE = 0.01
"""The impulse the steps sample may differ from the requested by this fraction."""


def sampled_pulse(pulse: Pulse, dt: float, end_time: float, beta1: float,
                  in_state: bool = True) -> tuple[float, float, int]:
    """What the nominal steps (Δt, no cut-back) make of a pulse: impulse, peak, steps.

    GN22 evaluates the loads at the step ends t_n and its momentum update is
    M (v₁ − v₀) = Δt [(1 − β₁) M a₀ + β₁ M a₁], so the impulse a load gives is
    Σ Δt_n [(1 − β₁) f(t_n) + β₁ f(t_{n+1})] (the trapezoidal rule at β₁ = ½; Δt Σ f(t_n)
    at a constant step for a load zero at both ends). Only the steps near the pulse are
    summed. A pulse left out of the initial state (``in_state`` False) is not in a₀: its
    f(t₀) is 0 (:meth:`breakwater.stepping.gn22.GN22.initialise`).

    Returns:
        The impulse and the largest amplitude sampled (the pulse's own units), and the
        number of step ends inside the pulse.
    """
    steps = max(1, math.ceil(end_time / dt - 1e-9))
    first = max(0, math.floor(pulse.start / dt) - 1)
    last = min(steps, math.ceil(pulse.end / dt) + 1)
    times = [min(k * dt, end_time) for k in range(first, last + 1)]
    values = [pulse(t) if in_state or t > 0.0 else 0.0 for t in times]
    impulse = math.fsum((t1 - t0) * ((1.0 - beta1) * f0 + beta1 * f1) for t0, t1, f0, f1
                        in zip(times, times[1:], values, values[1:], strict=False))
    inside = sum(pulse.start < t < pulse.end for t in times)
    return impulse, max(values), inside


def pulse_warning(load: loadcase.LoadCase, dt: float, end_time: float, beta1: float,
                  in_state: bool = True) -> tuple[str | None, dict[str, float]]:
    """What the nominal steps make of a pulse, and a one-line warning if it is poor.

    A pulse ending after the end time is applied in part; one lasting fewer than
    :data:`~breakwater.casefile.loads.RESOLVED_STEPS` steps, or whose sampled impulse
    differs from its own by more than :data:`SAMPLING_TOLERANCE`, is under-resolved: the
    warning gives the time step that samples it to that tolerance.

    Returns:
        The warning (None: none) and the summary's ``sampled`` entry: the ratios of the
        sampled impulse and peak to the requested, the step ends inside the pulse.
    """
    if load.kind != "pulse" or not load.enabled:
        return None, {}
    pulse = load.pulse(1.0, 1.0)  # the impulse per unit length and area: ratios only
    impulse, peak, inside = sampled_pulse(pulse, dt, end_time, beta1, in_state)
    ratio = impulse / pulse.impulse
    sampled = {"impulse_ratio": ratio, "peak_ratio": peak / pulse.maximum,
               "step_ends_inside": inside}
    where = f"loads.{load.name}"
    if pulse.end > end_time:
        return (f"{where}: the pulse ends at t = {pulse.end:g} s, after time.end_time = "
                f"{end_time:g} s: the run applies {100 * ratio:.3g}% of its impulse"), sampled
    if load.duration >= RESOLVED_STEPS * dt and abs(ratio - 1.0) <= SAMPLING_TOLERANCE:
        return None, sampled
    needed = next((load.duration / k for k in range(RESOLVED_STEPS, 201)
                   if abs(sampled_pulse(pulse, load.duration / k, end_time, beta1,
                                        in_state)[0]
                          / pulse.impulse - 1.0) <= SAMPLING_TOLERANCE),
                  load.duration / 200)
    return (f"{where}: the pulse (duration {load.duration:g} s) spans {inside} step ends of "
            f"time.dt = {dt:g} s: the steps apply {100 * ratio:.3g}% of its impulse and "
            f"{100 * peak / pulse.maximum:.3g}% of its peak; time.dt <= {needed:.3g} s "
            f"samples it to {100 * SAMPLING_TOLERANCE:g}%"), sampled


def start_warning(load: loadcase.LoadCase, in_state: bool, dt: float) -> str | None:
    """A one-line warning for a load non-zero at t = 0 and left out of the initial state.

    Such a load jumps at t = 0: the stepper's a₀ is that of the initial state (without
    it), the first step's end has it, so it is applied over the first step (as any jump
    between two step ends; :meth:`breakwater.stepping.gn22.GN22.initialise`). Meant as a
    step load, that is what it does; a record or a push the user meant to start from
    (its value at t = 0) belongs in the state. The warning says what is applied.
    """
    if not load.enabled or in_state or load.storm is not None:
        return None
    if load.kind == "pulse":
        pulse = load.pulse(1.0, 1.0)
        value = pulse(0.0) / pulse.maximum
        what = f"its value at t = 0 is {100 * value:.3g}% of its peak"
    else:
        value = load.time_factor()(0.0)
        what = f"its factor at t = 0 is {value:.4g}"
    if value == 0.0:
        return None
    return (f"loads.{load.name}: {what}, and it is left out "
            f"of [initial] loads: it jumps at t = 0, applied over the first step (time.dt = "
            f"{dt:g} s); to start from it at rest, put it in [initial] loads, or give it a "
            "start > 0 or a rise")


PEAK_TOLERANCE = 0.05
"""A table's peak may be missed by this fraction by the steps' sampling unwarned."""


def _table_history(load: loadcase.LoadCase) -> Table | None:
    """An enabled table load's time factor (its time 0 at the load's start), else None."""
    if load.kind != "table" or load.table is None or not load.enabled:
        return None
    return load.table.history(load.start)


def sampled_peak(f: Callable[[float], float], dt: float, end_time: float) -> float:
    """The largest |f| at the step ends k Δt (k Δt ≤ end_time): what the steps apply."""
    steps = max(1, math.ceil(end_time / dt - 1e-9))
    return max(abs(f(min(k * dt, end_time))) for k in range(steps + 1))


def table_warning(load: loadcase.LoadCase, dt: float, end_time: float) -> str | None:
    """A one-line warning where the steps miss a table's peak, or None.

    The loads are evaluated at the step ends: a table whose peak is narrower than a step
    (an impact's spike) is applied at whatever the step ends fall on. Measured on the
    design-wave example at Δt = 0.015 s: 72 % of its peak applied, the residual slip a
    third of the resolved run's, with no word (found by a user). The warning gives the
    peak applied and a Δt that samples it to :data:`PEAK_TOLERANCE`.
    """
    f = _table_history(load)
    if f is None:
        return None
    inside = [t for t in f.breakpoints if 0.0 <= t <= end_time] or [0.0]
    peak = max(abs(f(t)) for t in inside)
    if peak == 0.0:
        return None
    got = sampled_peak(f, dt, end_time)
    if got >= (1.0 - PEAK_TOLERANCE) * peak:
        return None
    needed = next((dt / k for k in range(2, 201)
                   if sampled_peak(f, dt / k, end_time) >= (1.0 - PEAK_TOLERANCE) * peak),
                  dt / 200)
    return (f"loads.{load.name}.table: the steps of time.dt = {dt:g} s apply "
            f"{100 * got / peak:.3g}% of its peak (|factor| {peak:.4g}); time.dt <= "
            f"{needed:.3g} s samples it to {100 * PEAK_TOLERANCE:g}%")


def late_peak_warning(load: loadcase.LoadCase, end_time: float) -> str | None:
    """A one-line warning where a table's largest value comes after the end time, or None.

    The run applies the table up to ``end_time`` only. A record whose times are in
    milliseconds with no unit in its header (a 20 ms impact written 0 … 20) is read in
    seconds: its peak at "10 s" lies far beyond a run of 0.15 s, which applies the rise
    of its first row or two with no word (issue 23's note: undetectable from the header).
    Whatever the cause, a run that never reaches the table's peak is said so, with the
    share of the peak it applies and the unit to write if the times are in ms.
    """
    f = _table_history(load)
    if f is None:
        return None
    points = list(f.breakpoints)
    if not points:
        return None
    peak_t = max(points, key=lambda t: abs(f(t)))
    peak = abs(f(peak_t))
    if peak == 0.0 or peak_t <= end_time:
        return None
    inside = [t for t in points if t <= end_time] + [end_time]
    applied = max(abs(f(t)) for t in inside)
    if applied >= (1.0 - PEAK_TOLERANCE) * peak:
        return None
    return (f"loads.{load.name}.table: its largest value (|factor| {peak:.4g}) is at "
            f"t = {peak_t:.4g} s, after time.end_time = {end_time:g} s: the run applies at "
            f"most {100 * applied / peak:.3g}% of it (if the table's times are in ms, say so "
            "in its header: t [ms])")


def landing_problems(load: loadcase.LoadCase, dt: float, end_time: float, max_steps: int
                     ) -> tuple[str | None, str | None]:
    """Adaptive steps: a table whose points are denser than ``time.dt`` (error, warning).

    Adaptive steps land on each point of a table (:mod:`breakwater.stepping.stepsize`),
    so a record sampled finer than Δt takes a step per row: measured, a table of 10⁶ rows
    over 0.35 s took 2858 steps for the first millisecond (10 fixed steps), and the whole
    run would have taken ~10⁶ steps, about 3 hours, to fail at ``time.max_steps``, with
    no word. Refused when the points within the run leave no room in ``time.max_steps``;
    warned when they outnumber the fixed steps (end_time / dt).

    Returns:
        (a one-line error, a one-line warning); None each where there is none.
    """
    f = _table_history(load)
    if f is None:
        return None, None
    times = f.breakpoints
    count = bisect.bisect_left(times, end_time) - bisect.bisect_right(times, 0.0)
    fixed = math.ceil(end_time / dt * (1 - 1e-12))
    if count <= fixed:
        return None, None
    what = (f"loads.{load.name}.table: the adaptive steps land on each of its {count} "
            f"points within time.end_time = {end_time:g} s")
    cure = ("thin the table (every k-th row, keeping its peaks) or set time.adaptive = "
            "false (steps of time.dt sample it)")
    if count >= max_steps:  # and a step beyond the last point at least
        return f"{what}, as many as time.max_steps = {max_steps} or more: {cure}", None
    return None, (f"{what}, {count / fixed:.3g} times the {fixed} steps of time.dt = "
                  f"{dt:g} s: {cure}")


def storm_warning(name: str, waves: Sequence[WaveLoad], dt: float, end_time: float,
                  beta1: float) -> str | None:
    """A one-line warning where the steps do not resolve a storm's shortest impulse.

    Each wave's p₁(t) is a sine hump of τ₀ with, under Takahashi's α_I, a triangular
    impulsive peak of τ₁ = 0.1 τ₀ on top (:mod:`breakwater.storms.waveforce`), whose
    impulse drives the sliding; the loads are evaluated at the step ends. Measured (found
    by a user): the 70 ms peak of ``examples/goda_storm.toml`` at Δt = 0.05 s, its apex on
    a step end, applied 143 % of the peak's impulse (the step ends either side of it
    spread it over 2Δt = 100 ms) and twice the sliding of the resolved run, with no word.
    The shortest impulse (a wave's τ₁, or τ₀ without a peak) must span
    :data:`~breakwater.casefile.loads.RESOLVED_STEPS` steps and every wave's peak (or
    hump) be applied to :data:`SAMPLING_TOLERANCE` of its impulse by GN22's momentum rule
    (:func:`sampled_pulse`), as for pulses; the warning names the shortest impulse, the
    worst-applied one, the step and the step that resolves the shortest.

    Args:
        name: The load's name.
        waves: The storm's wave loads, in order.
        dt: The step inside the waves (adaptive steps: the resolved one).
        end_time: The run's end (s).
        beta1: GN22's β₁ (the momentum rule).
    """
    if not waves:
        return None
    shortest, k = min((_impulse(w)[0], i) for i, w in enumerate(waves))
    worst, ratio = 0, 1.0  # the wave whose impulse the steps apply worst
    for i, w in enumerate(waves):
        part = _impulse(w)[1]
        if w.wave.start + w.duration > end_time:
            continue
        got = sampled_pulse(part, dt, end_time, beta1)[0] / part.impulse
        if abs(got - 1.0) > abs(ratio - 1.0):
            worst, ratio = i, got
    if shortest >= RESOLVED_STEPS * dt * (1.0 - 1e-9) \
            and abs(ratio - 1.0) <= SAMPLING_TOLERANCE:
        return None
    def what(w: WaveLoad) -> str:
        return "impulsive peak" if _impulse(w)[0] < w.duration else "force"

    return (f"loads.{name}.storm: the shortest impulse (wave {k + 1}'s {what(waves[k])}, "
            f"{shortest:.3g} s, at t = {waves[k].wave.start:g} s) spans "
            f"{shortest / dt:.3g} steps of time.dt = {dt:g} s, and the steps apply "
            f"{100 * ratio:.3g}% of the impulse of wave {worst + 1}'s {what(waves[worst])}; "
            f"time.dt <= {shortest / RESOLVED_STEPS:.3g} s resolves it "
            f"({RESOLVED_STEPS} steps)")


def _impulse(w: WaveLoad) -> tuple[float, Pulse]:
    """A wave's shortest impulse: its peak's triangle (τ₁), else its hump (τ₀), as a Pulse.

    The triangle (of Takahashi's excess, on the run's clock) or the hump as a
    :class:`~breakwater.loads.signals.Pulse` of unit impulse, for :func:`sampled_pulse`
    (a history other than :func:`~breakwater.storms.waveforce.wave_load`'s is taken as
    a half-sine of the wave's duration).
    """
    p1 = w.p1
    if isinstance(p1, PulseHistory) and p1.impulsive > 0.0:
        start = w.wave.start + 0.5 * (p1.duration - p1.impulse_duration)
        return p1.impulse_duration, Pulse(1.0, p1.impulse_duration, "triangular", start)
    return w.duration, Pulse(1.0, w.duration, "half-sine", w.wave.start)


COVERAGE_TOLERANCE = 0.01
"""A ``[profile]`` may lose this fraction of its ∫|p| ds off the loaded facets unwarned."""


def profile_area(profile: PressureProfile, lo: float = -math.inf, hi: float = math.inf
                 ) -> float:
    """∫ |p(s)| ds over the profile's points within [lo, hi] (Pa m).

    Exact: |p| is linear between the points, the zero crossings and the bounds.
    """
    knots = [s for s, _ in profile.points]
    for (s0, p0), (s1, p1) in zip(profile.points, profile.points[1:], strict=False):
        if p0 * p1 < 0.0:  # the piece crosses zero
            knots.append(s0 + (s1 - s0) * p0 / (p0 - p1))
    knots += [b for b in (lo, hi) if knots[0] < b < knots[-1]]
    knots = sorted(k for k in knots if lo <= k <= hi)
    values = [abs(float(profile.pressure(k))) for k in knots]
    return math.fsum(0.5 * (values[i] + values[i + 1]) * (knots[i + 1] - knots[i])
                     for i in range(len(knots) - 1))


def _s_range(model: ContactModel, profile: PressureProfile, group: str
             ) -> tuple[float, float]:
    """The lowest and highest s of a facet group's nodes (every rank; collective)."""
    import numpy as np
    from mpi4py import MPI

    from breakwater.casefile.meshloads import group_nodes

    x = group_nodes(model.mesh_data, group)
    s = profile.coordinate(x) if len(x) else np.zeros(0)
    lo = model.comm.allreduce(float(s.min()) if len(s) else math.inf, op=MPI.MIN)
    hi = model.comm.allreduce(float(s.max()) if len(s) else -math.inf, op=MPI.MAX)
    return lo, hi


def face_problems(load: loadcase.LoadCase, model: ContactModel) -> tuple[str | None, str | None]:
    """An error (the load applies nothing) or a warning about a profile's loaded facets.

    For each model load of ``load`` with a :class:`PressureProfile` (a ``[profile]``,
    Goda's front pressure and uplift), ``∫ |p(s(x))| |n × a| ds`` over its facets (a the
    profile's axis, n the facet normal: the measure of s covered) against the profile's
    own ``∫ |p| ds``. Zero on every facet: the load applies nothing (an error). A
    ``[profile]`` covered by less than 1 − :data:`COVERAGE_TOLERANCE`: a warning (Goda's
    pressure above the crest is cut by design: not warned). Collective.

    Returns:
        (error, warning), each a one-line message or None.
    """
    import ufl

    x = ufl.SpatialCoordinate(model.mesh)
    n = ufl.FacetNormal(model.mesh)
    covered: dict[PressureProfile, float] = {}  # a field may load several groups
    groups: dict[PressureProfile, list[str]] = {}
    for ld in model.loads:
        field = ld.spec.field
        if ld.spec.name != load.name or not isinstance(field, PressureProfile):
            continue
        groups.setdefault(field, []).append(ld.spec.group)
        if model.gdim == 2:
            a = field.axis
            measure = abs(field.ufl_pressure(x)) * abs(n[0] * a[1] - n[1] * a[0])
            covered[field] = covered.get(field, 0.0) \
                + model.assemble(model.form(measure * ld.ds))
    where = f"loads.{load.name}." + ("profile" if load.profile is not None else
                                     "storm" if load.storm is not None else "goda")
    if model.gdim == 3:
        # ∫ |p| |n × a| dS would be ∫ |p| ds times the face's width across the axis: the
        # profile covered is that of the groups' s-range (a face spanning its s-range).
        for field, group_names in groups.items():
            ranges = [_s_range(model, field, g) for g in group_names]
            covered[field] = profile_area(field, min(r[0] for r in ranges),
                                          max(r[1] for r in ranges))
    for field, part in covered.items():
        total = profile_area(field)
        names = ", ".join(f"'{g}'" for g in groups[field])
        if not part > 1e-12 * total or not total > 0.0:
            return (f"{where}: the pressure is zero on all of {names} (the profile lies "
                    "off the loaded facets, or is zero): the load would apply nothing"), None
        if load.profile is not None and part < (1.0 - COVERAGE_TOLERANCE) * total:
            s = [p[0] for p in field.points]
            return None, (f"{where}: only {100 * part / total:.3g}% of the profile "
                          f"(s = {s[0]:g}..{s[-1]:g} m along {list(field.axis)} from "
                          f"{list(field.origin)}) lies on {names}: the rest is not applied")
    return None, None


PULLED_PART = 0.1
"""A pulse whose direction points out of more than this part of its group (∫⟨d·n⟩₊ over
∫|d·n|) is warned of: a curved face struck obliquely may turn slightly away at its edge."""


def pulling_warning(load: loadcase.LoadCase, model: ContactModel) -> str | None:
    """One line if a pulse's direction points out of its struck face, else None.

    A pulse is an impact (the pendulum's, a wave's slam): it pushes the face. With its
    direction along the face's outward normal (``[-1, 0]`` on the Goda caisson's seaward
    face) it pulled the face outwards, without a word. The sign of ∫ d·n ds over the
    load's facets (n the body's outward normal) decides. Collective.
    """
    import numpy as np
    import ufl
    from dolfinx import fem

    if load.kind != "pulse":
        return None
    n = ufl.FacetNormal(model.mesh)
    d = fem.Constant(model.mesh, np.array(load.direction))  # one form for any direction
    dn = ufl.dot(d, n)
    ds = [ld.ds for ld in model.loads if ld.spec.name == load.name]
    pulled = sum(model.assemble(model.form(ufl.max_value(dn, 0.0) * m)) for m in ds)
    total = sum(model.assemble(model.form(abs(dn) * m)) for m in ds)
    outward = 2.0 * pulled - total  # ∫d·n = ∫⟨d·n⟩₊ − ∫⟨−d·n⟩₊, ∫|d·n| their sum
    direction = [float(c) for c in load.direction]
    if outward > 1e-9 * total:  # (not > 0: opposite faces cancel to round-off, either sign)
        into = [-c + 0.0 for c in load.direction]  # (+ 0.0: no -0.0)
        return (f"loads.{load.name}.direction: {direction} points out of '{load.group}' "
                "(along its outward normal): the pulse pulls the face outwards; an impact "
                f"pushes it: direction = {into} (into the body)")
    # Faces on opposite sides (a block's two ends struck along z): the sum cancels, half
    # the traction pulls its faces outwards (it ran without a word).
    if not pulled > PULLED_PART * total:
        return None
    return (f"loads.{load.name}.direction: {direction} points out of {pulled / total:.0%} of "
            f"'{load.group}' (weighted by the faces' area across it): the pulse pulls those "
            "faces outwards and pushes the others; an impact pushes one face: strike a group "
            "on one side of the body")
