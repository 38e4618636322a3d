r"""A prototype storm wave by wave: adaptive against fixed steps, and the rigid model (issue 24).

Run on purpose, never in CI::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/storm.py [--waves N] [--compare N]

Issue 24's performance goal: a storm of 1000 waves at prototype scale on the default
mesh in under 5 minutes on one core. The case is ``examples/prototype/storm.toml`` (a
B = 30 m caisson in h = 20 m on a rubble mound, H_1/3 = 8 m, T_1/3 = 14 s, Rayleigh
heights of seed 0, adaptive steps from 0.25 s). In one process, back to back:

- ``fixed``: the first ``--compare`` waves (default 10) with fixed steps of 1/64 s (the
  adaptive run's smaller steps, a quarter of its smallest allowed), the reference;
- ``adaptive``: the same waves with the example's adaptive steps (tolerance 1e-2);
- ``adaptive-1e-3``: the same with the default tolerance 1e-3;
- ``storm``: ``--waves`` waves (default 1000) with the example's settings.

Printed: steps, the time loop's CPU time and its ratio to the fixed run's, the total
sliding against the fixed run's, and for the storm the loop's CPU time per wave and in
all, with the rigid-block model's total sliding (the FE run's own reference, no added
mass) and the wall time of the rigid model alone.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import tempfile
import time
from typing import Any

from mpi4py import MPI

import breakwater  # noqa: F401  (loads the PETSc of the dolfinx wheel first)

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from general_vs_conforming import _run

STORM = pathlib.Path(__file__).parents[1] / "examples" / "prototype" / "storm.toml"
COMMON = ("output.figures=false", "output.checkpoint_interval=0")


def _waves(n: int) -> list[str]:
    return [f"loads.storm.storm.sea.waves={n}", f"time.end_time={14.0 * n}"]


def _line(name: str, run: dict[str, Any], ref: dict[str, Any] | None) -> str:
    s = run["summary"]
    loop = s["solver"]["time_loop"]["cpu"]
    total = s["storm"]["total_sliding"]
    text = (f"{name:16s} {s['solver']['steps']:8d} steps  loop CPU {loop:8.2f} s  "
            f"total sliding {total:.6e} m")
    if ref is not None:
        r = ref["summary"]
        text += (f"  ({loop / r['solver']['time_loop']['cpu']:.3f}× the loop, sliding "
                 f"{100 * (total / r['storm']['total_sliding'] - 1):+.2f} %)")
    return text


def main() -> None:
    """Run the cases and print the figures (rank 0)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--waves", type=int, default=1000)
    parser.add_argument("--compare", type=int, default=10)
    parser.add_argument("--out", type=pathlib.Path, default=None)
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    tmp = tempfile.mkdtemp(prefix="storm_") if comm.rank == 0 else None
    out = args.out or pathlib.Path(comm.bcast(tmp, root=0))
    case = (str(STORM),)
    few = _waves(args.compare)
    fixed = _run("fixed", out, [*few, "time.adaptive=false", "time.dt=0.015625"], case,
                 COMMON)
    adaptive = _run("adaptive", out, few, case, COMMON)
    strict = _run("adaptive-1e-3", out, [*few, "time.tolerance=1e-3"], case, COMMON)
    storm = _run("storm", out, _waves(args.waves), case, COMMON)
    if comm.rank != 0:
        return
    print(f"\n{args.compare} waves of {STORM.name}, one process, back to back:")
    print(_line("fixed 1/64 s", fixed, None))
    print(_line("adaptive 1e-2", adaptive, fixed))
    print(_line("adaptive 1e-3", strict, fixed))
    s = storm["summary"]
    loop = s["solver"]["time_loop"]["cpu"]
    print(f"\n{args.waves} waves: {s['solver']['steps']} steps "
          f"({s['solver']['steps'] / args.waves:.0f} per wave), time loop CPU {loop:.1f} s "
          f"({loop / args.waves:.3f} s per wave; wall {s['solver']['wall_time']:.1f} s with "
          f"the set-up and outputs); total sliding {s['storm']['total_sliding']:.6e} m, "
          f"rigid block {s['storm']['rigid']['total_sliding']:.6e} m")
    from breakwater.storms.rigid import Caisson, storm_sliding
    from breakwater.storms.seastate import SeaState, wave_train
    from breakwater.storms.waves import Site

    site = Site(depth=20.0, toe_depth=14.5, berm_depth=11.0, crest_height=5.0,
                base_width=30.0)
    caisson = Caisson(mass=2100.0 * 30.0 * 19.5, base_width=30.0, toe_depth=14.5,
                      friction=0.6)
    start = time.process_time()
    storm_sliding(wave_train(SeaState(8.0, 14.0, waves=args.waves, seed=0), site), site,
                  caisson)
    print(f"the rigid-block model alone, the same storm: "
          f"{time.process_time() - start:.3f} s CPU")


if __name__ == "__main__":
    main()
