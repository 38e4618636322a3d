"""The Goda case with the conforming pair and with a general pair on the same mesh.

Run on purpose, never in CI (two full Goda runs, about 1-2 min)::

    .venv/bin/python benchmarks/general_vs_conforming.py
    .venv/bin/python benchmarks/general_vs_conforming.py --set time.end_time=0.05
    .venv/bin/mpiexec -n 2 .venv/bin/python benchmarks/general_vs_conforming.py

Issue 12, item 5: on the conforming Goda mesh the general path (closest-point
kinematics, segment-to-segment integration: :mod:`breakwater.surfacepair`) should give
the headline results of the conforming (node-to-node) path within 0.5 %. The built-in
case runs twice through the CLI, each in its own output folder:

- ``conforming``: the case as it is (``[contact.interface]``, the shared facet group);
- ``general``: the same pair made general on the same group, ``slave_surface =
  master_surface = "interface"`` (each side takes the group's facets on its own body).
  Calibration with a general pair is a case error, so both runs take the mound's shear
  modulus from the conforming calibration, G = 2.27789e6 Pa (refinement 1); the
  general run drops the pair probes, the corners being measured as below.

The slip and opening at the caisson's base corners are measured the same way in both
runs, from point probes of both bodies at ``corner_front`` and ``corner_rear``
(slave minus master; the crest is horizontal, so the slip is the u_x jump and the
opening the u_y jump, as the pair probes' ``slip``/``opening``); the conforming run's
pair probes check them. Printed: a Markdown table of the headline results (summary.json
``dynamic``: peak and residual u_x per gauge, time of the largest u_x, residual slip
and largest uplift) with the relative differences, and the solver's figures.

Both runs start from their static state (the general one from
:mod:`breakwater.relaxation`). The results are in the README ("general pairs").
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
from breakwater.files import read_history

G_MOUND = 2.27789e6  # Pa: the conforming calibration at refinement 1 (K_x = 500 kN/m)
CORNERS = ("corner_front", "corner_rear")

COMMON = ["calibration.enabled=false", f"bodies.mound.shear_modulus={G_MOUND}",
          "output.figures=false", "output.field_interval=0",
          *(f'output.probes.{c}_{b}={{body="{b}", group="{c}"}}'
            for c in CORNERS for b in ("caisson", "mound"))]
GENERAL = ['contact.interface.slave_surface="interface"',
           'contact.interface.master_surface="interface"', "output.pair_probes={}"]


def _run(name: str, out: pathlib.Path, extra: list[str]) -> dict[str, Any]:
    """One CLI run; its summary and history (every rank)."""
    argv = ["run", "--out", str(out / name), "--no-progress", "--quiet"]
    for s in [*COMMON, *extra]:
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
    """Run both cases and print the tables (rank 0)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a case override for both runs (e.g. time.end_time=0.05)")
    parser.add_argument("--out", type=pathlib.Path, default=None,
                        help="output folder (default: a temporary one)")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    tmp = tempfile.mkdtemp(prefix="general_vs_conforming_") if comm.rank == 0 else None
    out = args.out or pathlib.Path(comm.bcast(tmp, root=0))
    conforming = _run("conforming", out, args.set)
    general = _run("general", out, [*args.set, *GENERAL])
    if comm.rank > 0:
        return
    # The corner probes reproduce the conforming run's pair probes.
    d = conforming["summary"]["dynamic"]
    check = _corners(conforming["history"])
    assert abs(check["corner_front_slip"][-1] - d["residual_slip"]) <= \
        1e-9 * max(abs(d["residual_slip"]), 1e-12), (check["corner_front_slip"][-1], d)
    assert abs(max(check[f"{c}_opening"].max() for c in CORNERS) - d["max_uplift"]) <= \
        1e-9 * max(abs(d["max_uplift"]), 1e-12)
    a, b = _headline(conforming), _headline(general)
    print(f"Goda case, conforming mesh, G_mound = {G_MOUND} Pa; outputs in {out}\n")
    print("| result | conforming | general | relative difference |")
    print("|---|---|---|---|")
    for key, x in a.items():
        y = b[key]
        rel = (y - x) / abs(x) if x else float("nan")
        print(f"| {key} | {x:.6g} | {y:.6g} | {rel:+.2%} |")
    print("\n| solver | conforming | general |\n|---|---|---|")
    sa, sb = conforming["summary"]["solver"], general["summary"]["solver"]
    for key in ("steps", "newton_iterations", "max_newton_iterations", "cutbacks",
                "wall_time"):
        if key in sa:
            print(f"| {key} | {sa[key]} | {sb.get(key)} |")


if __name__ == "__main__":
    main()
