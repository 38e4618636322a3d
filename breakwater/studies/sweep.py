"""Parameter studies: every point of a study file run as a case, in parallel, resumably.

:func:`run_study` runs the points of a :class:`~breakwater.studies.studyfile.Study`:

- the ranks of the communicator form groups of ``ranks_per_case`` ranks (MPI
  sub-communicators, ``comm.Split``); each group runs one case at a time with the usual
  run API (:meth:`Case.build <breakwater.casefile.case.Case.build>` and
  :func:`breakwater.run.simulation.run`) on its sub-communicator;
- the cases are handed out dynamically: the leader of a group that is free takes the
  next case number from a counter held by rank 0 (an MPI window,
  ``Fetch_and_op``), so no rank is spent on a master and a long case does not hold
  up the others;
- each case runs in its own folder ``<out>/case-0007_<values>`` (the usual run
  outputs); when it ends, its group writes ``sweep_case.json`` there, atomically and
  last: the point, the case's fingerprint, the status (``finished``, ``failed`` with
  its one-line error, ``interrupted``), the wall time and the headline numbers of its
  ``summary.json``; while the case runs, ``running`` and the process that runs it
  (:mod:`breakwater.common.liveness`): ``sweep.csv`` says ``stopped`` for a case whose
  process is gone (a study killed by SIGKILL);
- ``sweep.csv`` (one row per point: the values, status, wall time, error and headline
  numbers) is rewritten atomically after every case and by rank 0 at the end, with
  the figures of :mod:`breakwater.studies.plots`.

A case counts as finished only when its ``sweep_case.json`` says ``finished`` for the
same case (fingerprint of the resolved case and of the files it reads) and its
``summary.json`` agrees; a rerun skips those and runs the others again (a killed case
resumes from its checkpoint when it has one, otherwise starts afresh in an emptied
folder). SIGTERM or SIGINT stops the study (:class:`~breakwater.common.console.StopSignal`, as
a run; a second signal kills), at any moment, a case's meshing included: the running
cases stop at their next step (``interrupted``, with a checkpoint when the case makes
them), no new case starts, the others stay ``pending``; the study says so in one line
and exits 1. Under ``mpiexec`` the rank that finds the signal posts it in the shared
counter, so that every group stops (the ranks agree) even when the signal reached only
one of them.
"""

from __future__ import annotations

import contextlib
import logging
import math
import pathlib
import shutil
import signal
import sys
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

from mpi4py import MPI

from breakwater.common import files, liveness
from breakwater.common.console import StopSignal
from breakwater.common.cores import core_warning, host_usage
from breakwater.common.errors import CaseError, OutputError
from breakwater.common.gmshtools import settle_signal_handlers
from breakwater.common.parallel import on_every_rank, on_rank_zero
from breakwater.common.wholeimport import whole_imports
from breakwater.outputs import checkpoint  # importing PETSc is collective: at import
from breakwater.run import simulation
from breakwater.run.resumecase import build_to_resume
from breakwater.studies.columns import headline
from breakwater.studies.studyargs import checked_study_arguments
from breakwater.studies.studyfile import Point, Study, check_points
from breakwater.studies.sweeptable import RECORD, TABLE, read_records, write_table

if TYPE_CHECKING:
    from breakwater.casefile.case import Case

__all__ = ["RECORD", "TABLE", "StudyOutcome", "headline", "read_records", "run_study",
           "write_table"]

FIGURES = "figures"

log = logging.getLogger("breakwater.studies.sweep")


@dataclass(frozen=True)
class StudyOutcome:
    """What a study did: the count of points by status (after the run)."""

    total: int
    finished: int
    skipped: int
    failed: int
    interrupted: int
    not_run: int

    @property
    def complete(self) -> bool:
        """Whether every point's case finished."""
        return self.finished == self.total


# --- the records and the table -------------------------------------------------------------

def _finished(folder: pathlib.Path, fingerprint: str) -> bool:
    """Whether the case of a folder finished, for this very case."""
    record = files.read_json(folder / RECORD)
    summary = files.read_json(folder / files.SUMMARY)
    return (record is not None and summary is not None
            and record.get("status") == "finished" and summary.get("status") == "finished"
            and record.get("fingerprint") == fingerprint)


def _outputs_complete(folder: pathlib.Path, summary: dict[str, Any],
                      case_toml: dict[str, Any]) -> bool:
    """Whether the files a finished run's summary names are all in its folder.

    The history, static state, snapshot and ParaView files of its ``outputs``; its
    figures when the case draws them (the summary names them once drawn: a kill while
    they were drawn left none); a storm's ``waves.csv``.
    """
    outputs = summary.get("outputs")
    if not isinstance(outputs, dict):
        return False
    names: list[Any] = [outputs.get(k) for k in ("history", "static", "snapshot")]
    names += list(outputs.get("fields") or []) + list(outputs.get("figures") or [])
    if case_toml.get("output", {}).get("figures", True) and "figures" not in outputs:
        return False
    if summary.get("storm"):
        names.append(files.WAVES)
    return all(isinstance(n, str) and (folder / n).exists() for n in names if n is not None)


def _record_finished_run(folder: pathlib.Path, point: Point, fingerprint: str
                         ) -> dict[str, Any] | None:
    """Record a case whose run finished but whose record was not written (rank 0).

    A study killed between the run's last ``summary.json`` ("finished") and the case's
    record left a record that says ``running``; the rerun ran the whole case again. Its
    record is written now from the summary, when the record names this very case
    (fingerprint), the summary says finished and the outputs it names are there.

    Returns:
        The record written, or None (the case is run again, as before).
    """
    record = files.read_json(folder / RECORD)
    summary = files.read_json(folder / files.SUMMARY)
    if record is None or summary is None or record.get("fingerprint") != fingerprint \
            or summary.get("status") != "finished" or not summary.get("finished"):
        return None
    case_toml = files.read_toml(folder / files.CASE)
    if case_toml is None or not _outputs_complete(folder, summary, case_toml):
        return None
    times = [t for t in (record.get("wall_time"), _wall_time(folder))
             if isinstance(t, int | float) and not isinstance(t, bool)]
    ranks = summary.get("mpi_size")
    done = _record(point, fingerprint, "finished", None, float(max(times, default=0.0)),
                   ranks if isinstance(ranks, int) else None)
    done["headline"] = headline(summary, case_toml)
    done["warnings"] = []  # (the run's warnings were collected by the killed study)
    (folder / files.CHECKPOINT).unlink(missing_ok=True)  # (the run removes it after
    files.atomic_write_json(folder / RECORD, done)       # its summary: a kill between)
    return done


# --- one case ----------------------------------------------------------------------------

def _one_line(error: BaseException) -> str:
    return " ".join(str(error).split()) or type(error).__name__


class _CaseWarnings(logging.Handler):
    """The warnings a case's run logs, one line each."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.lines: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append(" ".join(record.getMessage().split()))


@contextlib.contextmanager
def _case_warnings() -> Iterator[list[str]]:
    """Collect the warnings of a case's run (the ``breakwater`` logger's).

    When the logger is quieter than its warnings (``sweep`` without ``--verbose``: the
    cases' messages are not printed), its handlers are set aside for the case: the
    warnings are collected only, and the study reports them with the case (the run's
    own rank-0 filter keeps one copy per group).
    """
    logger = logging.getLogger("breakwater")
    collect = _CaseWarnings()
    level, handlers = logger.level, list(logger.handlers)
    silent = logger.getEffectiveLevel() > logging.WARNING
    if silent:
        for h in handlers:
            logger.removeHandler(h)
        logger.setLevel(logging.WARNING)
    logger.addHandler(collect)
    try:
        yield collect.lines
    finally:
        logger.removeHandler(collect)
        if silent:
            logger.setLevel(level)
            for h in handlers:
                logger.addHandler(h)


def _run_case(case: Case, point: Point, fingerprint: str, folder: pathlib.Path,
              comm: MPI.Comm) -> dict[str, Any]:
    """Run one case on ``comm`` (collective); its record, written last in its folder."""
    from breakwater.outputs.checkpoint import CheckpointError

    def prepare() -> tuple[bool, float]:
        """Resume a killed run of this case from its checkpoint, or start afresh.

        Returns:
            Whether to resume, and the wall time the case took before: the largest of
            its record's (an interrupted run's), its summary's (a killed run's, to its
            last checkpoint) and its checkpoint's (the runs' own time up to it, from
            which the summary's ``loop_time`` goes on); 0 when it starts afresh.
        """
        record = files.read_json(folder / RECORD)
        if (folder / files.CHECKPOINT).is_file() and record is not None \
                and record.get("fingerprint") == fingerprint:
            with contextlib.suppress(CheckpointError):
                saved = checkpoint.check(folder).get("state", {}).get("wall_before")
                times = [t for t in (record.get("wall_time"), _wall_time(folder), saved)
                         if isinstance(t, int | float) and not isinstance(t, bool)]
                files.atomic_write_json(folder / RECORD,  # running again, by this process
                                        _record(point, fingerprint, "running"))
                return True, float(max(times, default=0.0))  # what was lost after the
                # last checkpoint is not counted
        if folder.exists():
            shutil.rmtree(folder)
        folder.mkdir(parents=True)
        # The record says which case the folder holds (a checkpoint is resumed only for
        # it); its status says it did not finish, until the run ends.
        files.atomic_write_json(folder / RECORD, _record(point, fingerprint, "running"))
        return False, 0.0

    start = time.perf_counter()
    resume, before = on_rank_zero(comm, prepare)
    status, error, summary = "finished", None, None
    interrupt: KeyboardInterrupt | None = None
    warnings: list[str] = []
    try:
        with _case_warnings() as warnings:
            built = build_to_resume(case, comm) if resume else case.build(comm)
            output = replace(built.output, progress=False)
            summary = simulation.run(built.model, built.time, output,
                                     resolved_case=built.case.resolved(),
                                     extra_summary=built.extra, report=False,
                                     resume=resume)
    except simulation.RunInterrupted as e:
        # A study goes on when it is run again (sweep has no --resume)
        error = _one_line(e).replace(simulation.RESUME_HINT.strip(),
                                     "(run the study again to go on)")
        status, summary = "interrupted", e.summary
    except KeyboardInterrupt as e:  # (a second interrupt in a notebook): recorded as
        interrupt = e  # interrupted, then raised (the record said "running")
        status, error = "interrupted", "KeyboardInterrupt (run the study again to go on)"
        summary = on_rank_zero(comm, lambda: files.read_json(folder / files.SUMMARY))
    except Exception as e:  # the study goes on: the case's one-line error is recorded
        status, error = "failed", _one_line(e)
        summary = getattr(e, "summary", None)
    # The case's wall time over its runs (as the summary's loop time: a resumed run's
    # counts the interrupted one's).
    wall = before + comm.allreduce(time.perf_counter() - start, op=MPI.MAX)

    def write() -> dict[str, Any]:
        record = _record(point, fingerprint, status, error, wall, comm.size)
        record["headline"] = headline(summary or {}, files.read_toml(folder / files.CASE))
        record["warnings"] = warnings
        files.atomic_write_json(folder / RECORD, record)
        return record

    record = on_rank_zero(comm, write)
    if interrupt is not None:
        raise interrupt
    return record


def _record(point: Point, fingerprint: str, status: str, error: str | None = None,
            wall: float | None = None, ranks: int | None = None) -> dict[str, Any]:
    record = {"case": point.index, "folder": point.folder, "values": point.values,
              "fingerprint": fingerprint, "status": status, "error": error,
              "wall_time": wall, "ranks": ranks, "headline": {}}
    if status == "running":  # who runs it: a killed case reads as stopped (liveness)
        record["process"] = liveness.this_process()
    return record


def _wall_time(folder: pathlib.Path) -> float:
    """The wall time in a killed run's ``summary.json`` (to its last checkpoint), or 0."""
    summary = files.read_json(folder / files.SUMMARY) or {}
    wall = summary.get("solver", {}).get("wall_time") \
        if isinstance(summary.get("solver"), dict) else None
    return float(wall) if isinstance(wall, int | float) and math.isfinite(wall) else 0.0


# --- the study ---------------------------------------------------------------------------

class _Counter:
    """The next case number, shared by every rank (an MPI window on rank 0).

    It also carries a stop request to every group: :meth:`stop` raises the counter to
    ``signum * STOP_UNIT`` at least, so that no group takes a case any more (the number
    it takes is past the last case) and :meth:`stopped` tells the running cases of the
    other groups to stop (their runs poll it, :class:`StopSignal`).

    One passive-target epoch on rank 0 for the window's life (``Lock_all``). An atomic
    operation on rank 0's memory completes only when rank 0 makes MPI progress (MPICH
    handles it there), which a rank computing its own case does rarely: a blocking read
    left the other groups' runs waiting at every poll, and their cases took four times
    as long (a 20-wave storm: 42.5 s against 11 s while rank 0's group ran its own). So
    :meth:`stopped` never waits: it starts a read and returns the last one completed.
    """

    STOP_UNIT = 1 << 40

    def __init__(self, comm: MPI.Intracomm) -> None:
        import numpy as np

        size = MPI.INT64_T.Get_size()
        self.win = MPI.Win.Allocate(size if comm.rank == 0 else 0, size, comm=comm)
        if comm.rank == 0:
            self.win.Lock(0, MPI.LOCK_EXCLUSIVE)
            memoryview(self.win.tomemory()).cast("B")[:size] = bytes(size)
            self.win.Unlock(0)
        comm.Barrier()
        self.win.Lock_all(MPI.MODE_NOCHECK)
        self._read = np.zeros(1, dtype=np.int64)  # the read in flight's result
        self._reading: MPI.Request | None = None
        self._stopped = 0  # the last read's signal

    def _fetch_add(self, amount: int, op: MPI.Op = MPI.SUM) -> int:
        import numpy as np

        add, got = np.full(1, amount, dtype=np.int64), np.zeros(1, dtype=np.int64)
        self.win.Fetch_and_op(add, got, 0, 0, op)
        self.win.Flush(0)
        return int(got[0])

    def next(self) -> int:
        """Take the next number (atomically; waits for rank 0)."""
        return self._fetch_add(1)

    def stop(self, signum: int) -> None:
        """Ask every group to stop (any rank, any number of times: the first counts)."""
        self._fetch_add(signum * self.STOP_UNIT, MPI.MAX)

    def stopped(self) -> int:
        """The signal a group stopped on (0: none), as last read; never waits.

        A read in flight that has completed gives its value, and the next read starts.
        """
        import numpy as np

        if self._reading is not None and self._reading.Test():
            self._reading = None
            self._stopped = int(self._read[0]) // self.STOP_UNIT
        if self._reading is None and not self._stopped:
            self._reading = self.win.Rget_accumulate(
                np.zeros(1, dtype=np.int64), self._read, 0, op=MPI.NO_OP)
        return self._stopped

    def free(self) -> None:
        """End the epoch (completes a read in flight) and free the window (collective)."""
        self.win.Unlock_all()
        if self._reading is not None:
            self._reading.Wait()
        self.win.Free()


def run_study(study: Study, out: str | pathlib.Path | None = None,
              comm: MPI.Intracomm | None = None, ranks_per_case: int = 1,
              quiet: bool = False) -> StudyOutcome:
    """Run every point of a study that has not finished yet (collective).

    Args:
        study: The study (:func:`breakwater.studies.studyfile.load_study`).
        out: The study's folder (default ``results/<study name>``).
        comm: The ranks to use (default: all).
        ranks_per_case: Ranks per group; the communicator's size must be a multiple.
        quiet: Print nothing but errors.

    Returns:
        The counts of the points by status, the same on every rank.

    Raises:
        TypeError: An argument of another type, e.g. a path for ``study`` (one line).
        CaseError: A bad study (every point's case is read before anything runs), or
            ``ranks_per_case`` does not divide the number of ranks.

    """
    ranks_per_case = checked_study_arguments(study, out, comm, ranks_per_case, quiet)
    comm = MPI.COMM_WORLD if comm is None else comm
    if ranks_per_case < 1:  # ("must divide the number of ranks (2)" said 0 and -1)
        raise CaseError(f"--ranks-per-case {ranks_per_case}: must be >= 1 (and divide the "
                        f"number of ranks, {comm.size})")
    if comm.size % ranks_per_case:
        raise CaseError(f"--ranks-per-case {ranks_per_case}: must divide the number of "
                        f"ranks ({comm.size})")
    target = out if out is not None else f"results/{study.name}"
    where = "out" if out is not None else "the study's folder"
    on_rank_zero(comm, lambda: files.check_unmixed(target, where, study=True))
    folder = files.make_directory(target, comm)
    # Rank 0 checks every point (the same error on every rank); then each rank reads
    # the cases itself (cheap, and no large broadcast).
    on_rank_zero(comm, lambda: bool(check_points(study, folder)))
    # (a rank that meets an error alone, a file changed since, raises on every rank)
    points, cases = on_every_rank(comm, lambda: check_points(study, folder))
    # Rank 0's fingerprints: every group then skips and resumes the same cases.
    fingerprints = comm.bcast([checkpoint.case_fingerprint(c.resolved()) for c in cases]
                              if comm.rank == 0 else None, root=0)
    keys = study.keys

    def pending() -> tuple[list[int], list[str]]:
        todo, recorded = [], []
        for j, p in enumerate(points):
            if _finished(folder / p.folder, fingerprints[j]):
                continue
            if _record_finished_run(folder / p.folder, p, fingerprints[j]) is not None:
                recorded.append(p.folder)
                continue
            todo.append(j)
        write_table(folder, points, keys, fingerprints)
        return todo, recorded

    todo, recorded = on_rank_zero(comm, pending)
    say = (lambda text: print(text, flush=True)) if not quiet else (lambda text: None)
    groups = comm.size // ranks_per_case
    if comm.rank == 0:
        say(f"study '{study.name}': {len(points)} cases, {len(points) - len(todo)} finished "
            f"before, {len(todo)} to run by {groups} group(s) of {ranks_per_case} rank(s) "
            f"-> {folder}")
        for name in recorded:
            say(f"  {name}: finished before its record was written (the study was "
                "stopped there): recorded from its summary")
    warning = core_warning(host_usage(comm), ranks_per_case,  # (collective)
                           "--ranks-per-case 1")
    if warning is not None and comm.rank == 0:  # also with --quiet, as the cases'
        print(f"breakwater: warning: {warning}", file=sys.stderr, flush=True)
    group = comm.Split(comm.rank // ranks_per_case, comm.rank)
    counter = _Counter(comm)
    signum, failure = 0, {}  # failure: the cases whose record could not be written
    unwritten: list[str] = []  # the table's write that failed (a full disk), its line
    settle_signal_handlers()  # gmsh's first initialisation, before the signals are caught
    try:
        with StopSignal(poll=counter.stopped, post=counter.stop) as stop:
            while True:
                if group.allreduce(stop.received, op=MPI.MAX):
                    break
                k = group.bcast(counter.next() if group.rank == 0 else None, root=0)
                if k >= len(todo):
                    break
                j = todo[k]
                p = points[j]
                try:
                    record = _run_case(cases[j], p, fingerprints[j], folder / p.folder, group)
                except KeyboardInterrupt:  # the table says so too, then it goes on
                    if group.rank == 0:
                        with contextlib.suppress(OutputError):  # (the interrupt first)
                            write_table(folder, points, keys, fingerprints)
                    raise
                except OutputError as e:  # its record not written (a full disk): the
                    failure = {p.folder: str(e)}  # group stops, the study fails after
                    break  # the other groups' cases, on every rank
                if not _table_written(group, folder, points, keys, fingerprints,
                                      unwritten):
                    break  # (as a record's full disk: the study fails after the others)
                if group.rank == 0:
                    tail = f": {record['error']}" if record["error"] else ""
                    say(f"  {p.folder}: {record['status']} in {record['wall_time']:.1f} s"
                        f"{tail}")
                    for line in record["warnings"]:  # also with --quiet, as a run's
                        print(f"breakwater: warning: {p.folder}: {line}", file=sys.stderr,
                              flush=True)
                if record["status"] == "interrupted":
                    break
            # A signal caught by a rank stops the others (``post``, when the rank finds
            # it: no new case starts anywhere, the running cases stop at their next step
            # as they poll the counter): the ranks agree.
            signum = stop.received
    finally:
        comm.Barrier()
        signum = comm.allreduce(signum, op=MPI.MAX)
        failure = {k: v for f in comm.allgather(failure) for k, v in f.items()}
        unwritten = [line for u in comm.allgather(unwritten) for line in u]
        counter.free()
        group.Free()

    def finish() -> StudyOutcome:
        write_table(folder, points, keys, fingerprints, failure)
        records = read_records(folder, points)
        status = [r.get("status") if r is not None and r.get("fingerprint") == fp else None
                  for r, fp in zip(records, fingerprints, strict=True)]
        status = ["failed" if p.folder in failure else s for p, s in zip(points, status,
                                                                          strict=True)]
        outcome = StudyOutcome(len(points), status.count("finished"),
                               len(points) - len(todo), status.count("failed"),
                               status.count("interrupted"),
                               len(points) - sum(status.count(s) for s in
                                                 ("finished", "failed", "interrupted")))
        # (matplotlib: a second interrupt there broke it for the rest of the process)
        with whole_imports():
            from breakwater.studies import plots as sweepplots
            from breakwater.studies import stormstats

        try:
            drawn = sweepplots.make_figures(folder, study, TABLE)
        except Exception as e:  # the table is written; a figure problem is reported
            print(f"breakwater: warning: the figures of the study could not be drawn: "
                  f"{_one_line(e)}", file=sys.stderr, flush=True)
            drawn = []
        mc = stormstats.monte_carlo(folder, study, *sweepplots.read_table(folder / TABLE))
        if mc is not None and "skipped" in mc:
            say(f"study '{study.name}': no Monte Carlo statistics of the storms: "
                f"{mc['skipped']}")
        elif mc is not None:
            p = mc["percentiles"]
            left = ", ".join(f"{n} {s}" for s, n in mc["left_out"].items())
            count = (f"{mc['storms']} storms" if not left else f"{mc['storms']} of "
                     f"{mc['planned']} storms: {left} left out")
            say(f"study '{study.name}': expected sliding per storm {mc['mean']:.4g} m "
                f"(± {mc['half_width_95']:.2g} m at 95 %, std {mc['std']:.3g} m, "
                f"{count}); percentiles 5/50/95 {p['5']:.3g} / {p['50']:.3g} "
                f"/ {p['95']:.3g} m"
                + "".join(f"; P(> {k} m) = {v:.3g}" for k, v in mc["exceedance"].items())
                + f" -> {folder / 'monte_carlo.json'}")
        if signum:
            print(f"breakwater: study '{study.name}' interrupted by "
                  f"{signal.Signals(signum).name}: {outcome.finished}/{outcome.total} "
                  f"finished, {outcome.interrupted} interrupted, {outcome.not_run} pending "
                  "(run the study again to go on)", file=sys.stderr, flush=True)
        say(f"study '{study.name}': {outcome.finished}/{outcome.total} finished"
            + (f", {outcome.failed} failed" if outcome.failed else "")
            + (f", {outcome.interrupted} interrupted" if outcome.interrupted else "")
            + (f", {outcome.not_run} not run" if outcome.not_run else "")
            + f" -> {folder / TABLE}" + (f" and {len(drawn)} figures" if drawn else ""))
        return outcome

    outcome = on_rank_zero(comm, finish)
    if failure or unwritten:  # as a run's full disk: the study stops in one line, exit 1
        raise OutputError(next(iter(failure.values())) if failure else unwritten[0])
    return outcome


def _table_written(group: MPI.Comm, folder: pathlib.Path, points: Sequence[Point],
                   keys: Sequence[str], fingerprints: Sequence[str], unwritten: list[str]
                   ) -> bool:
    """Rewrite ``sweep.csv`` after a group's case (its rank 0); whether it was written.

    A write that fails (a full disk, on ``sweep.csv`` or its lock file) appends its line
    to ``unwritten`` and stops the group (every rank of it agrees: collective on
    ``group``); the study then fails in that line, after the other groups' cases. It
    used to leave the loop on the failing rank alone, the others waiting for it.
    """
    line = None
    if group.rank == 0:
        try:
            write_table(folder, points, keys, fingerprints)
        except OutputError as e:
            line = str(e)
    line = group.bcast(line, root=0)
    if line is not None:
        unwritten.append(line)
    return line is None

