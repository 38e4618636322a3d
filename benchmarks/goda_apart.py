r"""The Goda case meshed apart by hand against the conforming case (issue 23).

Run on purpose, never in CI (three full runs, a few minutes)::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/goda_apart.py [--out DIR] [--repeat N]

Issue 23's acceptance: a separately meshed Goda case (``examples/goda_apart/``: a
``.geo`` written by hand, gmsh's Delaunay algorithm, caisson elements 12 mm, mound
22 mm, 14 mm on the crest; not ``meshes/goda.py``) with the general pair's default
settings finishes with mean Newton iterations per step within 1.5× of the conforming
run's, headline results within 2 % (peaks) and 10 % (residuals) of the conforming
run's, and a time loop within 1.5× of the conforming one's. Three runs through the
CLI, in one process, back to back:

- ``conforming``: the built-in case (the paper's mesh, caisson 29 mm, mound 26.5 mm);
- ``conforming-fine``: the built-in case meshed at the apart mesh's sizes (caisson and
  crest 12 mm, mound 22 mm), so that the time loops compare like with like;
- ``apart``: ``examples/goda_apart/goda_apart.toml``.

Every run takes the mound's shear modulus of the conforming calibration at refinement
1 (2.27789e6 Pa: calibration with a general pair is refused), and point probes of both
bodies at the caisson's base corners (slip = caisson − mound u_x; the pair probes of
the conforming runs check them). Printed: the headline table with relative
differences to ``conforming``, and the solvers' figures with the time loops' ratios;
with ``--repeat N``, N − 1 more pairs of ``conforming-fine`` and ``apart`` run back to
back, and the median of the N pairs' ratios.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import tempfile

import numpy as np
from mpi4py import MPI

import breakwater  # noqa: F401  (loads the PETSc of the dolfinx wheel first)

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from general_vs_conforming import COMMON, _headline, _run

APART = pathlib.Path(__file__).parents[1] / "examples" / "goda_apart" / "goda_apart.toml"
FINE = ["mesh.goda.caisson_element_size=0.012", "mesh.goda.mound_element_size=0.022"]
APART_PROBES = [f'output.probes.{c}_caisson={{body="caisson", group="{c}"}}'
                for c in ("corner_front", "corner_rear")] + [
    'output.probes.corner_front_mound={body="mound", point=[-0.1025, 0.19]}',
    'output.probes.corner_rear_mound={body="mound", point=[0.1025, 0.19]}']


def main() -> None:
    """Run the three cases and print the tables (rank 0)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=pathlib.Path, default=None)
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--repeat", type=int, default=1,
                        help="run conforming-fine and apart this many times, alternately, "
                             "and print each pair's ratio and their median (the machine's "
                             "speed drifts by 20 %% within minutes)")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    tmp = tempfile.mkdtemp(prefix="goda_apart_") if comm.rank == 0 else None
    out = args.out or pathlib.Path(comm.bcast(tmp, root=0))
    common = [s for s in COMMON if not s.startswith("output.probes.")]
    runs = {
        "conforming": _run("conforming", out, args.set),
        "conforming-fine": _run("conforming-fine", out, [*FINE, *args.set]),
        "apart": _run("apart", out, [*APART_PROBES, *args.set], (str(APART),), common),
    }
    pairs = [(runs["conforming-fine"], runs["apart"])]
    for k in range(1, args.repeat):
        pairs.append((_run(f"conforming-fine-{k}", out, [*FINE, *args.set]),
                      _run(f"apart-{k}", out, [*APART_PROBES, *args.set], (str(APART),),
                           common)))
    if comm.rank > 0:
        return
    rows = {k: _headline(r) for k, r in runs.items()}
    ref = rows["conforming"]
    print(f"Goda case: conforming, conforming at 12/22 mm, apart ({APART.name}); "
          f"outputs in {out}\n")
    print("| result | " + " | ".join(runs) + " |")
    print("|---|" + "---|" * len(runs))
    for key, x in ref.items():
        cells = [f"{rows[k][key]:.6g}" + (f" ({(rows[k][key] - x) / abs(x):+.2%})"
                                          if k != "conforming" and x else "")
                 for k in runs]
        print(f"| {key} | " + " | ".join(cells) + " |")
    print("\n| solver | " + " | ".join(runs) + " |")
    print("|---|" + "---|" * len(runs))
    for key in ("steps", "newton_iterations", "mean_newton_iterations",
                "max_newton_iterations", "cutbacks", "round_off_accepts"):
        cells = [r["summary"]["solver"].get(key) for r in runs.values()]
        print(f"| {key} | " + " | ".join(f"{c:.4g}" if isinstance(c, float) else str(c)
                                         for c in cells) + " |")
    for key in ("wall", "cpu"):
        cells = [r["summary"]["solver"]["time_loop"][key] for r in runs.values()]
        print(f"| time loop {key} (s) | " + " | ".join(f"{c:.3g}" for c in cells) + " |")
    loop = {k: r["summary"]["solver"]["time_loop"]["cpu"] for k, r in runs.items()}
    its = {k: r["summary"]["solver"]["mean_newton_iterations"] for k, r in runs.items()}
    print(f"\napart / conforming: mean Newton iterations {its['apart'] / its['conforming']:.2f}"
          f"x, time loop (CPU) {loop['apart'] / loop['conforming']:.2f}x; apart / "
          f"conforming-fine: {its['apart'] / its['conforming-fine']:.2f}x, "
          f"{loop['apart'] / loop['conforming-fine']:.2f}x")
    if len(pairs) > 1:
        cpu = [(f["summary"]["solver"]["time_loop"]["cpu"],
                a["summary"]["solver"]["time_loop"]["cpu"]) for f, a in pairs]
        ratios = [a / f for f, a in cpu]
        print("\nconforming-fine and apart alternately, time loops (CPU): " + ", ".join(
            f"{f:.2f}/{a:.2f} s ({a / f:.2f}x)" for f, a in cpu)
              + f"; median ratio {float(np.median(ratios)):.2f}x")


if __name__ == "__main__":
    main()
