r"""The Goda case with the conforming pair and with general pairs on the same mesh.

Run on purpose, never in CI (a conforming run of 6 s and general runs of 2-3 min each)::

    .venv/bin/python benchmarks/general_vs_conforming.py
    .venv/bin/python benchmarks/general_vs_conforming.py --variant nodes-small
    .venv/bin/python benchmarks/general_vs_conforming.py --repeat 5
    .venv/bin/python benchmarks/general_vs_conforming.py --set mesh.refinement=2 \
        --set bodies.mound.shear_modulus=2.30835e6
    .venv/bin/mpiexec -n 2 .venv/bin/python benchmarks/general_vs_conforming.py

Issue 12, item 5: on the conforming Goda mesh the general path (closest-point
kinematics: :mod:`breakwater.contact.general`) should give the headline results of the
conforming (node-to-node) path within 0.5 %. The built-in case runs through the CLI,
each run in its own output folder:

- ``conforming``: the case as it is (``[contact.interface]``, the shared facet group);
- general runs, the same pair made general on the same mesh (``slave_surface =
  "interface"``; each side takes a group's facets on its own body), one per variant
  (:data:`VARIANTS`):

  - ``segments``: the general pair's defaults (segment-to-segment Gauss integration,
    the current normal), master surface the shared group;
  - ``nodes``: node-to-segment (the slave nodes with Simpson weights, the conforming
    pair's quadrature), master surface the shared group and the crest beyond it
    (``mound_surface``), so that the caisson's corners sliding past the end of the
    shared group stay on the mound;
  - ``nodes-small``: as ``nodes`` with ``rotations = "small"`` (the reference
    normal, as the conforming pair's).

Calibration with a general pair is a case error, so every run takes the mound's shear
modulus from the conforming calibration, G = 2.27789e6 Pa (refinement 1; pass the
calibrated value of another refinement with ``--set``); the general runs drop the
pair probes, the corners being measured as below.

The slip and opening at the caisson's base corners are measured the same way in every
run, from point probes of both bodies at ``corner_front`` and ``corner_rear``
(slave minus master; the crest is horizontal, so the slip is the u_x jump and the
opening the u_y jump, as the pair probes' ``slip``/``opening``); the conforming run's
pair probes check them. Printed: a Markdown table of the headline results (summary.json
``dynamic``: peak and residual u_x per gauge, time of the largest u_x, residual slip
and largest uplift) with the relative differences, and the solvers' figures: the
Newton counts, the whole run's wall time, the time loops (wall and CPU) and the loops'
ratios to the conforming run's (issue 22's target is on the loops); with ``--repeat N``,
N − 1 more rounds of the conforming case and the variants, alternately, and the median
of each variant's N ratios.

Every run starts from its static state (the general ones from
:mod:`breakwater.statics.relaxation`). The results are in the README ("general pairs").
"""

from __future__ import annotations

import argparse
import json
import pathlib
import tempfile
from typing import Any

import numpy as np
from mpi4py import MPI

import breakwater  # noqa: F401  (loads the PETSc of the dolfinx wheel first)
from breakwater import cli
from breakwater.common.files import read_history

G_MOUND = 2.27789e6  # Pa: the conforming calibration at refinement 1 (K_x = 500 kN/m)
CORNERS = ("corner_front", "corner_rear")

COMMON = ["calibration.enabled=false", f"bodies.mound.shear_modulus={G_MOUND}",
          "output.figures=false", "output.field_interval=0",
          *(f'output.probes.{c}_{b}={{body="{b}", group="{c}"}}'
            for c in CORNERS for b in ("caisson", "mound"))]
GENERAL = ['contact.interface.slave_surface="interface"', "output.pair_probes={}"]
VARIANTS = {
    "segments": ['contact.interface.master_surface="interface"'],
    "nodes": ['contact.interface.master_surface=["interface", "mound_surface"]',
              'contact.interface.integration="nodes"'],
    "nodes-small": ['contact.interface.master_surface=["interface", "mound_surface"]',
                    'contact.interface.integration="nodes"',
                    'contact.interface.rotations="small"'],
}


def _run(name: str, out: pathlib.Path, extra: list[str], case: tuple[str, ...] = (),
         common: tuple[str, ...] | list[str] = tuple(COMMON)) -> dict[str, Any]:
    """One CLI run of ``case`` (the built-in one if empty); its summary and history."""
    argv = ["run", *case, "--out", str(out / name), "--no-progress", "--quiet"]
    for s in [*common, *extra]:
        argv += ["--set", s]
    code = cli.main(argv)
    if code != 0:
        raise SystemExit(f"the {name} run failed (exit {code})")
    summary = json.loads((out / name / "summary.json").read_text())
    return {"summary": summary, "history": read_history(out / name / "history.csv")}


def _corners(history: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Slip and opening at the base corners from the point probes of both bodies."""
    out = {}
    for c in CORNERS:
        out[f"{c}_slip"] = history[f"{c}_caisson_ux"] - history[f"{c}_mound_ux"]
        out[f"{c}_opening"] = history[f"{c}_caisson_uy"] - history[f"{c}_mound_uy"]
    return out


def _headline(run: dict[str, Any]) -> dict[str, float]:
    """The headline results: summary.json ``dynamic`` and the corners' slip and uplift."""
    d = run["summary"]["dynamic"]
    corners = _corners(run["history"])
    rows = {}
    for gauge in ("gauge_top", "gauge_bottom"):
        rows[f"peak u_x {gauge} (m)"] = d["peak_ux"][gauge]["value"]
        rows[f"residual u_x {gauge} (m)"] = d["residual_ux"][gauge]
    rows["time of max u_x (s)"] = d["time_of_max_ux"]
    rows["residual slip corner_front (m)"] = float(corners["corner_front_slip"][-1])
    rows["max uplift (m)"] = float(max(corners[f"{c}_opening"].max() for c in CORNERS))
    return rows


def main() -> None:
    """Run the cases and print the tables (rank 0)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a case override for every run (e.g. time.end_time=0.05)")
    parser.add_argument("--variant", action="append", choices=list(VARIANTS),
                        help="a general run to make (default: all)")
    parser.add_argument("--out", type=pathlib.Path, default=None,
                        help="output folder (default: a temporary one)")
    parser.add_argument("--repeat", type=int, default=1,
                        help="run the conforming case and each variant this many times, "
                             "alternately, and print each round's loop ratios and their "
                             "medians (the machine's speed drifts by 20 %% within minutes)")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    tmp = tempfile.mkdtemp(prefix="general_vs_conforming_") if comm.rank == 0 else None
    out = args.out or pathlib.Path(comm.bcast(tmp, root=0))
    conforming = _run("conforming", out, args.set)
    variants = args.variant or list(VARIANTS)
    general = {v: _run(v, out, [*args.set, *GENERAL, *VARIANTS[v]]) for v in variants}
    rounds = [{v: general[v]["summary"]["solver"]["time_loop"]["cpu"]
               / conforming["summary"]["solver"]["time_loop"]["cpu"] for v in variants}]
    for k in range(1, args.repeat):
        base = _run(f"conforming-{k}", out, args.set)["summary"]["solver"]["time_loop"]["cpu"]
        rounds.append({v: _run(f"{v}-{k}", out, [*args.set, *GENERAL, *VARIANTS[v]])[
            "summary"]["solver"]["time_loop"]["cpu"] / base for v in variants})
    if comm.rank > 0:
        return
    # The corner probes reproduce the conforming run's pair probes.
    d = conforming["summary"]["dynamic"]
    check = _corners(conforming["history"])
    assert abs(check["corner_front_slip"][-1] - d["residual_slip"]) <= \
        1e-9 * max(abs(d["residual_slip"]), 1e-12), (check["corner_front_slip"][-1], d)
    assert abs(max(check[f"{c}_opening"].max() for c in CORNERS) - d["max_uplift"]) <= \
        1e-9 * max(abs(d["max_uplift"]), 1e-12)
    a = _headline(conforming)
    rows = {v: _headline(run) for v, run in general.items()}
    print(f"Goda case, conforming mesh, overrides {COMMON[:2] + args.set}; "
          f"outputs in {out}\n")
    print("| result | conforming | " + " | ".join(general) + " |")
    print("|---|---|" + "---|" * len(general))
    for key, x in a.items():
        cells = [f"{rows[v][key]:.6g} ({(rows[v][key] - x) / abs(x):+.2%})" if x
                 else f"{rows[v][key]:.6g}" for v in general]
        print(f"| {key} | {x:.6g} | " + " | ".join(cells) + " |")
    print("\n| solver | conforming | " + " | ".join(general) + " |")
    print("|---|---|" + "---|" * len(general))
    runs = [conforming, *general.values()]
    for key in ("steps", "newton_iterations", "max_newton_iterations", "cutbacks",
                "wall_time"):
        cells = [run["summary"]["solver"].get(key) for run in runs]
        label = "wall_time (the whole run)" if key == "wall_time" else key
        print(f"| {label} | " + " | ".join(f"{c:.4g}" if isinstance(c, float) else str(c)
                                           for c in cells) + " |")
    # Issue 22's target is on the time loops (the run's set-up and static state aside).
    loops = [run["summary"]["solver"]["time_loop"] for run in runs]
    for key in ("wall", "cpu"):
        print(f"| time loop {key} (s) | " + " | ".join(f"{t[key]:.3g}" for t in loops) + " |")
    print("\ntime loop (CPU) / conforming's: " + ", ".join(
        f"{v} {t['cpu'] / loops[0]['cpu']:.2f}x"
        for v, t in zip(general, loops[1:], strict=True)))
    if args.repeat > 1:
        print("\nthe conforming case and the variants alternately, loop ratios per round: "
              + "; ".join(", ".join(f"{v} {r[v]:.2f}x" for v in variants) for r in rounds))
        print("median ratios: " + ", ".join(
            f"{v} {float(np.median([r[v] for r in rounds])):.2f}x" for v in variants))


if __name__ == "__main__":
    main()
