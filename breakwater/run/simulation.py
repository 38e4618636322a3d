"""A whole run: static equilibrium, GN22 time stepping with cut-back, outputs.

:func:`run` takes a built :class:`~breakwater.model.model.ContactModel` and the typed run
settings of :mod:`breakwater.config.runspec`; it never reads TOML. The run

1. finds the initial state (:func:`breakwater.statics.initial.initial_state`: the static
   equilibrium under gravity and the loads of the initial state, frictionless when it
   exists, else frictional, bodies that friction cannot hold held up to t = 0) and
   starts the GN22 stepper from it, at rest but for the bodies' initial velocities;
2. steps to ``end_time`` (the last step lands on it exactly). A step whose Newton
   solve fails is retried with Δt/2, up to ``max_cutbacks`` halvings; after
   :data:`GROW_AFTER` accepted steps the step doubles again, never above the nominal
   Δt. A step that still fails, or a non-finite state, ends the run: the outputs up to
   the last accepted step are written, ``summary.json`` says ``finished: false`` and
   :class:`SimulationFailed` is raised;
3. writes the outputs described in :mod:`breakwater.outputs.writers` and the figures of
   :mod:`breakwater.outputs.figures`, and a contact quality report per pair
   (:mod:`breakwater.outputs.quality`: penetration against the element size and the static
   settlement, penalty stiffness against E/h; ``contact_quality`` in the summary).

Checkpoints (:mod:`breakwater.outputs.checkpoint`): with ``output.checkpoint_interval`` = N >
0 the state is saved every N steps (``checkpoint.npz``, atomically, the latest only;
removed once ``summary.json`` says finished), and ``run(..., resume=True)`` continues from it:
``history.csv`` is cut back to the rows of the checkpoint and the run goes on, giving
the same history as an uninterrupted run (bit for bit serially). ``summary.json`` exists
from the start of a run (``status: "running"``) and is rewritten at every checkpoint,
so a killed run's folder says that it did not finish. On SIGTERM or SIGINT (Ctrl-C)
the run stops at the next step boundary (all ranks together), writes a checkpoint (when
N > 0) and the outputs, with ``status: "interrupted"``, and raises :class:`RunInterrupted`; a second
SIGTERM or SIGINT kills it at once.

Every rank runs the same code (all measurements are collective and give the same
values on every rank); only rank 0 writes files, logs and prints (the run's logger,
``breakwater.run.simulation``, lets only rank 0 log while :func:`run` goes:
:func:`~breakwater.common.console.rank_zero_logging`).

This module holds :func:`run` and its time loop; the parts it uses:

- :mod:`breakwater.stepping.stepsize`: the step-size control
  (:class:`~breakwater.stepping.stepsize.StepSize`);
- :mod:`breakwater.run.session`: the stepper and the objects measuring and writing its
  state, set up from the static state or from a checkpoint;
- :mod:`breakwater.outputs.monitor`: one history row per step
  (:class:`~breakwater.outputs.monitor.Monitor`, with the probes of
  :mod:`breakwater.outputs.probes`);
- :mod:`breakwater.run.runstate`: the bookkeeping a checkpoint saves and restores whole;
- :mod:`breakwater.outputs.summary`: ``summary.json`` and the report, from what the run produced;
- :mod:`breakwater.outputs.writers` and :mod:`breakwater.common.files`: the files written;
- :mod:`breakwater.common.console`: the progress bar, rank-0 logging, SIGTERM and SIGINT.
"""

from __future__ import annotations

import contextlib
import logging
import re
import signal
import sys
import time as _time
from collections.abc import Mapping
from typing import Any

from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from breakwater.common import files, folderlock, petscfree
from breakwater.common.arrays import finite
from breakwater.common.console import Progress, SlowPhase, StopSignal, rank_zero_logging
from breakwater.common.errors import (
    BreakwaterError,
    CaseError,
    ConvergenceError,
    Interrupted,
    MeshError,
    OutputError,
    PenetrationError,
    cannot_write,
)
from breakwater.common.notebookprogress import duration, in_kernel, time_left
from breakwater.common.parallel import on_rank_zero
from breakwater.common.wholeimport import whole_imports
from breakwater.config.runspec import OutputSpec, TimeSpec
from breakwater.model.model import ContactModel
from breakwater.outputs import checkpoint as ckpt
from breakwater.outputs.monitor import Monitor, interface_state, pair_names
from breakwater.outputs.rotation import rotation_warning
from breakwater.outputs.sliding import sliding_warnings
from breakwater.outputs.summary import balance_warning, format_report
from breakwater.run import begin
from breakwater.run.asrun import case_as_run, changed_line, checked_arguments, checked_extra
from breakwater.run.session import Session
from breakwater.stepping.gn22 import local_error
from breakwater.stepping.stepsize import GROW_AFTER
from breakwater.stepping.stepsolver import StepSolver

__all__ = ["GROW_AFTER", "RESUME_HINT", "Monitor", "RunInterrupted", "SimulationFailed",
           "interface_state", "pair_names", "run"]

RESUME_HINT = " (continue with --resume; from Python: run(..., resume=True))"
"""The end of an interrupted run's error when it saved a checkpoint."""

log = logging.getLogger("breakwater.run.simulation")

#: Without the progress bar (stderr not a terminal: a batch job's log), a line on the
#: time loop's progress every this many seconds of wall time.
HEARTBEAT = 60.0


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
    """The run stopped on a signal (SIGTERM, SIGINT); ``summary.json`` says ``interrupted``."""


class _Stop(Interrupted):
    """Raised inside the time loop when a stop signal was received."""


CRASHES = (PETSc.Error, RuntimeError, ArithmeticError, MemoryError, ValueError)
"""What the numerical libraries raise (PETSc, MUMPS through PETSc, dolfinx's C++,
NumPy): a run that meets one fails with ``summary.json`` saying so and one line,
instead of a traceback and a summary left ``running``."""


def crash_reason(error: BaseException) -> str:
    """One line for an error of PETSc (its code, routine and message) or another library.

    PETSc's text is ``error code N`` then ``[rank] Routine() at file:line`` and the
    message lines, each prefixed by the rank.
    """
    if not isinstance(error, PETSc.Error):  # ADIOS2 colours its messages: not in a file
        text = " ".join(re.sub(r"\x1b\[[0-9;]*m", "", str(error)).split())
        return (f"{type(error).__name__}: {text}" if not isinstance(error, BreakwaterError)
                else text) or type(error).__name__
    lines = [line.split("] ", 1)[-1].strip() for line in str(error).splitlines()[1:]]
    where = [line.split(" at ", 1)[0] for line in lines if "() at " in line]
    said = [line for line in lines if line and "() at " not in line]
    return (f"PETSc error {getattr(error, 'ierr', '?')}" + (f" in {where[0]}" if where else "")
            + (f": {'; '.join(said)}" if said else ""))


def _finite(comm: MPI.Comm, *functions: fem.Function) -> bool:
    """Whether every value of the Functions is finite, on every rank."""
    ok = all(finite(f.x.array) for f in functions)
    return ok if comm.size == 1 else bool(comm.allreduce(ok, op=MPI.LAND))


def _check_stop(r: Session, stop: StopSignal) -> None:
    """Stop (all ranks together) when a rank received a stop signal; checkpoint first."""
    signum = stop.received if r.comm.size == 1 else r.comm.allreduce(stop.received,
                                                                     op=MPI.MAX)
    if not signum:
        return
    saved = r.output.checkpoint_interval > 0
    if saved and (r.checkpointed is None or r.checkpointed["steps"] != r.state.steps):
        r.checkpoint()
    raise _Stop(f"interrupted by {signal.Signals(signum).name} at t = {r.state.step.t:.6g} s"
                + (RESUME_HINT if saved else ""))


class _LoopClock:
    """Wall time of the time loop and of its parts, kept in the run state.

    The solver's own parts (its :attr:`~breakwater.stepping.stepsolver.StepSolver.timings`)
    are folded in at checkpoints and at the end, so that a resumed run sums them over its
    parts.
    """

    def __init__(self, times: dict[str, float], solver: StepSolver) -> None:
        self.times, self.solver = times, solver
        self._mark = self._cpu = 0.0

    def add(self, key: str, seconds: float) -> None:
        self.times[key] = self.times.get(key, 0.0) + seconds

    def fold(self) -> None:
        now, cpu = _time.perf_counter(), _time.process_time()
        self.add("wall", now - self._mark)
        # The process's CPU time (all its threads): on a loaded machine, the work done.
        self.add("cpu", cpu - self._cpu)
        self._mark, self._cpu = now, cpu
        parts = self.solver.timings.seconds
        for key, seconds in parts.items():
            self.add(key, seconds)
            parts[key] = 0.0

    def __enter__(self) -> _LoopClock:
        self._mark, self._cpu = _time.perf_counter(), _time.process_time()
        return self

    def __exit__(self, *exc: object) -> None:
        self.fold()


def _named_differences(r: Session, resolved_case: Mapping[str, Any] | None
                       ) -> ckpt.CaseMismatch:
    """The refusal to resume another case, with the keys that differ (collective).

    Read from the folder's ``case.toml`` (the checkpointed run's, untouched) on rank 0.
    """
    def keys() -> list[str]:
        saved = files.read_toml(r.directory / files.CASE)
        if resolved_case is None or saved is None:
            return []
        return ckpt.case_differences(saved, resolved_case)

    return ckpt.CaseMismatch.of(r.directory / ckpt.CHECKPOINT, on_rank_zero(r.comm, keys))


def _loop(r: Session, stop: StopSignal) -> None:
    """Step from the state reached to the end time (collective)."""
    x, st, time, output = r.stepped, r.state, r.time, r.output
    assert x is not None
    s = x.stepper
    step, interval = st.step, output.checkpoint_interval
    # A Jupyter kernel's stderr is no terminal: its own line there (unless switched off).
    notebook = output.progress is not False and in_kernel()
    show = notebook or (output.progress if output.progress is not None
                        else sys.stderr.isatty())
    log.info("work estimate: %d steps × %d unknowns = %.3g", r.work["steps_planned"],
             r.work["dofs"], r.work["estimate"])
    if step.adaptive:
        log.info("time stepping to t = %g s with adaptive steps from dt = %g s down to "
                 "%.3g s (tolerance %g)", time.end_time, time.dt, time.dt / 2**step.levels,
                 time.tolerance)
    else:
        log.info("time stepping to t = %g s with dt = %g s", time.end_time, time.dt)
    clock = _LoopClock(st.time_loop, s.solver)
    beat = None if show else SlowPhase(log, "time stepping", every=HEARTBEAT)
    t_start, steps_start, iterations = step.t, st.steps, 0  # of this process
    with Progress(time.end_time, bool(show) and r.comm.rank == 0, output.case_name,
                  step.t, notebook) as progress, clock:
        while not step.finished:
            _check_stop(r, stop)
            t, trial = step.t, step.propose()
            if st.steps >= time.max_steps:
                raise SimulationFailed(
                    f"t = {t:.6g} s, dt = {trial:.3g} s: {st.steps} steps taken (the limit "
                    f"time.max_steps; cut-backs made the steps smaller) before end_time = "
                    f"{time.end_time:g} s (raise time.max_steps to go on)")
            try:
                s.stage(trial, step.landing())
                its = s.solve()
                if not _finite(r.comm, *s.da):
                    raise ConvergenceError("non-finite acceleration increment", 0, its)
                if step.adaptive and not step.judge(*local_error(s)):
                    log.debug("t = %.6g s, dt = %.3g s: local error %.3g times the "
                              "tolerance; retrying with dt = %.3g s", t, trial, step.ratio,
                              step.h)
                    continue
            except (ConvergenceError, PETSc.Error) as e:
                # The state (u, v, a) is untouched until update(): retry from it.
                st.failed_steps += 1
                st.failed_iterations += getattr(e, "iterations", 0)
                allowed = step.levels if step.adaptive else time.max_cutbacks
                if not step.reject():
                    floor = (f", and dt/2 = {0.5 * trial:.3g} s would be below time.min_dt "
                             f"= {time.min_dt:.3g} s" if step.halvings < allowed else "")
                    what = "was rejected" if isinstance(e, PenetrationError) else \
                        "did not converge"
                    halved = (f"at the smallest adaptive step (dt/2^{step.levels}; "
                              "time.min_dt sets it)" if step.adaptive
                              else f"after {step.halvings} cut-backs{floor}")
                    raise SimulationFailed(
                        f"step from t = {t:.6g} s with dt = {trial:.3g} s {what} "
                        f"{halved}: {crash_reason(e)}") from e
                log.warning("t = %.6g s: %s; retrying with dt = %.3g s (cut-back %d/%d)",
                            t, crash_reason(e), step.h, step.halvings, allowed)
                continue
            s.update()
            grew = step.accept()
            s.t.value = step.t  # the exactly rounded sum of the steps, or the end time
            if not _finite(r.comm, *s.u, *s.v, *s.a):
                raise SimulationFailed(f"non-finite state after the step to "
                                       f"t = {step.t:.6g} s")
            st.steps += 1
            st.iterations.append(its)
            outputs = _time.perf_counter()
            row = r.record(trial, its)
            log.debug("t = %.6g s, dt = %.3g s, %d Newton iterations", row["t"], trial, its)
            if output.field_interval > 0 and st.steps % output.field_interval == 0:
                x.files.write_fields(row["t"], s.u, s.v)
                st.fields_time = row["t"]
            if grew and not step.adaptive:
                log.info("t = %.6g s: step size back to dt = %.3g s", row["t"], step.h)
            if interval > 0 and st.steps % interval == 0:
                clock.fold()
                r.checkpoint()
            clock.add("outputs", _time.perf_counter() - outputs)
            progress.update(row["t"], its=its, cutbacks=step.cutbacks)
            iterations += its
            if beat is not None and beat.due():
                _beat(beat, row["t"], t_start, time.end_time, st.steps,
                      iterations / (st.steps - steps_start))


def _beat(beat: SlowPhase, t: float, t_start: float, end: float, steps: int,
          mean_iterations: float) -> None:
    """The time loop's progress line (a batch job's log): t, steps, time left.

    The time left is this process's rate in simulated seconds (from ``t_start``, where
    it started or resumed) over what remains.
    """
    elapsed = beat.elapsed
    left = time_left(elapsed, t, t_start, end)
    log.info("time stepping: t = %.6g s of %g s (%.0f%%), %d steps, %.2f Newton "
             "iterations per step; %s elapsed, about %s left", t, end, 100 * t / end, steps,
             mean_iterations, duration(elapsed), duration(left))


def run(model: ContactModel, time: TimeSpec, output: OutputSpec,
        resolved_case: Mapping[str, Any] | None = None,
        extra_summary: Mapping[str, Any] | None = None, *, report: bool = True,
        resume: bool = False, fingerprint: str | None = None) -> dict[str, Any]:
    """Run a case: static equilibrium, time stepping, outputs (collective).

    Args:
        model: The contact model (loads, damping, gravity included).
        time: Time step, end time, GN22 and Newton settings.
        output: Output directory, probes, output switches, checkpoint interval.
        resolved_case: The resolved case, written as ``case.toml`` when given, with
            the ``[time]`` table and the output's folder, intervals and figures of
            ``time`` and ``output``, and the model's damping and gravity
            (:func:`~breakwater.run.asrun.case_as_run`: a warning names the time,
            damping and gravity keys that differed); a ``Case`` (``built.case``) is
            taken for its ``resolved()``.
        extra_summary: Merged into the summary (e.g. calibration results): values
            JSON can hold, NumPy numbers and arrays (written as numbers and lists).
        report: Print a short report of the results at the end (rank 0).
        resume: Continue the run of ``output.directory`` from its checkpoint.
        fingerprint: Identifies the case in checkpoints; a checkpoint is resumed only
            by a run of the same fingerprint. Default: the hash of ``resolved_case``
            (:func:`~breakwater.outputs.checkpoint.case_fingerprint`) when given, else of the
            model, time and probe settings
            (:func:`~breakwater.outputs.checkpoint.model_fingerprint`).

    Returns:
        The summary, also written to ``summary.json`` (the same on every rank).

    Raises:
        TypeError: ``model``, ``time``, ``output`` or ``resolved_case`` of another type,
            or a value of ``extra_summary`` that JSON cannot hold (one line naming it;
            nothing is written).
        SimulationFailed: The run stopped before ``time.end_time``; the outputs up to
            the last accepted step are written, with ``finished: false``.
        RunInterrupted: (a SimulationFailed) The run stopped on SIGTERM or SIGINT.
        CheckpointError: ``resume``: no usable checkpoint (the folder is untouched).
    """
    resolved_case = checked_arguments(model, time, output, resolved_case)
    on_rank_zero(model.comm, lambda: files.check_unmixed(output.directory,
                                                         "output.directory", study=False))
    extra_summary = checked_extra(extra_summary)
    as_run: list[tuple[str, Any, Any]] = []
    if resolved_case is not None:  # case.toml says what runs (the specs given here)
        resolved_case, as_run = case_as_run(resolved_case, time, output, model.damping,
                                            model.gravity.value)
    if fingerprint is None and resolved_case is not None:
        # Rank 0's: every rank then resumes or refuses the same checkpoint, even when
        # an input file changes while the ranks read it.
        fingerprint = model.comm.bcast(ckpt.case_fingerprint(resolved_case)
                                       if model.comm.rank == 0 else None, root=0)
    elif fingerprint is None:
        fingerprint = ckpt.model_fingerprint(model, time, output)
    with rank_zero_logging(log, model.comm), StopSignal() as stop, \
            folderlock.holding(output.directory, model.comm):
        if (line := changed_line(as_run)) is not None:
            log.warning("%s", line)
        r = Session(model, time, output, fingerprint, extra_summary)
        if resume:
            try:
                begin.restore(r)  # CheckpointError: nothing written yet
            except ckpt.CaseMismatch:
                raise _named_differences(r, resolved_case) from None
        else:
            cleared = on_rank_zero(r.comm, lambda: files.clear_previous_run(r.directory))
            if cleared:
                log.info("replaced the outputs of the earlier run in %s", r.directory)
        if resolved_case is not None:
            on_rank_zero(r.comm, lambda: bool(
                files.atomic_write_toml(r.directory / files.CASE, resolved_case)))
        # From now on the folder always says whether the run finished.
        r.write_summary(r.summary(False, None, "running"))
        error: BaseException | None = None
        try:
            if not resume:
                begin.start(r)
            _loop(r, stop)
        except (BreakwaterError, KeyboardInterrupt) as e:
            error = e
        except CRASHES as e:  # not foreseen by a check: the run fails, in one line
            error = SimulationFailed(crash_reason(e))
            error.__cause__ = e  # (--debug shows it)
        checkpointed = r.checkpointed  # (a finished run's summary names none)
        try:
            summary = _end(r, error, output, report)
        except KeyboardInterrupt as e:  # (a second interrupt while the outputs are
            error = e  # written: the summary said "running" and the error had no note)
            summary = _interrupted_end(r, e, checkpointed)
        except (OutputError, OSError) as e:  # e.g. a full disk: the first error is
            if error is None:  # the reason
                error = e if isinstance(e, OutputError) else cannot_write(e.filename, e)
            r.checkpointed = checkpointed  # still there: run --resume goes on from it
            summary = _failed_end(r, error)
        finally:
            r.close()
            petscfree.release(model.comm)  # what dolfinx's destructors put aside
        if error is None:
            return summary
        if isinstance(error, KeyboardInterrupt):
            # (a second Ctrl-C or interrupt in a notebook, or the caller's own)
            error.add_note(_interrupted_note(r, summary))
            raise error
        stopped = isinstance(error, Interrupted)
        # The exception carries the reason (the command line prints it as its one error
        # line; the report and summary.json say it too): not logged a second time.
        log.debug("run %s: %s", "interrupted" if stopped else "failed", summary["error"])
        if stopped:
            interrupted = RunInterrupted(summary["error"], summary)
            interrupted.add_note(_interrupted_note(r, summary))
            raise interrupted from error
        if isinstance(error, CaseError | MeshError):  # an input found bad once built
            raise error  # (a pair probe off its slave surface): exit 2, as before a run
        raise SimulationFailed(summary["error"], summary) from error


def _interrupted_note(r: Session, summary: Mapping[str, Any]) -> str:
    """What an interrupted run left, for a traceback (a notebook's): where, and how to go on.

    The command line prints its error's one line only, without the note.
    """
    if summary.get("status") == "finished":  # interrupted once its summary was written
        return (f"breakwater: the run finished; its outputs are in {r.directory} "
                "(its figures or report may be missing)")
    reached = summary.get("time", {}).get("reached")
    at = "before its static state" if reached is None else f"at t = {reached:.6g} s"
    # (the summary's checkpoint, the same on every rank: not each rank's look at the folder)
    go_on = ("; run(..., resume=True) with the same settings continues from its checkpoint"
             if summary.get("checkpoint") else "")
    return (f"breakwater: the run stopped {at}; its outputs up to there are in "
            f"{r.directory} (summary.json: \"interrupted\"){go_on}")


def _end(r: Session, error: BaseException | None, output: OutputSpec, report: bool
         ) -> dict[str, Any]:
    """Write the outputs, the summary, the figures and the report (collective).

    Returns:
        The summary, the same on every rank.
    """
    message = None if error is None else (str(error) or type(error).__name__)
    stopped = isinstance(error, Interrupted | KeyboardInterrupt)
    status = "finished" if error is None else "interrupted" if stopped else "failed"
    if error is None:
        r.checkpointed = None  # (the summary names no checkpoint)
    summary = r.finish(error is None, message, status)
    if error is None or not stopped:
        r.log_quality(dynamic=True)
        for warning in (balance_warning(summary.get("energy", {}), files.per_metre(summary)),
                        rotation_warning(summary.get("dynamic", {}))):
            if warning is not None:
                log.warning("%s", warning)
        if r.stepped is not None and not summary.get("storm", {}).get("warning"):
            # (a storm's record warns of its pair's sliding itself: the report's line)
            s = r.stepped.stepper
            for line in sliding_warnings(s.contacts, s.u, r.state.contact):
                log.warning("%s", line)

    def write() -> dict[str, Any]:
        folderlock.write_final_summary(r.directory / files.SUMMARY, summary)
        if error is None:
            # Removed once the summary says finished, not before the last outputs: a
            # kill (the time limit) or a full disk between the two lost the whole run.
            (r.directory / files.CHECKPOINT).unlink(missing_ok=True)
        if output.figures and not stopped:
            with whole_imports():  # (matplotlib)
                from breakwater.outputs import figures

            try:
                drawn = figures.make_figures(r.directory)
            except Exception:
                if error is None:
                    raise
                log.exception("the figures of the failed run could not be drawn")
            else:
                summary["outputs"]["figures"] = [str(p.relative_to(r.directory))
                                                 for p in drawn]
                folderlock.write_final_summary(r.directory / files.SUMMARY, summary)
        if report:
            print(format_report(summary, r.directory), flush=True)
        return summary

    # Rank 0 writes; an error (e.g. OutputError: a full disk) is raised on every rank.
    return on_rank_zero(r.comm, write)


def _interrupted_end(r: Session, error: KeyboardInterrupt,
                     checkpointed: dict[str, Any] | None) -> dict[str, Any]:
    """The summary of a run interrupted while its last outputs were written (collective).

    A finished run whose ``summary.json`` already says so keeps it (its checkpoint is
    removed, its figures or report may be missing); else the summary says
    ``interrupted`` at the state reached, naming the checkpoint kept.
    """
    written = on_rank_zero(r.comm, lambda: files.read_json(r.directory / files.SUMMARY))
    if written is not None and written.get("status") == "finished":
        on_rank_zero(r.comm, lambda: (r.directory / files.CHECKPOINT).unlink(missing_ok=True))
        return written
    r.checkpointed = checkpointed
    return _failed_end(r, error)


def _failed_end(r: Session, error: BaseException) -> dict[str, Any]:
    """The summary of a run whose outputs could not all be written (collective).

    ``summary.json`` says ``failed`` (``interrupted`` on a stop) with the one-line
    reason, when it can still be written; the state is what the run had reached.
    """
    stopped = isinstance(error, Interrupted | KeyboardInterrupt)
    summary = r.summary(False, str(error) or type(error).__name__,
                        "interrupted" if stopped else "failed")
    with contextlib.suppress(OutputError):
        r.write_summary(summary)
    return summary
