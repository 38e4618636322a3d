"""Benchmark of a general pair's static state: issue 23's Hertz line contact.

Run on purpose, never in CI::

    .venv/bin/python benchmarks/hertz_static.py              # the reported case
    .venv/bin/python benchmarks/hertz_static.py --fine 0.8e-3 --order 1

The case of issue 23 (``docs/general-contact.md``, "The reported case"): an elastic
half-cylinder, R = 0.1 m, pressed by P = 5e4 N/m onto an elastic block, E = 1 GPa,
ν = 0.3, frictionless, quarter model (:func:`breakwater.meshes.hertz.hertz`: the block
3R × 3R, 0.4 mm elements within 2b of the contact, 4 mm elsewhere, second-order
geometry), ε_n = 1e14 N/m³. Johnson (Contact Mechanics, 1985, §4.3, eq. 4.45):
b = sqrt(4PR/(πE*)), p₀ = 2P/(πb), p(x) = p₀ sqrt(1 − x²/b²), E* = E/(2(1 − ν²)).

Timed in this process: the static state alone
(:func:`breakwater.statics.initial.initial_state` on the built model: wall and CPU
seconds, Newton iterations, pseudo steps), and beside it one factorisation of the step
matrix A of the same model (the linear-algebra unit of its Newton). Then the case runs
two steps through the command line for the static pressure field (``static.npz``), which
is compared with p(x) over |x| < 0.9 b. Issue 23's target: the static state in under
a minute; the field within 3 % of p₀ over |x| < 0.9 b, p₀ within 2 %.

The record is written to ``benchmarks/records/<date>-hertz-static.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import pathlib
import platform
import tempfile
import time
from typing import Any

import numpy as np
import tomli_w
from mpi4py import MPI

import breakwater  # noqa: F401  (loads the PETSc of the dolfinx wheel first)

# isort: split
from breakwater.meshes.hertz import hertz

from breakwater import cli
from breakwater.casefile.case import load_case
from breakwater.model.layout import MonolithicLayout
from breakwater.statics.initial import initial_state
from breakwater.stepping.bulk import BulkOperators, interface_dofs
from breakwater.stepping.factorisations import Factorisations

HERE = pathlib.Path(__file__).resolve().parent
R, E, NU, P = 0.1, 1e9, 0.3, 5e4
E_STAR = E / (2 * (1 - NU**2))
B = math.sqrt(4 * P * R / (math.pi * E_STAR))
P0 = 2 * P / (math.pi * B)


def case_file(folder: pathlib.Path, fine: float, coarse: float, penalty: float, order: int,
              comm: MPI.Comm) -> pathlib.Path:
    """The mesh and case file of the Hertz line contact (collective)."""
    mesh = hertz(folder / "hertz.msh", comm, R, 3 * R, 3 * R, fine, coarse, 2 * B,
                 overlap=0.1 * B**2 / (2 * R), order=order)
    case = folder / "hertz.toml"
    material = {"density": 2000.0, "poisson": NU, "young_modulus": E}
    if comm.rank == 0:
        case.write_text(tomli_w.dumps({
            "name": "hertz_static", "gravity": [0.0, 0.0], "mesh": {"source": str(mesh)},
            "bodies": {"cylinder": material, "block": material},
            "calibration": {"enabled": False},
            "fixed": {"block_bottom": {}, "block_axis": {"components": [0]},
                      "cylinder_axis": {"components": [0]}},
            "contact": {"hertz": {"slave": "cylinder", "master": "block",
                                  "slave_surface": "cylinder_contact",
                                  "master_surface": "block_top", "penalty": penalty}},
            "loads": {"top": {"group": "cylinder_top", "pressure": P / (2 * R)}},
            "time": {"dt": 1e-4, "end_time": 2e-4},
            "output": {"field_interval": 0, "figures": False}}))
    comm.barrier()
    return case


def static_timed(case: pathlib.Path, comm: MPI.Comm) -> dict[str, Any]:
    """The static state of the built case, timed; and one factorisation of A beside it."""
    model, spec, _, _ = load_case(str(case)).build(comm)
    dofs = sum(b.V.dofmap.index_map.size_global * b.V.dofmap.index_map_bs for b in model.bodies)
    model.set_time(0.0)
    comm.barrier()
    t0, c0 = time.perf_counter(), time.process_time()
    init = initial_state(model)
    cpu = time.process_time() - c0
    comm.barrier()
    wall = time.perf_counter() - t0
    layout = MonolithicLayout(model)
    bulk = BulkOperators(model, layout)
    factorisations = Factorisations(bulk, interface_dofs(model, layout), spec.beta1,
                                    spec.beta2, interface_solves=False)
    comm.barrier()
    t0 = time.perf_counter()
    factorisations.factorisation(spec.dt)
    comm.barrier()
    factorisation = time.perf_counter() - t0
    factorisations.destroy()
    bulk.destroy()
    return {"dofs": dofs, "wall": comm.allreduce(wall, op=MPI.MAX),
            "cpu": comm.allreduce(cpu, op=MPI.MAX), "newton_iterations": init.iterations,
            "pseudo_steps": (init.relaxation or {}).get("pseudo_steps"), "kind": init.kind,
            "factorisation": comm.allreduce(factorisation, op=MPI.MAX)}


def pressure_field(case: pathlib.Path, out: pathlib.Path) -> dict[str, float]:
    """The static pressure field of a run of two steps (the command line), against Johnson."""
    assert cli.main(["run", str(case), "--out", str(out), "--no-progress", "--quiet"]) == 0
    with np.load(out / "static.npz") as data:
        x, p = data["contact_hertz_x"][:, 0], data["contact_hertz_pressure"]
    exact = P0 * np.sqrt(np.clip(1 - (x / B) ** 2, 0.0, None))
    inside = np.abs(x) < 0.9 * B
    axis = int(np.argmin(np.abs(x)))
    error = (p - exact)[inside] / P0
    return {"nodes_inside": int(inside.sum()), "error_min": float(error.min()),
            "error_max": float(error.max()), "axis": float(p[axis] / P0 - 1)}


def main() -> None:
    """Run the benchmark and write its record."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--fine", type=float, default=4e-4, help="element size within 2b (m)")
    parser.add_argument("--coarse", type=float, default=4e-3, help="element size far (m)")
    parser.add_argument("--penalty", type=float, default=1e14, help="ε_n (N/m³)")
    parser.add_argument("--order", type=int, default=2, help="geometric order (1 or 2)")
    parser.add_argument("--out", type=pathlib.Path, default=HERE / "records")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *a, **k: None)
    load_start = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        folder = pathlib.Path(comm.bcast(tmp, root=0))
        case = case_file(folder, args.fine, args.coarse, args.penalty, args.order, comm)
        say(f"Hertz line contact: b = {1e3 * B:.3f} mm, p₀ = {P0 / 1e6:.3f} MPa; static "
            "state ...", flush=True)
        timed = static_timed(case, comm)
        say(f"  {timed['dofs']} DOFs: {timed['wall']:.1f} s ({timed['cpu']:.1f} s CPU), "
            f"{timed['newton_iterations']} Newton iterations, {timed['pseudo_steps']} pseudo "
            f"steps ({timed['kind']}); one factorisation of A {timed['factorisation']:.2f} s",
            flush=True)
        field = pressure_field(case, folder / "run")
    say(f"  pressure field over |x| < 0.9 b ({field['nodes_inside']} nodes): "
        f"{100 * field['error_min']:+.2f} … {100 * field['error_max']:+.2f} % of p₀, axis "
        f"{100 * field['axis']:+.2f} %")
    if comm.rank == 0:
        meta = {"date": datetime.date.today().isoformat(), "ranks": comm.size,
                "machine": f"{platform.machine()}, {os.cpu_count()} cores",
                "cpus_used": len(os.sched_getaffinity(0)),
                "load_average": {"start": load_start, "end": os.getloadavg()},
                "settings": vars(args) | {"out": str(args.out)}, "b": B, "p0": P0}
        record = {**meta, **timed, "pressure": field}
        stem = f"{meta['date']}-np{comm.size}-hertz-static"
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / f"{stem}.json").write_text(json.dumps(record, indent=1))
        (args.out / f"{stem}.md").write_text(
            f"# Hertz static state (issue 23), {meta['date']}, {comm.size} rank(s)\n\n"
            f"`benchmarks/hertz_static.py` (fine {args.fine:g} m, coarse {args.coarse:g} m, "
            f"ε_n {args.penalty:g} N/m³, geometric order {args.order}). Machine: "
            f"{meta['machine']}, this process on {meta['cpus_used']}; load average (1 min) "
            f"{load_start[0]:.2f} at the start, {meta['load_average']['end'][0]:.2f} at the "
            "end.\n\n"
            "| DOFs | static state (s) | CPU (s) | Newton iterations | pseudo steps | "
            "factorisation of A (s) | static / factorisation | p − p(x) over |x| < 0.9 b "
            "(% of p₀) | axis (% of p₀) |\n|---|---|---|---|---|---|---|---|---|\n"
            f"| {timed['dofs']} | {timed['wall']:.1f} | {timed['cpu']:.1f} | "
            f"{timed['newton_iterations']} | {timed['pseudo_steps']} | "
            f"{timed['factorisation']:.2f} | {timed['wall'] / timed['factorisation']:.0f}× | "
            f"{100 * field['error_min']:+.2f} … {100 * field['error_max']:+.2f} | "
            f"{100 * field['axis']:+.2f} |\n")
        say(f"written {args.out / stem}.json and .md")


if __name__ == "__main__":
    main()
