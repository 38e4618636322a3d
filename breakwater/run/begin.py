"""How a run begins: from the static equilibrium, or from the checkpoint of its folder.

:func:`start` finds the initial state (:func:`~breakwater.statics.initial.initial_state`),
builds the :class:`~breakwater.run.session.Stepped` objects of a
:class:`~breakwater.run.session.Session` on it and records the static state (its
history row, summary, contact quality and files). :func:`restore` builds them from
the checkpoint instead, once it is known to fit the case and the history kept.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater.common import files
from breakwater.common.errors import CaseError
from breakwater.contact.meshedgap import meshed_gap2d, meshed_gap3d
from breakwater.contact.penetration import meshed_overlap
from breakwater.model.model import ContactModel
from breakwater.outputs import summary as sm
from breakwater.outputs.applied import AppliedLoads
from breakwater.outputs.checkpoint import CheckpointError
from breakwater.outputs.monitor import interface_state
from breakwater.outputs.staticsummary import resolution_warnings, static_summary, triangle_row
from breakwater.run import runstate
from breakwater.run.session import Session, Stepped
from breakwater.statics.initial import initial_state
from breakwater.statics.rigidmodes import DriftError, drift, sideways
from breakwater.stepping.solverchoice import choose
from breakwater.stepping.stepsize import StepSize

__all__ = ["restore", "start", "step_solver"]

log = logging.getLogger("breakwater.run.simulation")  # the run's logger: rank 0 only in run()


def step_solver(r: Session) -> str:
    """The run's step solver, ``time.solver``'s choice; its warning line logged (collective).

    Raises:
        BreakwaterError: General pairs whose fast solver does not fit in memory
            (:func:`~breakwater.stepping.solverchoice.choose`).
    """
    solver, line = choose(r.model, r.time.solver)
    if line is not None:
        log.warning("%s", line)
    return solver


def start(r: Session) -> None:
    """Find the initial state, start the stepper from it (collective).

    The static equilibrium under gravity and the loads of the initial state, with
    friction if needed, bodies that friction cannot hold held up to t = 0
    (:func:`~breakwater.statics.initial.initial_state`); at rest but for the bodies'
    initial velocities (``model.initial``).
    """
    m, st = r.model, r.state
    log.info("static equilibrium under gravity (%d cells, %d bodies, %d contact pairs)",
             m.comm.allreduce(m.mesh.topology.index_map(m.mesh.topology.dim).size_local),
             len(m.bodies), len(m.pairs) + len(m.surface_pairs))
    for line in r.extra.get("mesh", {}).get("warnings", ()):
        log.warning("%s", line)  # cell groups left out (breakwater.casefile.build)
    for info in r.extra.get("loads", {}).values():
        for line in info.get("warnings", ()):
            log.warning("%s", line)  # the case's loads (breakwater.casefile.loadchecks)
    for spec in m.surface_pairs if m.gdim == 2 else ():  # meshed into each other (within
        # the search's reach; a 3-D pair refuses an overlap in its static_check)
        line = meshed_overlap(m, spec)
        if line is not None:
            log.warning("%s", line)
    if st.step.adaptive:  # a history without breakpoints: refused before the static state
        load_breakpoints(m)
    solver = step_solver(r)  # (general pairs that do not fit: before their static state)
    m.set_time(0.0)
    init = initial_state(m)
    st.static_iterations = init.iterations
    log.info("static: %d Newton iterations (%s)", st.static_iterations, init.kind)
    moved = sideways(m, init.u) if init.kind == "frictionless" else {}
    refusal, warnings = drift(m, moved)
    if refusal is not None:  # friction would hold it there: the frictional loading
        raise DriftError(refusal)
    for line in warnings:
        log.warning("%s", line)
    r.stepped = x = Stepped(m, r.time, r.output, r.directory, solver)
    r.applied = AppliedLoads(m, r.time.beta1, st.applied_loads)
    s, out = x.stepper, x.files
    s.initialise(init.u, init.v, m.initial.loads)  # a₀: the state's loads (f at 0⁻)
    for contact in s.surfaces:  # meshed apart, the gap closed
        line = (meshed_gap3d(contact) if m.gdim == 3  # type: ignore[arg-type]
                else meshed_gap2d(contact))  # type: ignore[arg-type]
        if line is not None:
            log.warning("%s", line)
    if st.step.adaptive:
        adaptive_start(st.step, m, s.u)
    r.rows = out.open_history(x.monitor.columns)
    out.open_fields(steps=r.time.planned_steps)
    row = r.record(0.0, st.static_iterations)
    interface = interface_state(s.contacts, s.u)
    st.static = static_summary(m, row, interface, st.static_iterations, s.contacts)
    st.static.update(init.summary())
    if moved:  # bodies held by contact alone in a frictionless state: (sideways, sinking)
        st.static["sideways_drift"] = {k: {"sideways": a, "sinking": b}
                                       for k, (a, b) in moved.items()}
    st.contact = sm.quality_inputs(s.contacts, s.u)
    if m.pairs:  # a tetrahedral interface's pressure along its mid z, for the figure
        key = f"contact_{s.contacts[0].name}"
        cut = triangle_row(m, m.pairs[0].spec.interface, interface[f"{key}_x"],
                           interface[f"{key}_pressure"])
        if cut is not None:
            interface = {**interface, f"{key}_row_x": cut[0], f"{key}_row_pressure": cut[1]}
    out.write_snapshot(files.STATIC, s.u, interface, 0.0)
    r.log_quality()
    for line in resolution_warnings(row, st.contact, m.gdim, interface, m.degree):
        log.warning("%s", line)
    out.write_fields(0.0, s.u, s.v)


def load_breakpoints(model: ContactModel) -> list[float]:
    """The loads' breakpoints, for adaptive steps.

    Raises:
        CaseError: A load's history does not name its breakpoints (a plain Python
            function): adaptive steps could jump over it.
    """
    times: set[float] = set()
    for ld in model.loads:
        bp = getattr(ld.spec.amplitude, "breakpoints", None)
        if bp is None:
            raise CaseError(f"time.adaptive: the history of load '{ld.spec.name or ld.spec.group}' "
                            "does not give its breakpoints (a plain function): adaptive "
                            "steps could step over it (use fixed steps, or a Pulse, Ramp, "
                            "Constant or Table history)")
        times.update(float(t) for t in bp)
    return sorted(times)


def adaptive_start(step: StepSize, model: ContactModel, u: Sequence[fem.Function]) -> None:
    """The loads' breakpoints and the first displacement scale of adaptive steps (collective).

    Raises:
        CaseError: A load's history does not name its breakpoints (:func:`load_breakpoints`).
    """
    step.breakpoints = load_breakpoints(model)
    largest = max((float(np.max(np.abs(f.x.array))) if f.x.array.size else 0.0 for f in u),
                  default=0.0)
    largest = model.comm.allreduce(largest, op=MPI.MAX)
    step.scale = largest


def restore(r: Session) -> None:
    """Continue from the checkpoint of the output folder (collective).

    Nothing in the folder changes until the checkpoint is known to fit.

    Raises:
        CheckpointError: No checkpoint, another case, a finished run, or a history
            that does not reach the checkpoint.
    """
    m, comm = r.model, r.comm
    saved = runstate.load(r.directory, r.fingerprint,
                          [b.spec.name for b in m.bodies], r.time, comm)
    if saved.mpi_size != comm.size:
        log.warning("resuming on %d ranks a checkpoint written on %d: the continuation "
                    "equals the uninterrupted run to round-off, not bit for bit",
                    comm.size, saved.mpi_size)
    m.set_time(0.0)  # GN22 scales its tolerances with the loads at t = 0
    r.stepped = x = Stepped(m, r.time, r.output, r.directory, step_solver(r))
    if saved.columns != x.monitor.columns:
        raise CheckpointError("the checkpoint's history columns are not the run's")
    saved.restore_fields(x.functions())
    st = r.state = saved.state
    r.applied = AppliedLoads(m, r.time.beta1, st.applied_loads)
    x.resume(st)
    t = st.step.t
    try:
        r.rows = x.files.open_history(x.monitor.columns, keep_rows=st.history_rows)
    except (ValueError, OSError) as e:
        raise CheckpointError(f"cannot resume: {e}") from e
    if r.rows[-1]["t"] != t:
        raise CheckpointError(f"cannot resume: the last history row kept (t = "
                              f"{r.rows[-1]['t']:.6g} s) is not the checkpoint's "
                              f"(t = {t:.6g} s)")
    st.resumed_from.append({"t": t, "steps": st.steps, "mpi_size": comm.size})
    st.field_parts += x.files.open_fields(resume=True,
                                          steps=max(r.time.planned_steps - st.steps, 0))
    r.checkpointed = {"file": files.CHECKPOINT, "t": t, "steps": st.steps,
                      "history_rows": st.history_rows}
    if comm.rank == 0:
        files.remove_temporaries(r.directory)
    log.info("resuming from the checkpoint at t = %.6g s (step %d)", t, st.steps)
    r.log_quality()
