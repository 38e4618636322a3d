"""Benchmark of the time loop: the fast path against the reference, side by side.

Run on purpose, never in CI::

    .venv/bin/python benchmarks/timeloop.py                       # default Goda case + refinements
    .venv/bin/python benchmarks/timeloop.py --refinements 1 3     # a subset
    .venv/bin/mpiexec -n 2 .venv/bin/python benchmarks/timeloop.py --refinements 9
    .venv/bin/python benchmarks/timeloop.py --case goda3d --refinements 1 1.5 --no-reference

For each mesh refinement of the built-in Goda case, both solvers (``time.solver =
"fast"`` and ``"reference"``) run the same case in this one process, one after the other,
through :func:`breakwater.run.simulation.run` with every output of the case file (history,
ledger, probes, fields at their interval). The reference path may be given a shorter end
time on big meshes (``--reference-end-time``); its figures are then per step and the
speed-up is the ratio of the times per step. Printed and recorded for each run: DOFs,
contact-surface DOFs, steps, Newton iterations, wall time of the time loop and its split
(factorisation, back-solves, interface assembly, bulk products, Newton, outputs, the rest),
peak memory and its growth over the run, the speed-up over the reference and the ratio of
the time loop to the linear-algebra floor: one factorisation of A = M + β₁Δt C + ½β₂Δt² K
plus one back-solve per step, both timed in this process on the same model.

The record is written to ``benchmarks/records/<date>-<ranks>.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import pathlib
import platform
import statistics
import tempfile
import threading
import time
from typing import Any

import numpy as np
from mpi4py import MPI

import breakwater  # noqa: F401  (loads the PETSc of the dolfinx wheel first)
from breakwater.casefile.case import load_case
from breakwater.common.parallel import single_threaded_blas
from breakwater.model.layout import MonolithicLayout
from breakwater.run.simulation import run
from breakwater.stepping.bulk import BulkOperators, interface_dofs
from breakwater.stepping.factorisations import Factorisations

HERE = pathlib.Path(__file__).resolve().parent
PAGE = os.sysconf("SC_PAGE_SIZE")


class MemorySampler:
    """Resident memory of this process, sampled every ``interval`` seconds in a thread."""

    def __init__(self, interval: float = 0.02) -> None:
        self.interval = interval
        self.samples: list[tuple[float, int]] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._sample, daemon=True)

    @staticmethod
    def rss() -> int:
        """Resident memory now (bytes)."""
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * PAGE

    def _sample(self) -> None:
        while not self._stop.is_set():
            self.samples.append((time.perf_counter(), self.rss()))
            self._stop.wait(self.interval)

    def __enter__(self) -> MemorySampler:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()
        self.samples.append((time.perf_counter(), self.rss()))

    def peak(self) -> int:
        """The largest sample (bytes)."""
        return max(s for _, s in self.samples)

    def growth(self, since: float) -> float:
        """Growth of the resident memory after ``since`` (bytes), from a linear fit."""
        t = np.array([a for a, _ in self.samples if a >= since])
        m = np.array([b for a, b in self.samples if a >= since], dtype=float)
        if len(t) < 3 or np.ptp(t) == 0:
            return 0.0
        slope = np.polyfit(t - t[0], m, 1)[0]
        return float(slope * np.ptp(t))


def floor(case_overrides: list[str], comm: MPI.Comm, backsolves: int = 20,
          name: str | None = None) -> dict[str, float]:
    """One factorisation of A and the mean of ``backsolves`` back-solves (s), this process."""
    case = load_case(name, case_overrides)
    model, spec, _, _ = case.build(comm)
    layout = MonolithicLayout(model)
    bulk = BulkOperators(model, layout)
    factorisations = Factorisations(bulk, interface_dofs(model, layout), spec.beta1,
                                    spec.beta2, interface_solves=False)
    comm.barrier()
    t0, c0 = time.perf_counter(), time.process_time()
    fact = factorisations.factorisation(spec.dt)
    c_fact = time.process_time() - c0
    comm.barrier()
    t_fact = time.perf_counter() - t0
    rhs, x = layout.vec.duplicate(), layout.vec.duplicate()
    rhs.setRandom()
    times, cpu = [], []
    for _ in range(backsolves):
        comm.barrier()
        t0, c0 = time.perf_counter(), time.process_time()
        fact.ksp.solve(rhs, x)
        cpu.append(time.process_time() - c0)
        comm.barrier()
        times.append(time.perf_counter() - t0)
    factorisations.destroy()
    bulk.destroy()
    return {"factorisation": comm.allreduce(t_fact, op=MPI.MAX),
            "back_solve": comm.allreduce(statistics.median(times), op=MPI.MAX),
            "factorisation_cpu": comm.allreduce(c_fact, op=MPI.MAX),
            "back_solve_cpu": comm.allreduce(statistics.median(cpu), op=MPI.MAX)}


def one_run(overrides: list[str], solver: str, comm: MPI.Comm,
            name: str | None = None) -> dict[str, Any]:
    """Run the case with one solver; the figures of the benchmark table."""
    with tempfile.TemporaryDirectory() as tmp:
        out = comm.bcast(tmp, root=0)
        case = load_case(name, [*overrides, f"time.solver={solver}", "output.figures=false",
                                f"output.directory={out}"])
        model, spec, output, extra = case.build(comm)
        dofs = sum(b.V.dofmap.index_map.size_global * b.V.dofmap.index_map_bs
                   for b in model.bodies)
        layout = MonolithicLayout(model)
        n_i = len(interface_dofs(model, layout))
        with MemorySampler() as memory:
            summary = run(model, spec, output, resolved_case=case.resolved(),
                          extra_summary=extra, report=False)
        loop = summary["solver"]["time_loop"]
        started = memory.samples[0][0] + (summary["solver"]["wall_time"] - loop["wall"])
        peak = comm.allreduce(memory.peak(), op=MPI.SUM)
        growth = comm.allreduce(memory.growth(started), op=MPI.SUM)
    return {"solver": solver, "dofs": dofs, "interface_dofs": n_i,
            "steps": summary["solver"]["steps"],
            "newton_iterations": summary["solver"]["newton_iterations"],
            "end_time": spec.end_time, "loop": loop,
            "peak_memory_mb": peak / 2**20, "memory_growth_mb": growth / 2**20}


def table(records: list[dict[str, Any]]) -> str:
    """The Markdown table of a benchmark record."""
    head = ("| refinement | solver | DOFs | interface DOFs | steps | Newton its | time loop (s) | "
            "per step (ms) | factorisation | back-solves | interface assembly | bulk products | "
            "Newton | outputs | rest | peak memory (MB) | growth (MB) | speed-up | loop / floor | "
            "CPU (s) | speed-up (CPU) | CPU / floor CPU |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in records:
        loop = r["loop"]
        parts = ("factorisation", "back_solves", "interface_assembly", "bulk_products",
                 "newton", "outputs")
        rest = loop["wall"] - sum(loop.get(k, 0.0) for k in parts)
        split = [f"{loop.get(k, 0.0):.2f}" for k in parts] + [f"{rest:.2f}"]
        lines.append(
            f"| {r['refinement']} | {r['solver']} | {r['dofs']} | {r['interface_dofs']} | "
            f"{r['steps']} | {r['newton_iterations']} | {loop['wall']:.2f} | "
            f"{1e3 * r['per_step']:.2f} | " + " | ".join(split) +
            f" | {r['peak_memory_mb']:.0f} | {r['memory_growth_mb']:+.1f} | "
            f"{r['speed_up']:.1f}× | {r['over_floor']:.1f}× | {r['cpu']:.2f} | "
            f"{r['speed_up_cpu']:.1f}× | {r['over_floor_cpu']:.1f}× |")
    return "\n".join(lines)


def main() -> None:
    """Run the benchmark and write its record."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--case", default=None,
                        help="a built-in case or case file (default: the Goda case; "
                        "goda3d: the 3D one)")
    parser.add_argument("--refinements", type=float, nargs="+", default=[1.0, 3.0, 9.0])
    parser.add_argument("--end-time", type=float, default=0.15,
                        help="end time of the fast runs (s); default the case's 0.15 s")
    parser.add_argument("--reference-end-time", type=float, default=None,
                        help="end time of the reference runs on refinements > 1 (s)")
    parser.add_argument("--no-reference", action="store_true")
    parser.add_argument("--out", type=pathlib.Path, default=HERE / "records")
    parser.add_argument("--suffix", default="", help="appended to the record's name")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *a, **k: None)
    # As the fast solver sets it under MPI, for the floor too (the same BLAS threads).
    single_threaded_blas(comm)
    # The machine's load and the process's CPU set, recorded with the figures: wall times
    # on a shared machine, or with fewer cores than ranks, are not comparable.
    load_start = os.getloadavg()
    # The kernels compiled, or loaded from numba's cache, before any loop is timed: after
    # a change to a kernel's file the first run's loop held the compilation (the paper
    # mesh 5.8 s against 3.7 s, 2026-11-26).
    say("warming up the compiled kernels (a few steps) ...", flush=True)
    one_run([f"mesh.refinement={min(args.refinements):g}", "time.end_time=5e-4"], "fast", comm,
            args.case)
    records = []
    for r in args.refinements:
        base = [f"mesh.refinement={r}"]
        fl = floor(base, comm, name=args.case)
        runs = {}
        for solver in ("fast", "reference"):
            if solver == "reference" and args.no_reference:
                continue
            end = args.end_time
            if solver == "reference" and r > 1 and args.reference_end_time is not None:
                end = min(end, args.reference_end_time)
            say(f"refinement {r:g}, {solver}: running to t = {end:g} s ...", flush=True)
            rec = one_run([*base, f"time.end_time={end}"], solver, comm, args.case)
            rec["refinement"] = r
            rec["per_step"] = rec["loop"]["wall"] / rec["steps"]
            rec["floor"] = fl["factorisation"] + rec["steps"] * fl["back_solve"]
            rec["floor_parts"] = fl
            rec["over_floor"] = rec["loop"]["wall"] / rec["floor"]
            # The same on CPU time (this rank's process, all threads): on a loaded machine
            # the work done, whatever the waiting for a core.
            rec["floor_cpu"] = fl["factorisation_cpu"] + rec["steps"] * fl["back_solve_cpu"]
            rec["cpu"] = comm.allreduce(rec["loop"].get("cpu", float("nan")), op=MPI.MAX)
            rec["over_floor_cpu"] = rec["cpu"] / rec["floor_cpu"]
            runs[solver] = rec
            say(f"  {rec['steps']} steps, {rec['newton_iterations']} Newton iterations, "
                f"time loop {rec['loop']['wall']:.2f} s ({1e3 * rec['per_step']:.2f} ms per "
                f"step), {rec['over_floor']:.1f}× the floor; CPU {rec['cpu']:.2f} s, "
                f"{rec['over_floor_cpu']:.1f}× the floor's", flush=True)
        for rec in runs.values():
            ref = runs.get("reference")
            rec["speed_up"] = ref["per_step"] / rec["per_step"] if ref else float("nan")
            rec["speed_up_cpu"] = (ref["cpu"] / ref["steps"]) / (rec["cpu"] / rec["steps"]) \
                if ref else float("nan")
            records.append(rec)
    md = table(records)
    say("\n" + md)
    if comm.rank == 0:
        args.out.mkdir(parents=True, exist_ok=True)
        stem = (f"{datetime.date.today().isoformat()}-np{comm.size}-"
                + (f"{pathlib.Path(args.case).stem}-" if args.case else "") + "r"
                + "-".join(f"{r:g}" for r in args.refinements) + args.suffix)
        meta = {"date": datetime.date.today().isoformat(), "ranks": comm.size,
                "case": args.case or "goda",
                "machine": f"{platform.machine()}, {os.cpu_count()} cores",
                "python": platform.python_version(),
                "cpus_used": len(os.sched_getaffinity(0)),
                "blas_threads_env": os.environ.get("OPENBLAS_NUM_THREADS"),
                "load_average": {"start": load_start, "end": os.getloadavg()}}
        (args.out / f"{stem}.json").write_text(json.dumps({**meta, "runs": records}, indent=1))
        (args.out / f"{stem}.md").write_text(
            f"# Time-loop benchmark, {meta['date']}, {comm.size} rank(s)\n\n"
            f"Machine: {meta['machine']}; this process on {meta['cpus_used']} of them"
            + (f", OPENBLAS_NUM_THREADS={meta['blas_threads_env']}"
               if meta["blas_threads_env"] else "")
            + f"; load average (1 min) {meta['load_average']['start'][0]:.2f} at the start, "
            f"{meta['load_average']['end'][0]:.2f} at the end.\n"
            "Times in seconds unless stated; the reference path's "
            "split has the outputs and its SNES (assembly, factorisation and Newton at every "
            "iteration) under Newton.\n"
            "The floor is one factorisation of A plus one back-solve per step, timed in the "
            "same process (median of 20 back-solves). The CPU columns are the same on the "
            "process's CPU time (all threads; under MPI the slowest rank): on a loaded "
            "machine, the work done whatever the wait for a core.\n\n" + md + "\n")
        say(f"\nwritten {args.out / stem}.json and .md")


if __name__ == "__main__":
    main()
