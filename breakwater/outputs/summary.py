"""The summary of a run (``summary.json``) and its on-screen report.

Everything here reads what a run produced, the history rows and the nodal interface
data of the static state, and steps or solves nothing (but :func:`quality_inputs`,
which asks the pairs):

- :func:`~breakwater.outputs.staticsummary.static_summary` (its own module): the first
  contact pair's static state;
- :func:`quality_inputs` and :func:`contact_quality`: the contact quality report of
  each pair (:mod:`breakwater.outputs.quality`);
- :class:`PeakSnapshot`: the state at the largest |u_x| of the first probe (the
  paper's Figs. 20, 22: ``snapshot_max_ux.npz``);
- :func:`dynamic_summary`: peak and residual displacement of the probes, slip and
  opening of the pair probes, residual slip and largest uplift;
- :func:`solver_summary`, :func:`energy_summary`, :func:`versions`, and
  :func:`run_summary`, which puts them together;
- :func:`format_report`: the short report printed at the end of a run.
"""

from __future__ import annotations

import pathlib
import platform
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater import __version__  # type: ignore[attr-defined]
from breakwater.common.files import per_metre
from breakwater.config.runspec import TimeSpec
from breakwater.energy.ledger import FIELDS
from breakwater.model.model import ContactModel
from breakwater.model.pairs import Pair
from breakwater.outputs import quality, rotation
from breakwater.outputs.historyrows import column
from breakwater.outputs.probes import Probes

__all__ = ["BALANCE_WARNING", "PeakSnapshot", "balance_warning", "contact_quality",
           "dynamic_summary", "energy_summary", "format_report", "merge", "quality_inputs",
           "run_summary", "solver_summary", "versions"]


# --- contact quality --------------------------------------------------------------

def quality_inputs(pairs: Sequence[Pair], u: Sequence[fem.Function]
                   ) -> list[quality.PairInputs]:
    """The static measures of each pair's contact quality (collective).

    Args:
        pairs: The pairs (the stepper's :attr:`~breakwater.stepping.gn22.GN22.contacts`).
        u: The static state (one Function per body).
    """
    return [quality.PairInputs.of(p.name, p.static_measures(u)) for p in pairs]


def contact_quality(inputs: Sequence[quality.PairInputs], steps: Sequence[Mapping[str, float]]
                    ) -> dict[str, quality.ContactQuality]:
    """The contact quality of each pair, with the largest penetration over ``steps``.

    Args:
        inputs: The static measures of each pair.
        steps: History rows of the time steps (the static row excluded); none for the
            static report.
    """
    report = {}
    for c in inputs:
        δ, when = None, None
        if steps:
            δs = column(steps, f"{c.name}_penetration")
            j = int(np.argmax(δs))
            δ, when = float(δs[j]), float(column(steps, "t")[j])
        report[c.name] = c.assess(δ, when)
    return report


# --- the instant of the largest displacement ----------------------------------------

class PeakSnapshot:
    """The state at the largest |u_x| of the first probe (the first such instant).

    Args:
        model: The contact model (the snapshot is one Function per body).
        probes: Names of the point probes; without any there is no snapshot.

    Attributes:
        u: The state at that instant.
        time: The instant (None before the first row, or without probes).
        value: u_x of the first probe then.

    """

    def __init__(self, model: ContactModel, probes: Sequence[str]) -> None:
        self.column = f"{probes[0]}_ux" if probes else None
        self.u = model.functions("u_snapshot")
        self.time: float | None = None
        self.value = 0.0

    def update(self, row: Mapping[str, float], u: Sequence[fem.Function]) -> None:
        """Keep the state ``u`` of the history row ``row`` if its |u_x| is the largest."""
        if self.column is None:
            return
        ux = row[self.column]
        if self.time is None or abs(ux) > abs(self.value):
            for dst, src in zip(self.u, u, strict=True):
                dst.x.array[:] = src.x.array
            self.time, self.value = row["t"], ux


# --- the time steps ---------------------------------------------------------------

def dynamic_summary(rows: Sequence[Mapping[str, float]], probes: Sequence[str],
                    pair_probes: Sequence[str], bodies: Sequence[str] = ()
                    ) -> dict[str, Any]:
    """The ``dynamic`` entry of the summary, from the history rows (static row first).

    Args:
        rows: The history rows.
        probes: Names of the point probes.
        pair_probes: Names of the pair probes.
        bodies: Names of the bodies whose ``<body>_rotation`` the rows have
            (``max_rotation``: :func:`breakwater.outputs.rotation.largest`).
    """
    if not rows:
        return {}
    end = rows[-1]
    dynamic: dict[str, Any] = {"peak_ux": {}}
    t = column(rows, "t")
    for name in probes:
        ux = column(rows, f"{name}_ux")
        k = int(np.argmax(np.abs(ux)))  # the first largest
        dynamic["peak_ux"][name] = {"value": float(ux[k]), "time": float(t[k])}
    dynamic["residual_ux"] = {name: end[f"{name}_ux"] for name in probes}
    dynamic["residual_uy"] = {name: end[f"{name}_uy"] for name in probes}
    if probes and f"{probes[0]}_uz" in end:  # 3D
        dynamic["peak_uz"] = {}
        for name in probes:
            uz = column(rows, f"{name}_uz")
            k = int(np.argmax(np.abs(uz)))
            dynamic["peak_uz"][name] = {"value": float(uz[k]), "time": float(t[k])}
        dynamic["residual_uz"] = {name: end[f"{name}_uz"] for name in probes}
    dynamic["time_of_max_ux"] = dynamic["peak_ux"][probes[0]]["time"] if probes else None
    pairs: dict[str, Any] = {}
    for name in pair_probes:
        slip, opening = column(rows, f"{name}_slip"), column(rows, f"{name}_opening")
        k = int(np.argmax(opening))
        change = float(slip[-1] - slip[0])
        if f"{name}_slave_uz" in end:
            # 3D: the slip column is a magnitude, whose difference is no slip (it had the
            # wrong sign, and 2|s₀| off where the slip turns): the magnitude of the
            # tangential part of the jump's change, |Δ(u_s − u_m)|² − Δopening².
            jump = [column(rows, f"{name}_slave_u{a}") - column(rows, f"{name}_master_u{a}")
                    for a in "xyz"]
            moved = sum((j[-1] - j[0]) ** 2 for j in jump)
            change = float(np.sqrt(max(moved - (opening[-1] - opening[0]) ** 2, 0.0)))
        pairs[name] = {"residual_slip": float(slip[-1]), "residual_opening": float(opening[-1]),
                       # the static (frictionless) state may already slip a bit
                       "static_slip": float(slip[0]), "slip_change": change,
                       "max_abs_slip": float(np.abs(slip).max()),
                       "max_opening": float(opening[k]), "time_of_max_opening": float(t[k])}
    dynamic["pair_probes"] = pairs
    dynamic["residual_slip"] = pairs[pair_probes[0]]["residual_slip"] if pair_probes else None
    dynamic["max_uplift"] = max((p["max_opening"] for p in pairs.values()), default=None)
    if bodies:
        dynamic["max_rotation"] = rotation.largest(rows, bodies)
    return dynamic


def solver_summary(steps: int, iterations: Sequence[int], failed_steps: int,
                   failed_iterations: int, cutbacks: int, min_dt: float, flips: int,
                   round_off_accepts: int, wall_time: float, kind: str = "fast",
                   time_loop: Mapping[str, float] | None = None) -> dict[str, Any]:
    """The ``solver`` entry of the summary.

    ``time_loop`` is the wall time of the time loop and of its parts (s): ``outputs``,
    ``cpu`` (the process's CPU time over the loop, all threads) and the step solver's
    parts (:attr:`~breakwater.stepping.stepsolver.StepSolver.timings`): for the fast
    solver, ``factorisation``, ``back_solves``, ``bulk_products``,
    ``interface_assembly``, ``newton`` and ``contact_search`` (the general pairs' search,
    a part of ``interface_assembly``); for the reference solver, ``newton`` (its SNES
    solves in total). ``flips``: the nodal Newton steps the slip guard changed
    (``slip_guard_corrections``: reversals landed at zero slip and slips landed on the
    law's curve, :mod:`breakwater.contact.slipguard`).
    """
    its = iterations
    return {
        "kind": kind,
        "steps": steps,
        "newton_iterations": int(sum(its)),
        "mean_newton_iterations": float(np.mean(its)) if its else None,
        "max_newton_iterations": int(max(its)) if its else None,
        "failed_steps": failed_steps,
        "failed_newton_iterations": failed_iterations,
        "cutbacks": cutbacks,
        "min_dt": min_dt,
        "slip_guard_corrections": flips,
        "round_off_accepts": round_off_accepts,
        "wall_time": wall_time,
        "time_loop": dict(time_loop or {}),
    }


BALANCE_WARNING = 1e-2
"""A run warns when its largest |balance error| exceeds this fraction of its energy scale.

The ledger closes to Newton's tolerance (1e-9 of the external work on the Goda case,
README "Energy"): an error of 1 % means that the steps did not resolve what happened,
e.g. an impact within one step, where the contact's acceleration acts on for
(1 − β₁)Δt after the bodies part and a block thrown at 20 m/s leaves at 23.6 m/s.
"""


def energy_summary(rows: Sequence[Mapping[str, float]]) -> dict[str, Any]:
    """The ``energy`` entry of the summary: the largest |balance error|, the last ledger.

    Also the largest |balance error| and the final numerical dissipation as fractions
    of the final external work (None when no work was done), and the largest |balance
    error| as a fraction of the run's energy scale: the largest of the stored energy
    (kinetic + strain + penalty) and of |external work| over the records.
    """
    if not rows:
        return {"max_balance_error": None, "final": None, "numerical_dissipation": None,
                "max_balance_error_over_external_work": None,
                "numerical_dissipation_over_external_work": None, "energy_scale": 0.0,
                "max_balance_error_over_energy_scale": None}
    last = rows[-1]
    work = last["external_work"]
    stored = column(rows, "kinetic") + column(rows, "strain") + column(rows, "penalty")
    scale = float(np.maximum(stored, np.abs(column(rows, "external_work"))).max())

    def of(x: float | None, y: float) -> float | None:
        return None if x is None or not y else x / abs(y)

    largest = float(np.abs(column(rows, "balance_error")).max())
    numerical = last.get("numerical_dissipation")
    return {"max_balance_error": largest,
            "final": {k: last[k] for k in FIELDS if k in last},
            "numerical_dissipation": numerical,
            "max_balance_error_over_external_work": of(largest, work),
            "numerical_dissipation_over_external_work": of(numerical, work),
            "energy_scale": scale,
            "max_balance_error_over_energy_scale": of(largest, scale)}


def balance_warning(energy: Mapping[str, Any], per: str = "/m") -> str | None:
    """The warning of a run whose energy balance does not close, or None.

    See :data:`BALANCE_WARNING`.
    """
    ratio = energy.get("max_balance_error_over_energy_scale")
    if ratio is None or ratio <= BALANCE_WARNING:
        return None
    return (f"energy: the balance error reaches {energy['max_balance_error']:.3g} J{per}, "
            f"{100 * ratio:.3g} % of the run's largest energy "
            f"({energy['energy_scale']:.3g} J{per}): the time steps do not resolve the motion "
            "(an impact within a step?); these results are not reliable: reduce time.dt")


def run_summary(*, case_name: str, finished: bool, status: str, error: str | None,
                time: TimeSpec, static: dict[str, Any],
                resumed_from: list[dict[str, Any]], rows: Sequence[Mapping[str, float]],
                probes: Probes | None, contact_quality: Mapping[str, quality.ContactQuality],
                solver: Mapping[str, Any], checkpoint: Mapping[str, Any] | None,
                outputs: Mapping[str, Any], comm: MPI.Comm, extra: Mapping[str, Any],
                dimension: int = 2, bodies: Sequence[str] = ()) -> dict[str, Any]:
    """The summary of a run (``summary.json``), ``extra`` merged in.

    Args:
        case_name: The case's name.
        finished: Whether the end time was reached.
        status: ``running``, ``finished``, ``failed`` or ``interrupted``.
        error: Why the run stopped early.
        time: The time settings.
        static: The ``static`` entry
            (:func:`~breakwater.outputs.staticsummary.static_summary`; empty before the
            static state is solved).
        resumed_from: Where each earlier part of a resumed run ended (``t``, ``steps``,
            ``mpi_size``).
        rows: The history rows (the static state's first).
        probes: The run's probes (None before they exist).
        contact_quality: The contact quality of each pair.
        solver: The ``solver`` entry (:func:`solver_summary`).
        checkpoint: The latest checkpoint written.
        outputs: The ``outputs`` entry.
        comm: The communicator (its size is in ``versions``).
        extra: Merged into the summary (e.g. calibration results).
        dimension: The model's (2: plane strain, forces and energies per metre; 3).
        bodies: The bodies whose rotation the rows have (:func:`dynamic_summary`).
    """
    summary: dict[str, Any] = {
        "case_name": case_name,
        "dimension": dimension,
        "finished": finished,
        "status": status,
        "error": error,
        "time": {"end_time": time.end_time, "dt": time.dt,
                 "reached": rows[-1]["t"] if rows else None},
        "static": static,
        "dynamic": (dynamic_summary(rows, probes.names, probes.pair_names, bodies)
                    if probes is not None else {}),
        "contact_quality": {name: q.as_dict() for name, q in contact_quality.items()},
        "solver": dict(solver),
        "energy": energy_summary(rows),
        "checkpoint": checkpoint,
        "resumed_from": resumed_from,
        "outputs": dict(outputs),
        "versions": versions(comm),
    }
    return merge(summary, extra)


def versions(comm: MPI.Comm) -> dict[str, Any]:
    """Versions of breakwater and of the libraries it runs on."""
    import basix
    import dolfinx
    import ffcx
    import gmsh
    import petsc4py
    import ufl
    from petsc4py import PETSc

    return {
        "breakwater": __version__,
        "dolfinx": dolfinx.__version__,
        "petsc4py": petsc4py.__version__,
        "petsc": ".".join(str(v) for v in PETSc.Sys.getVersion()),
        "ufl": ufl.__version__,
        "basix": basix.__version__,
        "ffcx": ffcx.__version__,
        "gmsh": gmsh.__version__,
        "python": platform.python_version(),
        "mpi_size": comm.size,
    }


def merge(base: dict[str, Any], extra: Mapping[str, Any]) -> dict[str, Any]:
    """Recursive dictionary merge (``extra`` wins)."""
    for k, v in extra.items():
        if isinstance(v, Mapping) and isinstance(base.get(k), dict):
            merge(base[k], v)
        else:
            base[k] = dict(v) if isinstance(v, Mapping) else v
    return base


# --- on-screen report -------------------------------------------------------------

def whole_body_keys(tree: Any) -> Any:
    """A 3D run's load summary with its keys of the whole bodies, not per metre.

    The loads are summarised with plane strain's keys (``impulse_per_length``,
    ``patch_length``, ...); in 3D the same values are the whole structure's (N s, N)
    and the patch's area (m²): ``<key>_per_length`` becomes ``<key>`` and
    ``patch_length`` ``patch_area``, at every level.
    """
    if isinstance(tree, dict):
        return {("patch_area" if k == "patch_length" else k.removesuffix("_per_length")):
                whole_body_keys(v) for k, v in tree.items()}
    return tree


def format_report(summary: Mapping[str, Any], directory: str | pathlib.Path) -> str:
    """A short human-readable report of a run summary."""
    s, d, sol = summary.get("static", {}), summary.get("dynamic", {}), summary.get("solver", {})
    per = per_metre(summary)

    def num(x: Any, fmt: str = ".4g") -> str:
        return "n/a" if x is None else format(x, fmt)

    reached = num(summary.get("time", {}).get("reached"))
    lines = [f"breakwater: case '{summary.get('case_name', 'case')}' "
             + ("finished" if summary.get("finished") else
                f"INTERRUPTED at t = {reached} s: {summary.get('error')}"
                if summary.get("status") == "interrupted" else
                f"FAILED at t = {reached} s: {summary.get('error')}")]
    if s:
        lines.append(f"  static: normal contact resultant ∫p dS {num(s.get('contact_resultant'))} "
                     f"N{per}, weight carried {num(s.get('weight'))} N{per}, mean pressure "
                     f"{num(s.get('mean_contact_pressure'))} Pa (edge "
                     f"{num(s.get('edge_pressure'))}, centre {num(s.get('center_pressure'))})")
    held = []
    for group, f in summary.get("fixed", {}).items():

        def size(k: str, v: float) -> str:
            return (f"{v:g} point{'' if v == 1 else 's'}" if k == "points" else
                    f"{v:.4g} m{'²' if k == 'area' else ''}")

        on = ", ".join(f"{body} " + ", ".join(size(k, v) for k, v in measures.items())
                       for body, measures in f.get("bodies", {}).items())
        held.append(f"{group} {''.join(f.get('components', []))} ({on})")
    if held:
        lines.append(f"  fixed: {'; '.join(held)}")
    for name, peak in d.get("peak_ux", {}).items():
        line = (f"  {name}: peak u_x {num(peak.get('value'))} m at t = "
                f"{num(peak.get('time'))} s, residual {num(d.get('residual_ux', {}).get(name))} m")
        z = d.get("peak_uz", {}).get(name)
        if z is not None:
            line += (f"; peak u_z {num(z.get('value'))} m at t = {num(z.get('time'))} s, "
                     f"residual {num(d.get('residual_uz', {}).get(name))} m")
        lines.append(line)
    if d.get("residual_slip") is not None:
        lines.append(f"  residual slip {num(d.get('residual_slip'))} m, max uplift "
                     f"{num(d.get('max_uplift'))} m")
    if sol and not sol.get("steps"):
        lines.append(f"  solver: no time step taken, {num(sol.get('wall_time'), '.1f')} s "
                     "wall time")
    elif sol:
        lines.append(f"  solver: {sol.get('steps')} steps, {sol.get('newton_iterations')} "
                     f"Newton iterations (mean {num(sol.get('mean_newton_iterations'), '.2f')}"
                     f", max {sol.get('max_newton_iterations')}), {sol.get('cutbacks')} "
                     f"cut-backs, {num(sol.get('wall_time'), '.1f')} s wall time (time loop "
                     f"{num(sol.get('time_loop', {}).get('wall'), '.1f')} s, "
                     f"{sol.get('kind')} solver)")
        if sol.get("round_off_accepts"):
            lines.append(f"  solver: {sol['round_off_accepts']} steps accepted with a residual "
                         "stalled at round-off (NewtonOptions.floor_atol)")
        if sol.get("newton_continuations"):
            lines.append(f"  solver: {sol['newton_continuations']} Newton solves converged only "
                         "by a continuation in the friction's regularisation χ")
        if sol.get("newton_rescues"):
            lines.append(f"  solver: {sol['newton_rescues']} Newton solves converged only when "
                         f"done again with their overshooting steps halved "
                         f"({sol.get('newton_halvings', 0)} halvings)")
        if (sol.get("elimination") or {}).get("X") == "interface rows only":
            e = sol["elimination"]
            lines.append(f"  solver: X = A⁻¹E did not fit in memory: its interface rows built "
                         f"in {e['chunks']} chunks, a second back-solve per step")
    def pct(x: Any) -> str:
        return "n/a" if x is None else f"{100 * x:.2g}%"

    for name, q in summary.get("contact_quality", {}).items():
        ratios = q.get("penalty_h_over_E", {})
        lines.append(f"  contact '{name}': penetration static "
                     f"{num(q.get('static_penetration'), '.3g')} m "
                     f"({pct(q.get('static_penetration_over_h'))} of h, "
                     f"{pct(q.get('static_penetration_over_settlement'))} of the settlement), "
                     f"max {num(q.get('dynamic_penetration'), '.3g')} m "
                     f"({pct(q.get('dynamic_penetration_over_h'))} of h); ε_n h/E "
                     f"{num(ratios.get('slave'), '.3g')} (slave), "
                     f"{num(ratios.get('master'), '.3g')} (master): {q.get('verdict')}")
    e = summary.get("energy", {})
    if e.get("max_balance_error") is not None:
        line = f"  energy: max |balance error| {num(e.get('max_balance_error'))} J{per}"
        work = (e.get("final") or {}).get("external_work")
        scale, numerical = e.get("energy_scale") or 0.0, e.get("numerical_dissipation")
        if work is not None and scale and abs(work) < 0.5 * scale:
            # The energy came from elsewhere (initial velocities, a release): the work
            # done is no measure (a sliding block stopped by friction: 1.7e4 of it).
            line += (f" ({num(e.get('max_balance_error_over_energy_scale'), '.2g')} of the "
                     f"run's largest energy, {num(scale, '.3g')} J{per}); numerical "
                     f"dissipation {num(numerical)} J{per}"
                     + (f" ({pct(numerical / scale)} of that energy)" if numerical is not None
                        else ""))
        elif e.get("max_balance_error_over_external_work") is not None:
            line += (f" ({num(e['max_balance_error_over_external_work'], '.2g')} of the "
                     f"external work); numerical dissipation "
                     f"{num(numerical)} J{per} "
                     f"({pct(e.get('numerical_dissipation_over_external_work'))})")
        lines.append(line)
    storm = summary.get("storm")
    if storm:
        line = (f"  storm: {storm.get('waves_finished')} of {storm.get('waves')} waves, "
                f"total sliding {num(storm.get('total_sliding'))} m")
        big = storm.get("largest_wave")
        if big:
            line += (f" (the highest, wave {big['wave']}, H = {num(big['height'])} m: "
                     f"{num(big['sliding'])} m)")
        lines.append(line + "; waves.csv")
        if storm.get("warning"):
            lines.append(f"  warning: {storm['warning']}")
    lines.append(f"  outputs: {directory}")
    return "\n".join(lines)
