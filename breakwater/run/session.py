"""The objects of one run and its bookkeeping, between the steps of the time loop.

:class:`Stepped` is the GN22 stepper with the objects bound to its state (energy
ledger, history monitor, peak snapshot, the run's files). :mod:`breakwater.run.begin`
builds it for a :class:`Session`, from the static equilibrium (``begin.start``) or from
a checkpoint (``begin.restore``). The time loop (:mod:`breakwater.run.simulation`) steps the
stepper and calls :meth:`Session.record` after each accepted step (one history row,
measured by the :class:`~breakwater.outputs.monitor.Monitor`), :meth:`Session.checkpoint`,
and at the end :meth:`Session.finish`. The bookkeeping a checkpoint saves is
:attr:`Session.state` (:class:`~breakwater.run.runstate.RunState`).
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import logging
import pathlib
import time as _time
from collections.abc import Mapping
from typing import Any

from dolfinx import fem

from breakwater.casefile.frictionchecks import model_warnings as regularisation_warnings
from breakwater.common import files, folderlock, liveness
from breakwater.common.parallel import on_rank_zero
from breakwater.config.runspec import OutputSpec, TimeSpec
from breakwater.energy.ledger import EnergyLedger
from breakwater.model.model import ContactModel
from breakwater.outputs import summary as sm
from breakwater.outputs.applied import AppliedLoads, applied_warnings, compare
from breakwater.outputs.bodysizes import initial_motion, unit_checks
from breakwater.outputs.historyrows import HistoryRows
from breakwater.outputs.monitor import Monitor, interface_state
from breakwater.outputs.stormrecord import write_storm_record
from breakwater.outputs.writers import RunFiles
from breakwater.run import runstate
from breakwater.run.runstate import RunState
from breakwater.stepping.gn22 import GN22, GN22Parameters
from breakwater.stepping.solver import NewtonOptions

__all__ = ["Session", "Stepped"]

log = logging.getLogger("breakwater.run.simulation")  # the run's logger: rank 0 only in run()

ADAPTIVE_CACHE = 8
"""Adaptive steps: factorisations kept at most (distinct step sizes, the latest used)."""


class Stepped:
    """The GN22 stepper and the objects bound to its state.

    Args:
        model: The contact model.
        time: The time settings (step, GN22 and Newton parameters).
        output: The probes and the field output interval.
        directory: The output folder.
        solver: The step solver, ``"fast"`` or ``"reference"`` (``time.solver``'s choice:
            :func:`breakwater.run.begin.step_solver`).

    Attributes:
        stepper: The GN22 stepper (its pairs, :attr:`~breakwater.stepping.gn22.GN22.contacts`,
            are the ones every object here measures).
        ledger: The energy ledger.
        monitor: Measures one history row per step.
        peak: The state at the largest |u_x| of the first probe.
        files: The files written as the run steps.

    """

    def __init__(self, model: ContactModel, time: TimeSpec, output: OutputSpec,
                 directory: pathlib.Path, solver: str) -> None:
        newton = NewtonOptions(rtol=time.newton_rtol, atol=time.newton_atol,
                               max_it=time.newton_max_it)
        params = GN22Parameters(time.beta1, time.beta2, time.allow_conditional)
        self.stepper = s = GN22(model, time.dt, params, newton=newton, solver=solver)
        if s.fast is not None and time.levels:  # adaptive steps: a factorisation per level
            s.fast.factorisations.cache_size = max(s.fast.factorisations.cache_size,
                                                   min(time.levels + 1, ADAPTIVE_CACHE))
        self.ledger = EnergyLedger(s)
        self.monitor = Monitor(model, s, output)
        self.peak = sm.PeakSnapshot(model, self.monitor.probes.names)
        self.files = RunFiles(model, s.contacts, directory, output.field_interval)

    def functions(self) -> list[list[fem.Function]]:
        """The Functions of each body that a checkpoint saves."""
        s, ledger = self.stepper, self.ledger
        return [[s.u[i], s.v[i], s.a[i], ledger.u0[i], ledger.v0[i], self.peak.u[i]]
                for i in range(len(s.u))]

    def record(self, dt: float, iterations: int) -> dict[str, float]:
        """Measure the stepper's state: one history row, written (collective)."""
        assert self.files.history is not None
        with contextlib.ExitStack() as stack:  # each general pair's state gathered once
            for pair in self.stepper.contacts:
                if hasattr(pair, "recording"):
                    stack.enter_context(pair.recording())
            row = self.monitor.row(dt, iterations, self.ledger.record().as_dict())
        self.files.history.append(row)
        self.peak.update(row, self.stepper.u)
        return row

    def saved(self, state: RunState, wall_time: float) -> RunState:
        """A copy of ``state`` with these objects' state, to save in a checkpoint."""
        s, history = self.stepper, self.files.history
        assert history is not None
        return dataclasses.replace(
            state, history_rows=history.rows, wall_before=wall_time,
            stepper={"dt": float(s.dt.value), "flips": s.flips,
                     "floor_accepts": s.solver.floor_accepts, "memory": s.solver.memory(),
                     "rescues": s.fast.newton.rescues if s.fast is not None else 0,
                     "halvings": s.fast.newton.halvings if s.fast is not None else 0},
            ledger=self.ledger.state(), snapshot={"time": self.peak.time,
                                                  "value": self.peak.value})

    def resume(self, state: RunState) -> None:
        """Set these objects' state from a checkpoint's (the nodal values set already)."""
        s = self.stepper
        s.t.value, s.dt.value = state.step.t, state.stepper["dt"]
        s.flips, s.solver.floor_accepts = state.stepper["flips"], state.stepper["floor_accepts"]
        if s.fast is not None:  # (a checkpoint from before the rescue existed: none)
            s.fast.newton.rescues = state.stepper.get("rescues", 0)
            s.fast.newton.halvings = state.stepper.get("halvings", 0)
        s.solver.restore(state.stepper["memory"])
        s.model.set_time(state.step.t)  # a staged field's stage, for the ledger
        self.ledger.restore(state.ledger)
        self.peak.time, self.peak.value = state.snapshot["time"], state.snapshot["value"]


class Session:
    """One run: its stepped objects and bookkeeping, from set-up to the summary.

    Args:
        model: The contact model.
        time: The time settings.
        output: The output settings.
        fingerprint: Identifies the case in checkpoints.
        extra_summary: Merged into the summary.

    Attributes:
        state: The bookkeeping a checkpoint saves.
        rows: The history rows so far (the static state's first), kept as one array.
        stepped: The stepper and its objects (built by :func:`breakwater.run.begin.start`
            or :func:`breakwater.run.begin.restore`).
        checkpointed: The latest checkpoint written (``summary.json``'s ``checkpoint``).

    """

    def __init__(self, model: ContactModel, time: TimeSpec, output: OutputSpec,
                 fingerprint: str, extra_summary: Mapping[str, Any] | None = None) -> None:
        if not (time.dt > 0 and time.end_time >= 0 and time.max_cutbacks >= 0):
            raise ValueError(f"invalid time settings: {time}")
        if output.checkpoint_interval < 0:
            raise ValueError(f"invalid checkpoint interval {output.checkpoint_interval}")
        self.model, self.time, self.output = model, time, output
        self.fingerprint = fingerprint
        self.extra = dict(extra_summary or {})
        self.extra.setdefault("fixed", model.fixed_summary())  # what holds the bodies
        if "mesh" not in self.extra:  # a model built in Python: a case file's unit checks
            self.extra["mesh"] = unit_checks(model)
        # The gravity and initial velocities applied: the model's now (set after a case's
        # build, or in Python), beside each body's mass to check the momentum by hand.
        self.extra["gravity"] = [float(g) for g in model.gravity.value]
        mesh = self.extra["mesh"]
        if isinstance(mesh, dict) and isinstance(mesh.get("bodies"), dict):
            initial_motion(mesh["bodies"], model.initial.velocities)
            # χ against the run's scales, any model's: logged when the run starts (a copy:
            # the caller's extra_summary, run again, would collect them twice)
            if chi := regularisation_warnings(model, time, mesh["bodies"]):
                self.extra["mesh"] = {**mesh, "warnings": [*mesh.get("warnings", ()), *chi]}
        self.comm = model.comm
        self.directory = files.make_directory(output.directory, self.comm)
        self.wall0 = _time.perf_counter()
        self.process = liveness.this_process()  # rank 0's is written: who runs the folder
        self.state = RunState.start(time)
        self.rows = HistoryRows(())  # (the run's columns once its history is opened)
        self.stepped: Stepped | None = None
        self.checkpointed: dict[str, Any] | None = None
        self.applied: AppliedLoads | None = None
        self._warned: set[tuple[str, str]] = set()
        # The work of the run, estimated before it starts: steps × unknowns.
        dofs = sum(b.V.dofmap.index_map.size_global * b.V.dofmap.index_map_bs
                   for b in model.bodies)
        self.work = {"steps_planned": time.planned_steps, "dofs": int(dofs),
                     "estimate": time.planned_steps * int(dofs),
                     "max_steps": time.max_steps, "max_cutbacks": time.max_cutbacks,
                     "min_dt": time.min_dt}

    def record(self, dt: float, iterations: int) -> dict[str, float]:
        """Measure the stepper's state: one history row, written (collective)."""
        assert self.stepped is not None
        row = self.stepped.record(dt, iterations)
        self.rows.append(row)
        if self.applied is not None:
            s = self.stepped.stepper
            t = float(s.t.value)
            self.applied.record(t, s.start_amplitudes if t == s.start_time else None)
        return row

    def checkpoint(self) -> None:
        """Save the state after the last accepted step (collective)."""
        x = self.stepped
        assert x is not None and x.files.history is not None
        history = x.files.history
        history.sync()  # the rows the checkpoint counts are on disk before it
        runstate.save(self.directory, self.fingerprint, [b.spec.name for b in self.model.bodies],
                      history.columns, x.saved(self.state, self.wall_time()), x.functions(),
                      self.comm)
        t, steps = self.state.step.t, self.state.steps
        self.checkpointed = {"file": files.CHECKPOINT, "t": t, "steps": steps,
                             "history_rows": history.rows}
        self.write_summary(self.summary(False, None, "running"))
        log.debug("checkpoint at t = %.6g s (step %d)", t, steps)

    def finish(self, finished: bool, error: str | None, status: str) -> dict[str, Any]:
        """Write the remaining outputs and return the summary (collective)."""
        x = self.stepped
        if x is not None:
            # The last accepted state, unless already written (or the state is not
            # the accepted one: a non-finite step is not written).
            s, t = x.stepper, self.rows[-1]["t"] if self.rows else None
            if t is not None and float(s.t.value) == t and self.state.fields_time != t:
                x.files.write_fields(t, s.u, s.v)
            x.files.close()
            if x.peak.time is not None:
                interface = interface_state(x.stepper.contacts, x.peak.u)
                x.files.write_snapshot(files.SNAPSHOT, x.peak.u, interface, x.peak.time)
        summary = self.summary(finished, error, status)
        if finished:
            for line in applied_warnings(summary.get("loads", {})):
                log.warning("%s", line)
        write_storm_record(self.model, self.rows, summary, self.directory)
        return summary

    def close(self) -> None:
        """Free the stepper's and the ledger's PETSc objects (collective; after the summary)."""
        if self.stepped is not None:
            self.stepped.ledger.destroy()
            self.stepped.stepper.destroy()

    def wall_time(self) -> float:
        """Wall time of the run so far, earlier parts of a resumed run included (s)."""
        return self.state.wall_before + _time.perf_counter() - self.wall0

    def write_summary(self, summary: Mapping[str, Any]) -> None:
        """Write ``summary.json`` (rank 0; collective: an OutputError on every rank).

        A summary that ends the run (any status but ``running``) is written on a full
        disk too, in the room the folder's lock keeps for it
        (:func:`~breakwater.common.folderlock.write_final_summary`).
        """
        data = {**summary, "process": self.process}
        path = self.directory / files.SUMMARY
        if data.get("status") == "running":
            on_rank_zero(self.comm, lambda: bool(files.atomic_write_json(path, data)))
        else:
            on_rank_zero(self.comm, lambda: folderlock.write_final_summary(path, data))

    def log_quality(self, dynamic: bool = False) -> None:
        """Log (rank 0) the warnings of the contact quality not logged yet.

        Args:
            dynamic: Include the largest penetration over the steps so far.
        """
        steps = self.rows[1:] if dynamic else []
        for name, q in sm.contact_quality(self.state.contact, steps).items():
            for issue, message in zip(q.issues, q.warnings, strict=True):
                if (name, issue) not in self._warned:
                    self._warned.add((name, issue))
                    log.warning("%s", message)

    def summary(self, finished: bool, error: str | None, status: str) -> dict[str, Any]:
        """The summary of the run so far (:func:`~breakwater.outputs.summary.run_summary`).

        Args:
            finished: Whether the end time was reached.
            error: Why the run stopped early.
            status: ``running``, ``finished``, ``failed`` or ``interrupted``.
        """
        st, x = self.state, self.stepped
        s = x.stepper if x is not None else None
        solver = sm.solver_summary(
            st.steps, st.iterations, st.failed_steps, st.failed_iterations,
            st.step.cutbacks, st.step.min_dt, s.flips if s is not None else 0,
            s.solver.floor_accepts if s is not None else 0, self.wall_time(),
            kind=s.kind if s is not None else self.time.solver, time_loop=st.time_loop)
        if st.step.adaptive:
            taken = st.step.accepted[1:]
            solver["adaptive"] = {
                "tolerance": st.step.tolerance, "smallest_allowed_dt": st.step.dt
                / 2**st.step.levels, "rejected_steps": st.step.rejected,
                "smallest_dt": min(taken, default=None), "largest_dt": max(taken, default=None)}
        if s is not None and s.fast is not None:
            solver["elimination"] = s.fast.factorisations.describe()
            # Solves that converged only by a continuation in χ, or done again with
            # their overshooting steps halved (InterfaceNewton's rescues).
            solver["newton_continuations"] = s.fast.newton.continuations
            solver["newton_rescues"] = s.fast.newton.rescues
            solver["newton_halvings"] = s.fast.newton.halvings  # the steps halved in them
        outputs = files.outputs_entry(
            self.directory, [*st.field_parts, *(x.files.field_files if x else [])],
            snapshot=x is not None and x.peak.time is not None, static=bool(st.static))
        return {**sm.run_summary(
            case_name=self.output.case_name, finished=finished, status=status, error=error,
            time=self.time, static=st.static, resumed_from=st.resumed_from, rows=self.rows,
            probes=x.monitor.probes if x is not None else None,
            contact_quality=sm.contact_quality(st.contact, self.rows[1:]), solver=solver,
            checkpoint=self.checkpointed, outputs=outputs, comm=self.comm,
            extra=self._extra(), dimension=self.model.gdim,
            bodies=x.monitor.rotations.names if x is not None else ()), "work": self.work}

    def _extra(self) -> dict[str, Any]:
        """``extra_summary`` with the loads applied so far (requested against applied)."""
        extra = copy.deepcopy(self.extra)
        if self.applied is not None:
            sm.merge(extra, {"loads": self.applied.summary()})
            sm.merge(extra, {"loads": compare(extra["loads"])})
        if self.model.gdim == 3 and "loads" in extra:
            extra["loads"] = sm.whole_body_keys(extra["loads"])
        return extra
