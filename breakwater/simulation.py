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
   :mod:`breakwater.figures`, and a contact quality report per pair
   (:mod:`breakwater.quality`: penetration against the element size and the static
   settlement, penalty stiffness against E/h; ``contact_quality`` in the summary).

Checkpoints (:mod:`breakwater.checkpoint`): with ``output.checkpoint_interval`` = N >
0 the state is saved every N steps (``checkpoint.npz``, atomically, the latest only;
removed when the run finishes), and ``run(..., resume=True)`` continues from it:
``history.csv`` is cut back to the rows of the checkpoint and the run goes on, giving
the same history as an uninterrupted run (bit for bit serially). ``summary.json`` exists
from the start of a run (``status: "running"``) and is rewritten at every checkpoint,
so a killed run's folder says that it did not finish. On SIGTERM the run stops at the
next step boundary (all ranks together), writes a checkpoint (when N > 0) and the
outputs, with ``status: "interrupted"``, and raises :class:`RunInterrupted`; a second
SIGTERM kills it at once.

Every rank runs the same code (all measurements are collective and give the same
values on every rank); only rank 0 writes files, logs and prints.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import pathlib
import platform
import signal
import sys
import threading
import time as _time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from . import __version__, forms, quality  # type: ignore[attr-defined]
from . import checkpoint as ckpt
from . import outputs as out
from .checkpoint import CheckpointError
from .errors import BreakwaterError, ConvergenceError
from .gn22 import GN22, GN22Parameters, solve_static
from .interface import InterfaceNodes, interface_nodes
from .ledger import FIELDS, EnergyLedger
from .model import ContactModel
from .probes import PointProbe
from .runspec import OutputSpec, PairProbeSpec, TimeSpec
from .solver import NewtonOptions

__all__ = ["GROW_AFTER", "RunInterrupted", "SimulationFailed", "run"]

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


class RunInterrupted(SimulationFailed):
    """The run stopped on a signal (SIGTERM); ``summary.json`` says ``interrupted``."""


class _Stop(BreakwaterError):
    """Raised inside the time loop when a stop signal was received."""


class _StopSignal:
    """Catches SIGTERM: the run stops at the next step boundary.

    The handler only sets a flag (the time loop polls it collectively, so that every
    rank stops at the same step) and restores the default action, so a second
    SIGTERM kills the process at once. Installed only from the main thread.
    """

    SIGNALS = (signal.SIGTERM,)

    def __init__(self) -> None:
        self.received = 0
        self._previous: dict[int, Any] = {}

    def _handle(self, signum: int, frame: object) -> None:
        self.received = signum
        signal.signal(signum, signal.SIG_DFL)

    def __enter__(self) -> _StopSignal:
        if threading.current_thread() is threading.main_thread():
            for sig in self.SIGNALS:
                self._previous[sig] = signal.signal(sig, self._handle)
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, previous in self._previous.items():
            signal.signal(sig, previous)
        self._previous.clear()


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

    Columns: ``t``, ``dt``, ``newton_iterations``; ``<probe>_ux``, ``<probe>_uy``;
    ``<pair probe>_<key>`` (see :class:`_PairProbe`); per contact pair ``k``:
    ``contact_length_k`` (length where g_n ≤ 0), ``normal_force_k``,
    ``tangential_force_k`` (resultants on the slave), ``penetration_k`` (largest
    nodal ⟨−g_n⟩₊, m); the ledger's :data:`~breakwater.ledger.FIELDS`.

    Args:
        model: The contact model.
        stepper: The GN22 stepper (its ``u``, ``v`` are measured).
        output: The probes.
        nodes: Interface nodes of every pair.

    """

    def __init__(self, model: ContactModel, stepper: GN22, output: OutputSpec,
                 nodes: Sequence[InterfaceNodes]) -> None:
        self.model, self.stepper = model, stepper
        self.nodes = nodes
        self.probes = [(p.name, PointProbe(model, p.body, p.point, p.name))
                       for p in output.probes]
        self.pair_probes = [_PairProbe(model, p, nodes) for p in output.pair_probes]
        u, v = stepper.u, stepper.v
        self._contact = []
        for p in model.pairs:
            us, um = u[p.slave]("+"), u[p.master]("-")
            g_n = p.law.gap(us, um, p.n)
            pressure = p.law.normal.pressure(g_n)
            traction = model.traction(p, u, v)
            if model.gdim == 2:
                t = ufl.as_vector((p.n[1], -p.n[0]))
                tangential = ufl.dot(traction, t)
            else:
                tangential = ufl.sqrt(ufl.dot(forms.tangential_part(traction, p.n),
                                              forms.tangential_part(traction, p.n)))
            self._contact.append(tuple(model.form(f * p.dS) for f in (
                p.law.normal.closed(g_n), pressure, tangential)))
        self.columns = ["t", "dt", "newton_iterations"]
        for name, _ in self.probes:
            self.columns += [f"{name}_ux", f"{name}_uy"]
        for pp in self.pair_probes:
            self.columns += [f"{pp.name}_{k}" for k in _PairProbe.KEYS]
        for k in range(len(model.pairs)):
            self.columns += [f"contact_length_{k}", f"normal_force_{k}",
                             f"tangential_force_{k}", f"penetration_{k}"]
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
        for k, (p, nd) in enumerate(zip(self.model.pairs, self.nodes, strict=True)):
            gap = nd.contact_state(s.u[p.slave].x.array, s.u[p.master].x.array)["gap"]
            r[f"penetration_{k}"] = quality.max_penetration(gap)
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
        state = nd.contact_state(u[p.slave].x.array, u[p.master].x.array)
        data[f"pair{k}_x"] = nd.x
        data[f"pair{k}_normal"] = nd.normal
        data[f"pair{k}_gap"] = state["gap"]
        if model.gdim == 2:
            data[f"pair{k}_slip"] = np.sum(state["slip"] * nd.tangents[:, 0], axis=1)
        data[f"pair{k}_pressure"] = state["pressure"]
    return data


def _resting_on(model: ContactModel, body: int) -> set[int]:
    """A body and every body resting on it: the slaves of pairs whose master is one of them.

    Under gravity their weight is what the body's contacts below it carry.
    """
    found = {body}
    while new := {p.slave for p in model.pairs if p.master in found} - found:
        found |= new
    return found


def pair_names(model: ContactModel) -> list[str]:
    """Names of the contact pairs: the interface group, or the index where it repeats."""
    names = [p.spec.interface for p in model.pairs]
    return [n if names.count(n) == 1 else str(k) for k, n in enumerate(names)]


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

    def __init__(self, end_time: float, enabled: bool, name: str, start: float = 0.0
                 ) -> None:
        self.bar = None
        self._redirect: contextlib.AbstractContextManager[None] = contextlib.nullcontext()
        if enabled:
            from tqdm import tqdm
            from tqdm.contrib.logging import logging_redirect_tqdm

            self.bar = tqdm(total=end_time, initial=start, desc=name, unit="s",
                            file=sys.stderr,
                            bar_format="{desc}: {percentage:3.0f}%|{bar}| t={n:.4g}/"
                                       "{total:.4g} s [{elapsed}<{remaining}{postfix}]")
            self._redirect = logging_redirect_tqdm(
                loggers=[logging.getLogger(), logging.getLogger("breakwater")])
        self._t = start

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

    def __init__(self, model: ContactModel, time: TimeSpec, output: OutputSpec,
                 fingerprint: str, extra_summary: Mapping[str, Any] | None = None) -> None:
        if not (time.dt > 0 and time.end_time >= 0 and time.max_cutbacks >= 0):
            raise ValueError(f"invalid time settings: {time}")
        if output.checkpoint_interval < 0:
            raise ValueError(f"invalid checkpoint interval {output.checkpoint_interval}")
        self.model, self.time, self.output = model, time, output
        self.fingerprint = fingerprint
        self.extra = dict(extra_summary or {})
        self.comm = comm = model.comm
        self.directory = pathlib.Path(comm.bcast(
            str(pathlib.Path(output.directory).resolve()) if comm.rank == 0 else None, root=0))
        if comm.rank == 0:
            self.directory.mkdir(parents=True, exist_ok=True)
        comm.barrier()
        self.wall0 = _time.perf_counter()
        self.wall_before = 0.0  # wall time of the earlier parts of a resumed run
        self.steps = 0
        self.iterations: list[int] = []
        self.failed_steps = 0
        self.failed_iterations = 0
        self.cutbacks = 0
        self.min_dt = time.dt
        self.static: dict[str, Any] = {}
        self.contact: list[dict[str, Any]] = []  # static inputs of the quality report
        self.static_iterations = 0
        self.rows: list[dict[str, float]] = []
        self.peaks: dict[str, dict[str, float]] = {}
        self.stepper: GN22 | None = None
        self.ledger: EnergyLedger | None = None
        self.history: out.HistoryWriter | None = None
        self.fields: list[out.BodyFields] = []
        self.interfaces: list[out.InterfaceFields] = []
        self.writer: out.FieldWriter | None = None
        self.field_parts: list[str] = []  # VTX files of the earlier parts of a resumed run
        self.snapshot: list[fem.Function] = []
        self.snapshot_time: float | None = None
        self.nodes: Sequence[InterfaceNodes] = ()
        self.monitor: Monitor | None = None
        self.fields_time = 0.0  # time of the last VTX output
        # Step-size state of the time loop: current Δt, halvings of the nominal Δt in
        # effect, accepted steps since the last change, accepted step sizes.
        self.h = time.dt
        self.halvings = 0
        self.streak = 0
        self.accepted: list[float] = [0.0]
        self.checkpointed: dict[str, Any] | None = None  # the latest checkpoint written
        self.resumed_from: list[dict[str, Any]] = []
        self.stop = _StopSignal()
        self._warned: set[tuple[str, str]] = set()

    # --- set-up and static state --------------------------------------------------

    def _stepper(self) -> GN22:
        time = self.time
        newton = NewtonOptions(rtol=time.newton_rtol, atol=time.newton_atol,
                               max_it=time.newton_max_it)
        params = GN22Parameters(time.beta1, time.beta2, time.allow_conditional)
        return GN22(self.model, time.dt, params, newton=newton)

    def _measures(self, s: GN22) -> None:
        """The measuring objects of the stepper's state (nodes, ledger, monitor...)."""
        m = self.model
        self.nodes = s.nodes or interface_nodes(m)
        self.ledger = EnergyLedger(s)
        self.monitor = Monitor(m, s, self.output, self.nodes)
        self.fields = [out.BodyFields(m, i) for i in range(len(m.bodies))]
        if self.output.field_interval > 0:
            self.interfaces = [out.InterfaceFields(m, nd, name)
                               for nd, name in zip(self.nodes, pair_names(m), strict=True)]
        self.snapshot = m.functions("u_snapshot")

    def start(self) -> None:
        m = self.model
        log.info("static equilibrium under gravity (%d cells, %d bodies, %d contact pairs)",
                 m.comm.allreduce(m.mesh.topology.index_map(m.mesh.topology.dim).size_local),
                 len(m.bodies), len(m.pairs))
        m.set_time(0.0)
        u_static, self.static_iterations = solve_static(m)
        log.info("static: %d Newton iterations", self.static_iterations)
        self.stepper = s = self._stepper()
        s.initialise(u_static)
        self._measures(s)
        assert self.monitor is not None
        self.history = out.HistoryWriter(self.directory / out.HISTORY, self.monitor.columns,
                                         self.comm)
        if self.output.field_interval > 0:
            self.writer = out.FieldWriter(self.fields, self.interfaces, self.directory,
                                         self.comm)
        self._record(0.0, self.static_iterations)
        self._static_summary()
        self._log_quality()
        if self.writer is not None:
            self.writer.write(0.0, s.u, s.v)

    def _static_summary(self) -> None:
        m, r = self.model, self.rows[0]
        assert self.stepper is not None
        u = self.stepper.u
        interface = interface_state(m, self.nodes, u)
        static: dict[str, Any] = {"newton_iterations": self.static_iterations}
        if m.pairs:
            slave = m.pairs[0].slave
            weights = m.weight()
            weight = sum(weights[i] for i in _resting_on(m, slave))
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
        self.contact = []
        for k, (p, nd, name) in enumerate(zip(m.pairs, self.nodes, pair_names(m),
                                              strict=True)):
            us, um = nd.gather(u[p.slave].x.array, u[p.master].x.array)
            length = m.assemble(m.form(1.0 * p.dS))
            facets = m.comm.allreduce(len(p.facet_data))
            self.contact.append({
                "name": name,
                "penalty": p.spec.penalty,
                "element_size": length / facets,
                "young_moduli": [m.bodies[i].spec.material.E for i in (p.slave, p.master)],
                "static_penetration": quality.max_penetration(interface[f"pair{k}_gap"]),
                "settlement": quality.settlement(us, um, nd.normal),
            })
        arrays = out.snapshot_arrays(self.fields, u, interface, 0.0, self.comm)
        if arrays is not None:
            out.atomic_savez(self.directory / out.STATIC, **arrays)

    def contact_quality(self, dynamic: bool = True) -> dict[str, quality.ContactQuality]:
        """The contact quality of each pair (:mod:`breakwater.quality`).

        Args:
            dynamic: Include the largest penetration over the steps so far.
        """
        report = {}
        steps = self.rows[1:] if dynamic else []
        for k, c in enumerate(self.contact):
            δ, when = None, None
            if steps:
                j = int(np.argmax([r[f"penetration_{k}"] for r in steps]))
                δ, when = steps[j][f"penetration_{k}"], steps[j]["t"]
            report[c["name"]] = quality.assess(
                c["name"], c["penalty"], c["element_size"], tuple(c["young_moduli"]),
                c["static_penetration"], c["settlement"], δ, when)
        return report

    def _log_quality(self, dynamic: bool = False) -> None:
        """Log (rank 0) the warnings of the contact quality not logged yet."""
        for name, q in self.contact_quality(dynamic).items():
            for issue, message in zip(q.issues, q.warnings, strict=True):
                if (name, issue) not in self._warned:
                    self._warned.add((name, issue))
                    log.warning("%s", message)

    # --- checkpoints --------------------------------------------------------------

    def _saved_functions(self) -> list[list[fem.Function]]:
        s, ledger = self.stepper, self.ledger
        assert s is not None and ledger is not None
        return [[s.u[i], s.v[i], s.a[i], ledger.u0[i], ledger.v0[i], self.snapshot[i]]
                for i in range(len(self.model.bodies))]

    def checkpoint(self) -> None:
        """Save the state after the last accepted step (collective)."""
        s, ledger, history = self.stepper, self.ledger, self.history
        assert s is not None and ledger is not None and history is not None
        history.sync()  # the rows the checkpoint counts are on disk before it
        t = float(s.t.value)
        meta = {
            "fingerprint": self.fingerprint,
            "mpi_size": self.comm.size,
            "bodies": [b.spec.name for b in self.model.bodies],
            "t": t, "dt_constant": float(s.dt.value),
            "h": self.h, "halvings": self.halvings, "streak": self.streak,
            "steps": self.steps, "history_rows": history.rows,
            "columns": list(history.columns),
            "iterations": self.iterations, "failed_steps": self.failed_steps,
            "failed_iterations": self.failed_iterations, "cutbacks": self.cutbacks,
            "min_dt": self.min_dt, "flips": s.flips,
            "floor_accepts": s.solver.floor_accepts, "peaks": self.peaks,
            "snapshot_time": self.snapshot_time, "fields_time": self.fields_time,
            "static": self.static, "static_iterations": self.static_iterations,
            "contact": self.contact,
            "ledger": ledger.state(),
            "wall_time": self.wall_time(),
            "resumed_from": self.resumed_from,
            "field_parts": self.field_parts,
        }
        arrays = ckpt.gather_nodal(self._saved_functions(), self.comm)
        if arrays is not None:
            ckpt.write(self.directory / ckpt.CHECKPOINT, meta,
                       {**arrays, "accepted": np.array(self.accepted)})
        self.checkpointed = {"file": ckpt.CHECKPOINT, "t": t, "steps": self.steps,
                             "history_rows": history.rows}
        self.write_summary(self.summary(False, None, "running"))
        log.debug("checkpoint at t = %.6g s (step %d)", t, self.steps)

    def discard_checkpoint(self) -> None:
        """Remove the checkpoint of a finished run (nothing is left to resume)."""
        if self.comm.rank == 0:
            (self.directory / ckpt.CHECKPOINT).unlink(missing_ok=True)
        self.checkpointed = None

    def restore(self) -> None:
        """Continue from the checkpoint of the output folder (collective).

        Nothing in the folder changes until the checkpoint is known to fit.

        Raises:
            CheckpointError: No checkpoint, another case, a finished run, or a history
                that does not reach the checkpoint.
        """
        m, comm = self.model, self.comm
        problem = None
        if comm.rank == 0:
            try:
                ckpt.check(self.directory, self.fingerprint)
            except CheckpointError as e:
                problem = str(e)
        problem = comm.bcast(problem, root=0)
        if problem is not None:
            raise CheckpointError(problem)
        meta, arrays = ckpt.read(self.directory / ckpt.CHECKPOINT, self.fingerprint)
        if meta["bodies"] != [b.spec.name for b in m.bodies]:
            raise CheckpointError(f"the checkpoint's bodies {meta['bodies']} are not the "
                                  "model's")
        if meta["mpi_size"] != comm.size:
            log.warning("resuming on %d ranks a checkpoint written on %d: the continuation "
                        "equals the uninterrupted run to round-off, not bit for bit",
                        comm.size, meta["mpi_size"])
        m.set_time(0.0)  # GN22 scales its tolerances with the loads at t = 0
        self.stepper = s = self._stepper()
        self._measures(s)
        assert self.ledger is not None and self.monitor is not None
        if meta["columns"] != self.monitor.columns:
            raise CheckpointError("the checkpoint's history columns are not the run's")
        ckpt.scatter_nodal(arrays, self._saved_functions())
        s.t.value = meta["t"]
        s.dt.value = meta["dt_constant"]
        s.flips = meta["flips"]
        s.solver.floor_accepts = meta["floor_accepts"]
        self.ledger.restore(meta["ledger"])
        try:
            self.history = out.HistoryWriter(self.directory / out.HISTORY,
                                             self.monitor.columns, comm,
                                             keep_rows=meta["history_rows"])
        except (ValueError, OSError) as e:
            raise CheckpointError(f"cannot resume: {e}") from e
        self.rows = self.history.kept
        if self.rows[-1]["t"] != meta["t"]:
            raise CheckpointError(f"cannot resume: the last history row kept (t = "
                                  f"{self.rows[-1]['t']:.6g} s) is not the checkpoint's "
                                  f"(t = {meta['t']:.6g} s)")
        self.h, self.halvings, self.streak = meta["h"], meta["halvings"], meta["streak"]
        self.accepted = arrays["accepted"].tolist()
        self.steps, self.iterations = meta["steps"], meta["iterations"]
        self.failed_steps = meta["failed_steps"]
        self.failed_iterations = meta["failed_iterations"]
        self.cutbacks, self.min_dt = meta["cutbacks"], meta["min_dt"]
        self.peaks, self.snapshot_time = meta["peaks"], meta["snapshot_time"]
        self.fields_time = meta["fields_time"]
        self.static, self.static_iterations = meta["static"], meta["static_iterations"]
        self.contact = meta["contact"]
        self.wall_before = meta["wall_time"]
        self.resumed_from = [*meta["resumed_from"],
                             {"t": meta["t"], "steps": self.steps, "mpi_size": comm.size}]
        self.field_parts = list(meta["field_parts"])
        if self.output.field_interval > 0:
            self._set_aside_fields()
            self.writer = out.FieldWriter(self.fields, self.interfaces, self.directory,
                                         self.comm)
        self.checkpointed = {"file": ckpt.CHECKPOINT, "t": meta["t"], "steps": self.steps,
                             "history_rows": meta["history_rows"]}
        if comm.rank == 0:  # temporary files of atomic writes cut short by a kill
            for tmp in self.directory.glob(".*.tmp[0-9]*"):
                with contextlib.suppress(OSError):
                    tmp.unlink()
        log.info("resuming from the checkpoint at t = %.6g s (step %d)", meta["t"],
                 self.steps)
        self._log_quality()

    def _set_aside_fields(self) -> None:
        """Rename the VTX files of the interrupted part: ``<file>.part<k>.bp``.

        A VTX file cannot be appended to, so a resumed run writes new ones from the
        checkpoint on; the earlier ones are kept beside them.
        """
        if self.comm.rank == 0:
            for filename in [f.filename for f in self.fields] + \
                    [f.filename for f in self.interfaces]:
                path = self.directory / filename
                if path.exists():
                    k = 1
                    while (target := path.with_suffix(f".part{k}.bp")).exists():
                        k += 1
                    os.replace(path, target)
                    self.field_parts.append(target.name)
        self.field_parts = self.comm.bcast(self.field_parts, root=0)
        self.comm.barrier()

    # --- time loop ----------------------------------------------------------------

    def _record(self, dt: float, iterations: int) -> dict[str, float]:
        assert self.monitor is not None and self.history is not None
        assert self.stepper is not None and self.ledger is not None
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

    def _check_stop(self) -> None:
        """Stop (all ranks together) when a rank received a stop signal."""
        signum = self.comm.allreduce(self.stop.received, op=MPI.MAX)
        if not signum:
            return
        assert self.stepper is not None
        t = float(self.stepper.t.value)
        saved = self.output.checkpoint_interval > 0
        if saved and (self.checkpointed is None or self.checkpointed["steps"] != self.steps):
            self.checkpoint()
        raise _Stop(f"interrupted by {signal.Signals(signum).name} at t = {t:.6g} s"
                    + (" (continue with --resume)" if saved else ""))

    def loop(self) -> None:
        s, time, output = self.stepper, self.time, self.output
        assert s is not None
        show = output.progress if output.progress is not None else sys.stderr.isatty()
        progress = _Progress(time.end_time, bool(show) and self.comm.rank == 0,
                             output.case_name, float(s.t.value))
        interval = output.checkpoint_interval
        log.info("time stepping to t = %g s with dt = %g s", time.end_time, time.dt)
        with progress:
            while True:
                t = float(s.t.value)
                remaining = time.end_time - t
                if remaining <= 1e-9 * time.dt:
                    break
                self._check_stop()
                h = self.h
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
                    if self.halvings >= time.max_cutbacks:
                        raise SimulationFailed(
                            f"step from t = {t:.6g} s with dt = {trial:.3g} s did not "
                            f"converge after {self.halvings} cut-backs: {e}") from e
                    self.halvings += 1
                    self.cutbacks += 1
                    self.h = 0.5 * trial
                    self.min_dt = min(self.min_dt, self.h)
                    self.streak = 0
                    log.warning("t = %.6g s: %s; retrying with dt = %.3g s (cut-back %d/%d)",
                                t, e, self.h, self.halvings, time.max_cutbacks)
                    continue
                s.update()
                # The time is the exactly rounded sum of the steps (no drift), and the
                # end time exactly on the last step.
                self.accepted.append(trial)
                s.t.value = time.end_time if last else math.fsum(self.accepted)
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
                self.streak += 1
                if self.halvings > 0 and self.streak >= GROW_AFTER:
                    self.halvings -= 1
                    self.h = min(2.0 * self.h, time.dt)
                    self.streak = 0
                    log.info("t = %.6g s: step size back to dt = %.3g s", row["t"], self.h)
                if interval > 0 and self.steps % interval == 0:
                    self.checkpoint()
                progress.update(row["t"], its=its, cutbacks=self.cutbacks)

    # --- end ----------------------------------------------------------------------

    def finish(self, finished: bool, error: str | None, status: str) -> dict[str, Any]:
        """Write the remaining outputs and return the summary (collective)."""
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
        return self.summary(finished, error, status)

    def wall_time(self) -> float:
        """Wall time of the run so far, earlier parts of a resumed run included (s)."""
        return self.wall_before + _time.perf_counter() - self.wall0

    def write_summary(self, summary: Mapping[str, Any]) -> None:
        """Write ``summary.json`` (rank 0)."""
        if self.comm.rank == 0:
            out.atomic_write_json(self.directory / out.SUMMARY, summary)

    def summary(self, finished: bool, error: str | None, status: str) -> dict[str, Any]:
        """The summary of the run so far (the extra summary merged in).

        Args:
            finished: Whether the end time was reached.
            error: Why the run stopped early.
            status: ``running``, ``finished``, ``failed`` or ``interrupted``.
        """
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
        fields = [*self.field_parts, *(p.name for p in self.writer.paths)] \
            if self.writer else list(self.field_parts)
        summary: dict[str, Any] = {
            "case_name": self.output.case_name,
            "finished": finished,
            "status": status,
            "error": error,
            "time": {"end_time": self.time.end_time, "dt": self.time.dt,
                     "reached": rows[-1]["t"] if rows else None},
            "static": self.static,
            "dynamic": dynamic,
            "contact_quality": {name: q.as_dict()
                                for name, q in self.contact_quality().items()},
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
                "round_off_accepts": (self.stepper.solver.floor_accepts
                                      if self.stepper is not None else 0),
                "wall_time": self.wall_time(),
            },
            "energy": {"max_balance_error": max(balance) if balance else None,
                       "final": {k: rows[-1][k] for k in FIELDS} if rows else None},
            "checkpoint": self.checkpointed,
            "resumed_from": self.resumed_from,
            "outputs": {"directory": str(self.directory), "history": out.HISTORY,
                        "fields": fields,
                        "static": out.STATIC,
                        "snapshot": out.SNAPSHOT if self.snapshot_time is not None else None},
            "versions": versions(self.comm),
        }
        return _merge(summary, self.extra)


def run(model: ContactModel, time: TimeSpec, output: OutputSpec,
        resolved_case: Mapping[str, Any] | None = None,
        extra_summary: Mapping[str, Any] | None = None, *, report: bool = True,
        resume: bool = False, fingerprint: str | None = None) -> dict[str, Any]:
    """Run a case: static equilibrium, time stepping, outputs (collective).

    Args:
        model: The contact model (loads, damping, gravity included).
        time: Time step, end time, GN22 and Newton settings.
        output: Output directory, probes, output switches, checkpoint interval.
        resolved_case: The resolved case, written as ``case.toml`` when given.
        extra_summary: Merged into the summary (e.g. calibration results).
        report: Print a short report of the results at the end (rank 0).
        resume: Continue the run of ``output.directory`` from its checkpoint.
        fingerprint: Identifies the case in checkpoints; a checkpoint is resumed only
            by a run of the same fingerprint. Default: the hash of ``resolved_case``
            (:func:`~breakwater.checkpoint.case_fingerprint`) when given, else of the
            model, time and probe settings
            (:func:`~breakwater.checkpoint.model_fingerprint`).

    Returns:
        The summary, also written to ``summary.json`` (the same on every rank).

    Raises:
        SimulationFailed: The run stopped before ``time.end_time``; the outputs up to
            the last accepted step are written, with ``finished: false``.
        RunInterrupted: (a SimulationFailed) The run stopped on SIGTERM.
        CheckpointError: ``resume``: no usable checkpoint (the folder is untouched).
    """
    if fingerprint is None:
        fingerprint = (ckpt.case_fingerprint(resolved_case) if resolved_case is not None
                       else ckpt.model_fingerprint(model, time, output))
    r = _Run(model, time, output, fingerprint, extra_summary)
    comm = r.comm
    error: BaseException | None = None
    with r.stop:
        if resume:
            r.restore()  # CheckpointError: nothing written yet
        if resolved_case is not None and comm.rank == 0:
            out.atomic_write_toml(r.directory / out.CASE, resolved_case)
        # From now on the folder always says whether the run finished.
        r.write_summary(r.summary(False, None, "running"))
        try:
            if not resume:
                r.start()
            r.loop()
        except (BreakwaterError, KeyboardInterrupt) as e:
            error = e
        message = None if error is None else (str(error) or type(error).__name__)
        stopped = isinstance(error, _Stop | KeyboardInterrupt)
        status = "finished" if error is None else "interrupted" if stopped else "failed"
        if error is None:
            r.discard_checkpoint()
        summary = r.finish(error is None, message, status)
        if error is None or not stopped:
            r._log_quality(dynamic=True)
        if comm.rank == 0:
            out.atomic_write_json(r.directory / out.SUMMARY, summary)
            if output.figures and not stopped:
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
        log.error("run %s: %s", "interrupted" if stopped else "failed", summary["error"])
        if stopped:
            raise RunInterrupted(summary["error"], summary) from error
        raise SimulationFailed(summary["error"], summary) from error
    return summary
