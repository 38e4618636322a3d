r"""The fast solver's dense interface memory, measured against ``solverchoice.DENSE_COPIES``.

Run on purpose, never in CI (a few steps of each case)::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/solver_choice.py [--steps N]

``time.solver = "auto"`` (:mod:`breakwater.stepping.solverchoice`) takes the fast solver
unless ``DENSE_COPIES`` × 8 n_I² bytes per rank would not fit. Here numpy's own
allocations are traced (``tracemalloc``) while a fast GN22 stepper is built and steps:

- *kept*: the arrays of at least n_I²/4 doubles still allocated after the steps, by the
  line that allocated them (X_II, S, the round-off estimate's |X_II| and |S|, a jump
  system's compliance, ...), leaving out X's body blocks (N_b × n_I: X has its own memory
  check, :class:`~breakwater.stepping.elimination.Elimination`);
- *steps' peak*: the largest traced memory within the steps above what was allocated
  when they began (the Newton's systems, their LU copies and the step's vectors).

Printed per case: n_I, both in units of 8 n_I² bytes, and their sum against
``DENSE_COPIES``. Cases: ``goda3d`` (conforming pair, the jump Newton) and the
separately meshed Goda case (``examples/goda_apart``: a general pair, the active-set
Newton).
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import tempfile
import tracemalloc
from typing import Any

from mpi4py import MPI

import breakwater  # noqa: F401  (loads the PETSc of the dolfinx wheel first)
from breakwater.casefile.case import load_case
from breakwater.statics.initial import initial_state
from breakwater.stepping.gn22 import GN22
from breakwater.stepping.solverchoice import DENSE_COPIES

HERE = pathlib.Path(__file__).resolve().parent
#: Where the fast solver allocates its n_I × n_I arrays: X_II (elimination), S
#: (numpy's inverse), the jump system's compliance, the Newton's kept columns and the
#: round-off estimate's magnitudes (interfacenewton), the near factors (reach).
INTERFACE = ("elimination.py", "_linalg.py", "jumpsystem.py", "interfacenewton.py",
             "reach.py")
CASES = {
    "goda3d": ("goda3d", ["mesh.refinement=1"]),
    "goda_apart": (str(HERE.parent / "examples" / "goda_apart" / "goda_apart.toml"), []),
}


def measure(name: str, overrides: list[str], steps: int) -> dict[str, Any]:
    """n_I and the dense memory of the fast solver over ``steps`` steps (units of 8 n_I²).

    Traced from the stepper's construction; its first step builds the factorisation
    (X_II, S, X's blocks): the arrays alive after it, by allocating line, are *kept*;
    the steps after it give the *steps' peak*.
    """
    comm = MPI.COMM_WORLD
    with tempfile.TemporaryDirectory() as tmp:
        case = load_case(name, [*overrides, f"output.directory={tmp}"])
        model, spec, _, _ = case.build(comm)
        model.set_time(0.0)
        init = initial_state(model)
        tracemalloc.start(1)
        stepper = GN22(model, spec.dt, solver="fast")
        assert stepper.fast is not None
        n = stepper.fast.n
        unit = 8.0 * n * n
        stepper.initialise(init.u, init.v)
        stepper.step()
        snapshot = tracemalloc.take_snapshot()
        tracemalloc.reset_peak()
        start = tracemalloc.get_traced_memory()[0]
        for _ in range(steps - 1):
            stepper.step()
        peak = tracemalloc.get_traced_memory()[1] - start
        tracemalloc.stop()
        x_bytes = sum(b.X.nbytes for f in stepper.fast.factorisations._cache.values()
                      for b in f.X_blocks or ())
        kept: dict[str, float] = {}
        others: dict[str, float] = {}
        for stat in snapshot.statistics("lineno"):
            if stat.size < unit / 4:
                continue
            frame = stat.traceback[0]
            where = f"{pathlib.Path(frame.filename).name}:{frame.lineno}"
            # The interface's arrays (n_I² each), not X's blocks (N_b × n_I, as large as
            # all of them together) nor the mesh's and matrices' (stateproducts' CSR).
            interface = where.startswith(INTERFACE) and abs(stat.size - x_bytes) > unit / 4
            (kept if interface else others)[where] = stat.size / unit
        stepper.destroy()
    return {"n": n, "kept": kept, "others": others, "x_blocks": x_bytes / unit,
            "peak": peak / unit}


def main() -> None:
    """Measure each case and print the table (rank 0)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--steps", type=int, default=20)
    args = parser.parse_args()
    for label, (name, overrides) in CASES.items():
        r = measure(name, overrides, args.steps)
        if MPI.COMM_WORLD.rank:
            continue
        dense = r["kept"]
        total = sum(dense.values())
        print(f"{label}: n_I = {r['n']}; kept (units of 8 n_I² bytes): "
              + ", ".join(f"{k} {v:.2f}" for k, v in sorted(dense.items()))
              + f"; sum {total:.2f}; not counted: X blocks {r['x_blocks']:.1f}, "
              + ", ".join(f"{k} {v:.2f}" for k, v in sorted(r["others"].items()))
              + "; steps' "
              f"peak {r['peak']:.2f}; kept + peak {total + r['peak']:.2f} against "
              f"DENSE_COPIES = {DENSE_COPIES}")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
