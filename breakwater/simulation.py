"""A whole run: static equilibrium, GN22 time stepping with cut-back, outputs.

:func:`run` takes a built :class:`~breakwater.model.ContactModel` and the typed run
settings of :mod:`breakwater.runspec`; it never reads TOML. The run

1. solves the frictionless static equilibrium under gravity
   (:func:`breakwater.gn22.solve_static`) and starts the GN22 stepper from it at rest;
2. steps to ``end_time`` (the last step lands on it exactly). A step whose Newton
   solve fails is retried with Δt/2, up to ``max_cutbacks`` halvings; after
   :data:`GROW_AFTER` accepted steps the step doubles again, never above the nominal
   Δt. A step that still fails, or a non-finite state, ends the run: the outputs up to
   the last accepted step are written, ``summary.json`` says ``finished: false`` and
   :class:`SimulationFailed` is raised;
3. writes the outputs described in :mod:`breakwater.outputs` and the figures of
   :mod:`breakwater.figures`.

Every rank runs the same code (all measurements are collective and give the same
values on every rank); only rank 0 writes files, logs and prints.
"""

from __future__ import annotations

import contextlib
import logging
import math
import pathlib
import platform
import sys
import time as _time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from . import __version__, forms  # type: ignore[attr-defined]
from . import outputs as out
from .errors import BreakwaterError, ConvergenceError
from .gn22 import GN22, GN22Parameters, solve_static
from .interface import InterfaceNodes, interface_nodes
from .ledger import FIELDS, EnergyLedger
from .model import ContactModel
from .probes import PointProbe
from .runspec import OutputSpec, PairProbeSpec, TimeSpec
from .solver import NewtonOptions

__all__ = ["GROW_AFTER", "SimulationFailed", "run"]

GROW_AFTER = 4
"""Accepted steps after a cut-back before the step size doubles again."""


class _RankZero(logging.Filter):
    """Let only rank 0 of COMM_WORLD log."""

    def filter(self, record: logging.LogRecord) -> bool:
        return MPI.COMM_WORLD.rank == 0


log = logging.getLogger("breakwater.simulation")
log.addFilter(_RankZero())


class SimulationFailed(BreakwaterError):
    """The run stopped before its end time.

    A step failed to converge after every cut-back, or the state became non-finite.

    Attributes:
        summary: The summary written to ``summary.json`` (``finished`` is False).

    """

    def __init__(self, message: str, summary: Mapping[str, Any] | None = None) -> None:
        super().__init__(message)
        self.summary = dict(summary or {})


# --- measurements -----------------------------------------------------------------

def _tangent(n: np.ndarray) -> np.ndarray:
    """2D unit tangent t = (n_y, −n_x): +x on a horizontal interface with n = +y."""
    return np.array([n[1], -n[0]])


class _PairProbe:
    """Slip and opening (slave minus master) at an interface point.

    The normal is the master's outward normal at the nearest interface node;
    slip is along ``t = (n_y, −n_x)`` in 2D (the tangential magnitude in 3D).
    """

    KEYS = ("slip", "opening", "slave_ux", "slave_uy", "master_ux", "master_uy")

    def __init__(self, model: ContactModel, spec: PairProbeSpec,
                 nodes: Sequence[InterfaceNodes]) -> None:
        if not 0 <= spec.pair < len(model.pairs):
            raise ValueError(f"pair probe '{spec.name}': no contact pair {spec.pair} "
                             f"(the model has {len(model.pairs)})")
        self.name = spec.name
        pair = model.pairs[spec.pair]
        self.slave = PointProbe(model, model.bodies[pair.slave].spec.name, spec.point,
                                f"{spec.name}_slave")
        self.master = PointProbe(model, model.bodies[pair.master].spec.name, spec.point,
                                 f"{spec.name}_master")
        nd = nodes[spec.pair]
        x = np.zeros(model.gdim)
        x[:] = np.asarray(spec.point, dtype=float)[: model.gdim]
        self.normal = nd.normal[np.argmin(np.linalg.norm(nd.x - x, axis=1))]
        self.gdim = model.gdim

    def value(self, u: Sequence[fem.Function]) -> dict[str, float]:
        """Slip, opening and both sides' displacements for the state ``u``.

        Returns:
            Keys ``slip``, ``opening``, ``slave_ux``, ``slave_uy``, ``master_ux``,
            ``master_uy``.
        """
        us, um = self.slave.value(u), self.master.value(u)
        jump = us - um
        opening = float(jump @ self.normal)
        if self.gdim == 2:
            slip = float(jump @ _tangent(self.normal))
        else:
            slip = float(np.linalg.norm(jump - opening * self.normal))
        return {"slip": slip, "opening": opening,
                "slave_ux": float(us[0]), "slave_uy": float(us[1]),
                "master_ux": float(um[0]), "master_uy": float(um[1])}


class Monitor:
    """Everything measured on the state after each step: one history row.

    Args:
        model: The contact model.
        stepper: The GN22 stepper (its ``u``, ``v`` are measured).
        output: The probes.
        nodes: Interface nodes of every pair.

    """

    def __init__(self, model: ContactModel, stepper: GN22, output: OutputSpec,
                 nodes: Sequence[InterfaceNodes]) -> None:
        self.model, self.stepper = model, stepper
        self.probes = [(p.name, PointProbe(model, p.body, p.point, p.name))
                       for p in output.probes]
        self.pair_probes = [_PairProbe(model, p, nodes) for p in output.pair_probes]
        u, v = stepper.u, stepper.v
        self._contact = []
        for p in model.pairs:
            us, um = u[p.slave]("+"), u[p.master]("-")
            g_n = forms.normal_gap(us, um, p.n, p.g0)
            pressure = forms.penalty_pressure(g_n, p.ε_n)
            traction = model.traction(p, u, v)
            if model.gdim == 2:
                t = ufl.as_vector((p.n[1], -p.n[0]))
                tangential = ufl.dot(traction, t)
            else:
                tangential = ufl.sqrt(ufl.dot(forms.tangential_part(traction, p.n),
                                              forms.tangential_part(traction, p.n)))
            self._contact.append(tuple(model.form(f * p.dS) for f in (
                ufl.conditional(ufl.le(g_n, 0.0), 1.0, 0.0), pressure, tangential)))
        self.columns = ["t", "dt", "newton_iterations"]
        for name, _ in self.probes:
            self.columns += [f"{name}_ux", f"{name}_uy"]
        for pp in self.pair_probes:
            self.columns += [f"{pp.name}_{k}" for k in _PairProbe.KEYS]
        for k in range(len(model.pairs)):
            self.columns += [f"contact_length_{k}", f"normal_force_{k}",
                             f"tangential_force_{k}"]
        self.columns += list(FIELDS)

    def row(self, dt: float, iterations: int, energies: Mapping[str, float]) -> dict[str, float]:
        """The history row of the stepper's current state."""
        s = self.stepper
        r: dict[str, float] = {"t": float(s.t.value), "dt": dt,
                               "newton_iterations": float(iterations)}
        for name, probe in self.probes:
            value = probe.value(s.u)
            r[f"{name}_ux"], r[f"{name}_uy"] = float(value[0]), float(value[1])
        for pp in self.pair_probes:
            r.update({f"{pp.name}_{k}": x for k, x in pp.value(s.u).items()})
        for k, compiled in enumerate(self._contact):
            length, normal, tangential = (self.model.assemble(c) for c in compiled)
            r[f"contact_length_{k}"] = length
            r[f"normal_force_{k}"] = normal
            r[f"tangential_force_{k}"] = tangential
        r.update({k: float(energies[k]) for k in FIELDS})
        return r


def interface_state(model: ContactModel, nodes: Sequence[InterfaceNodes],
                    u: Sequence[fem.Function]) -> dict[str, np.ndarray]:
    """Nodal interface data of every pair (same on all ranks; collective).

    Returns:
        ``pair<k>_x`` node coordinates (sorted), ``pair<k>_normal``, ``pair<k>_gap``
        (normal gap g_n), ``pair<k>_slip`` (2D: along t = (n_y, −n_x)) and
        ``pair<k>_pressure`` (ε_n ⟨−g_n⟩₊).
    """
    data: dict[str, np.ndarray] = {}
    for k, (p, nd) in enumerate(zip(model.pairs, nodes, strict=True)):
        us, um = nd.gather(u[p.slave].x.array, u[p.master].x.array)
        jump = us - um
        gap = np.sum(jump * nd.normal, axis=1) + p.spec.gap
        data[f"pair{k}_x"] = nd.x
        data[f"pair{k}_normal"] = nd.normal
        data[f"pair{k}_gap"] = gap
        if model.gdim == 2:
            t = np.column_stack([nd.normal[:, 1], -nd.normal[:, 0]])
            data[f"pair{k}_slip"] = np.sum(jump * t, axis=1)
        data[f"pair{k}_pressure"] = p.spec.penalty * np.maximum(-gap, 0.0)
    return data


def _edge_centre(x: np.ndarray) -> tuple[int, int, int]:
    """Indices of the two end nodes of an interface and of the node nearest its centre.

    The nodes are sorted lexicographically (x, then y), so for a straight interface
    the first and last are its ends.
    """
    first, last = 0, len(x) - 1
    centre = int(np.argmin(np.linalg.norm(x - 0.5 * (x[first] + x[last]), axis=1)))
    return first, last, centre


def versions(comm: MPI.Comm) -> dict[str, Any]:
    """Versions of breakwater and of the libraries it runs on."""
    import basix
    import dolfinx
    import ffcx
    import gmsh
    import petsc4py
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


def _merge(base: dict[str, Any], extra: Mapping[str, Any]) -> dict[str, Any]:
    """Recursive dictionary merge (``extra`` wins)."""
    for k, v in extra.items():
        if isinstance(v, Mapping) and isinstance(base.get(k), dict):
            _merge(base[k], v)
        else:
            base[k] = dict(v) if isinstance(v, Mapping) else v
    return base


# --- the run ----------------------------------------------------------------------

class _Progress:
    """A tqdm bar in simulated seconds on rank 0 (no-op elsewhere or when disabled).

    While the bar is shown, log records of the console handlers are routed through
    ``tqdm.write`` so that they do not break the bar.
    """

    def __init__(self, end_time: float, enabled: bool, name: str) -> None:
        self.bar = None
        self._redirect: contextlib.AbstractContextManager[None] = contextlib.nullcontext()
        if enabled:
            from tqdm import tqdm
            from tqdm.contrib.logging import logging_redirect_tqdm

            self.bar = tqdm(total=end_time, desc=name, unit="s", file=sys.stderr,
                            bar_format="{desc}: {percentage:3.0f}%|{bar}| t={n:.4g}/"
                                       "{total:.4g} s [{elapsed}<{remaining}{postfix}]")
            self._redirect = logging_redirect_tqdm(
                loggers=[logging.getLogger(), logging.getLogger("breakwater")])
        self._t = 0.0

    def __enter__(self) -> _Progress:
        self._redirect.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.close()
        self._redirect.__exit__(None, None, None)

    def update(self, t: float, **postfix: Any) -> None:
        """Move the bar to simulated time ``t``."""
        if self.bar is not None:
            self.bar.update(t - self._t)
            self.bar.set_postfix(postfix, refresh=False)
            self._t = t


class _Run:
    """State and bookkeeping of one run (see :func:`run`)."""

    def __init__(self, model: ContactModel, time: TimeSpec, output: OutputSpec) -> None:
        if not (time.dt > 0 and time.end_time >= 0 and time.max_cutbacks >= 0):
            raise ValueError(f"invalid time settings: {time}")
        self.model, self.time, self.output = model, time, output
        self.comm = comm = model.comm
        self.directory = pathlib.Path(comm.bcast(
            str(pathlib.Path(output.directory).resolve()) if comm.rank == 0 else None, root=0))
        if comm.rank == 0:
            self.directory.mkdir(parents=True, exist_ok=True)
        comm.barrier()
        self.wall0 = _time.perf_counter()
        self.steps = 0
        self.iterations: list[int] = []
        self.failed_steps = 0
        self.failed_iterations = 0
        self.cutbacks = 0
        self.min_dt = time.dt
        self.static: dict[str, Any] = {}
        self.static_iterations = 0
        self.rows: list[dict[str, float]] = []
        self.peaks: dict[str, dict[str, float]] = {}
        self.stepper: GN22 | None = None
        self.history: out.HistoryWriter | None = None
        self.fields: list[out.BodyFields] = []
        self.writer: out.FieldWriter | None = None
        self.snapshot: list[fem.Function] = []
        self.snapshot_time: float | None = None
        self.nodes: Sequence[InterfaceNodes] = ()
        self.monitor: Monitor | None = None
        self.fields_time = 0.0  # time of the last VTX output

    # --- set-up and static state --------------------------------------------------

    def start(self) -> None:
        m, time, output = self.model, self.time, self.output
        if output.checkpoint_interval:
            log.warning("checkpoint_interval is not implemented yet: no checkpoints")
        log.info("static equilibrium under gravity (%d cells, %d bodies, %d contact pairs)",
                 m.comm.allreduce(m.mesh.topology.index_map(m.mesh.topology.dim).size_local),
                 len(m.bodies), len(m.pairs))
        m.set_time(0.0)
        u_static, self.static_iterations = solve_static(m)
        log.info("static: %d Newton iterations", self.static_iterations)
        newton = NewtonOptions(rtol=time.newton_rtol, atol=time.newton_atol,
                               max_it=time.newton_max_it)
        params = GN22Parameters(time.beta1, time.beta2, time.allow_conditional)
        self.stepper = s = GN22(m, time.dt, params, newton=newton)
        s.initialise(u_static)
        self.nodes = s.nodes or interface_nodes(m)
        self.ledger = EnergyLedger(s)
        self.monitor = Monitor(m, s, output, self.nodes)
        self.history = out.HistoryWriter(self.directory / out.HISTORY, self.monitor.columns,
                                         self.comm)
        self.fields = [out.BodyFields(m, i) for i in range(len(m.bodies))]
        if output.field_interval > 0:
            self.writer = out.FieldWriter(self.fields, self.directory, self.comm)
        self.snapshot = m.functions("u_snapshot")
        self._record(0.0, self.static_iterations)
        self._static_summary()
        if self.writer is not None:
            self.writer.write(0.0, s.u, s.v)

    def _static_summary(self) -> None:
        m, r = self.model, self.rows[0]
        assert self.stepper is not None
        interface = interface_state(m, self.nodes, self.stepper.u)
        static: dict[str, Any] = {"newton_iterations": self.static_iterations}
        if m.pairs:
            slave = m.pairs[0].slave
            weight = m.weight()[slave]
            length, resultant = r["contact_length_0"], r["normal_force_0"]
            pressure = interface["pair0_pressure"]
            first, last, centre = _edge_centre(interface["pair0_x"])
            static.update({
                "slave": m.bodies[slave].spec.name,
                "weight": weight,
                "contact_resultant": resultant,
                "contact_length": length,
                "mean_contact_pressure": resultant / length if length > 0 else None,
                "edge_pressure": 0.5 * (pressure[first] + pressure[last]),
                "edge_pressures": [pressure[first], pressure[last]],
                "center_pressure": pressure[centre],
                "max_pressure": float(pressure.max()),
                "resultant_over_weight": resultant / weight if weight > 0 else None,
            })
        self.static = static
        arrays = out.snapshot_arrays(self.fields, self.stepper.u, interface, 0.0, self.comm)
        if arrays is not None:
            out.atomic_savez(self.directory / out.STATIC, **arrays)

    # --- time loop ----------------------------------------------------------------

    def _record(self, dt: float, iterations: int) -> dict[str, float]:
        assert self.monitor is not None and self.history is not None
        assert self.stepper is not None
        row = self.monitor.row(dt, iterations, self.ledger.record().as_dict())
        self.rows.append(row)
        self.history.append(row)
        t = row["t"]
        for name, _ in self.monitor.probes:
            ux = row[f"{name}_ux"]
            peak = self.peaks.setdefault(name, {"value": ux, "time": t})
            if abs(ux) > abs(peak["value"]) or not self.rows[1:]:
                peak.update(value=ux, time=t)
                if name == self.monitor.probes[0][0]:
                    for dst, src in zip(self.snapshot, self.stepper.u, strict=True):
                        dst.x.array[:] = src.x.array
                    self.snapshot_time = t
        return row

    def _finite(self, *functions: fem.Function) -> bool:
        """Whether every value of the Functions is finite, on every rank."""
        ok = all(np.isfinite(f.x.array).all() for f in functions)
        return bool(self.comm.allreduce(ok, op=MPI.LAND))

    def loop(self) -> None:
        s, time, output = self.stepper, self.time, self.output
        assert s is not None
        show = output.progress if output.progress is not None else sys.stderr.isatty()
        progress = _Progress(time.end_time, bool(show) and self.comm.rank == 0,
                             output.case_name)
        h = time.dt          # current step size (halved on failure, regrown after)
        halvings = 0         # halvings of the nominal step in effect
        streak = 0           # accepted steps since the last change of step size
        accepted = [float(s.t.value)]
        log.info("time stepping to t = %g s with dt = %g s", time.end_time, time.dt)
        with progress:
            while True:
                t = float(s.t.value)
                remaining = time.end_time - t
                if remaining <= 1e-9 * time.dt:
                    break
                last = remaining <= h * (1.0 + 1e-6)
                trial = remaining if last and abs(remaining - h) > 1e-9 * h else h
                try:
                    s.stage(trial)
                    its = s.solve()
                    if not self._finite(*s.da):
                        raise ConvergenceError("non-finite acceleration increment", 0, its)
                except (ConvergenceError, PETSc.Error) as e:
                    # The state (u, v, a) is untouched until update(): retry from it.
                    self.failed_steps += 1
                    self.failed_iterations += getattr(e, "iterations", 0)
                    if halvings >= time.max_cutbacks:
                        raise SimulationFailed(
                            f"step from t = {t:.6g} s with dt = {trial:.3g} s did not "
                            f"converge after {halvings} cut-backs: {e}") from e
                    halvings += 1
                    self.cutbacks += 1
                    h = 0.5 * trial
                    self.min_dt = min(self.min_dt, h)
                    streak = 0
                    log.warning("t = %.6g s: %s; retrying with dt = %.3g s (cut-back %d/%d)",
                                t, e, h, halvings, time.max_cutbacks)
                    continue
                s.update()
                # The time is the exactly rounded sum of the steps (no drift), and the
                # end time exactly on the last step.
                accepted.append(trial)
                s.t.value = time.end_time if last else math.fsum(accepted)
                if not self._finite(*s.u, *s.v, *s.a):
                    raise SimulationFailed(f"non-finite state after the step to "
                                           f"t = {float(s.t.value):.6g} s")
                self.steps += 1
                self.iterations.append(its)
                row = self._record(trial, its)
                log.debug("t = %.6g s, dt = %.3g s, %d Newton iterations", row["t"], trial,
                          its)
                if self.writer is not None and self.steps % output.field_interval == 0:
                    self.writer.write(row["t"], s.u, s.v)
                    self.fields_time = row["t"]
                streak += 1
                if halvings > 0 and streak >= GROW_AFTER:
                    halvings -= 1
                    h = min(2.0 * h, time.dt)
                    streak = 0
                    log.info("t = %.6g s: step size back to dt = %.3g s", row["t"], h)
                progress.update(row["t"], its=its, cutbacks=self.cutbacks)

    # --- end ----------------------------------------------------------------------

    def finish(self, finished: bool, error: str | None) -> dict[str, Any]:
        """Write the remaining outputs and the summary (collective)."""
        s = self.stepper
        if self.history is not None:
            self.history.close()
        if self.writer is not None and s is not None:
            # The last accepted state, unless already written (or the state is not
            # the accepted one: a non-finite step is not written).
            t = self.rows[-1]["t"] if self.rows else None
            if t is not None and float(s.t.value) == t and self.fields_time != t:
                self.writer.write(t, s.u, s.v)
            self.writer.close()
        if s is not None and self.snapshot_time is not None:
            interface = interface_state(self.model, self.nodes, self.snapshot)
            arrays = out.snapshot_arrays(self.fields, self.snapshot, interface,
                                         self.snapshot_time, self.comm)
            if arrays is not None:
                out.atomic_savez(self.directory / out.SNAPSHOT, **arrays)
        return self.summary(finished, error)

    def summary(self, finished: bool, error: str | None) -> dict[str, Any]:
        rows, its = self.rows, self.iterations
        dynamic: dict[str, Any] = {}
        if rows and self.monitor is not None:
            end = rows[-1]
            dynamic["peak_ux"] = {k: dict(v) for k, v in self.peaks.items()}
            dynamic["residual_ux"] = {name: end[f"{name}_ux"] for name, _ in self.monitor.probes}
            dynamic["residual_uy"] = {name: end[f"{name}_uy"] for name, _ in self.monitor.probes}
            first = self.monitor.probes[0][0] if self.monitor.probes else None
            dynamic["time_of_max_ux"] = self.peaks[first]["time"] if first else None
            pairs: dict[str, Any] = {}
            for pp in self.monitor.pair_probes:
                slip = np.array([r[f"{pp.name}_slip"] for r in rows])
                opening = np.array([r[f"{pp.name}_opening"] for r in rows])
                k = int(np.argmax(opening))
                pairs[pp.name] = {"residual_slip": slip[-1], "residual_opening": opening[-1],
                                  # the static (frictionless) state may already slip a bit
                                  "static_slip": slip[0], "slip_change": slip[-1] - slip[0],
                                  "max_abs_slip": float(np.abs(slip).max()),
                                  "max_opening": opening[k], "time_of_max_opening": rows[k]["t"]}
            dynamic["pair_probes"] = pairs
            names = [pp.name for pp in self.monitor.pair_probes]
            dynamic["residual_slip"] = pairs[names[0]]["residual_slip"] if names else None
            dynamic["max_uplift"] = max((p["max_opening"] for p in pairs.values()),
                                        default=None)
        balance = [abs(r["balance_error"]) for r in rows]
        summary: dict[str, Any] = {
            "case_name": self.output.case_name,
            "finished": finished,
            "error": error,
            "time": {"end_time": self.time.end_time, "dt": self.time.dt,
                     "reached": rows[-1]["t"] if rows else None},
            "static": self.static,
            "dynamic": dynamic,
            "solver": {
                "steps": self.steps,
                "newton_iterations": int(sum(its)),
                "mean_newton_iterations": float(np.mean(its)) if its else None,
                "max_newton_iterations": int(max(its)) if its else None,
                "failed_steps": self.failed_steps,
                "failed_newton_iterations": self.failed_iterations,
                "cutbacks": self.cutbacks,
                "min_dt": self.min_dt,
                "flip_corrections": self.stepper.flips if self.stepper is not None else 0,
                "wall_time": _time.perf_counter() - self.wall0,
            },
            "energy": {"max_balance_error": max(balance) if balance else None,
                       "final": {k: rows[-1][k] for k in FIELDS} if rows else None},
            "outputs": {"directory": str(self.directory), "history": out.HISTORY,
                        "fields": [p.name for p in self.writer.paths] if self.writer else [],
                        "static": out.STATIC,
                        "snapshot": out.SNAPSHOT if self.snapshot_time is not None else None},
            "versions": versions(self.comm),
        }
        return summary


def run(model: ContactModel, time: TimeSpec, output: OutputSpec,
        resolved_case: Mapping[str, Any] | None = None,
        extra_summary: Mapping[str, Any] | None = None, *, report: bool = True,
        ) -> dict[str, Any]:
    """Run a case: static equilibrium, time stepping, outputs (collective).

    Args:
        model: The contact model (loads, damping, gravity included).
        time: Time step, end time, GN22 and Newton settings.
        output: Output directory, probes, output switches.
        resolved_case: The resolved case, written as ``case.toml`` when given.
        extra_summary: Merged into the summary (e.g. calibration results).
        report: Print a short report of the results at the end (rank 0).

    Returns:
        The summary, also written to ``summary.json`` (the same on every rank).

    Raises:
        SimulationFailed: The run stopped before ``time.end_time``; the outputs up to
            the last accepted step are written, with ``finished: false``.
    """
    r = _Run(model, time, output)
    comm = r.comm
    if resolved_case is not None and comm.rank == 0:
        out.atomic_write_toml(r.directory / out.CASE, resolved_case)
    error: BaseException | None = None
    try:
        r.start()
        r.loop()
    except (BreakwaterError, KeyboardInterrupt) as e:
        error = e
    message = None if error is None else (str(error) or type(error).__name__)
    summary = r.finish(error is None, message)
    if extra_summary:
        _merge(summary, extra_summary)
    if comm.rank == 0:
        out.atomic_write_json(r.directory / out.SUMMARY, summary)
        if output.figures:
            from . import figures

            try:
                drawn = figures.make_figures(r.directory)
            except Exception:
                if error is None:
                    raise
                log.exception("the figures of the failed run could not be drawn")
            else:
                summary["outputs"]["figures"] = [str(p.relative_to(r.directory))
                                                 for p in drawn]
                out.atomic_write_json(r.directory / out.SUMMARY, summary)
        if report:
            print(out.format_report(summary, r.directory), flush=True)
    summary = comm.bcast(summary, root=0)
    if error is not None:
        if isinstance(error, KeyboardInterrupt):
            raise error
        log.error("run failed: %s", summary["error"])
        raise SimulationFailed(summary["error"], summary) from error
    return summary
