r"""The step matrix's LU package: PETSc's own LU against MUMPS on the same A (one rank).

Run on purpose, never in CI::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/lu_package.py \
        [--case goda] [--set mesh.refinement=3 ...] [--solves 200]

The fast solver factorises A = M + β₁Δt C + ½β₂Δt² K once per Δt and back-solves with it
once per step (:mod:`breakwater.stepping.factorisations`); which package does it is
:func:`~breakwater.stepping.factorisations.lu_package`'s rule. This benchmark builds the
case's A once and, in one process, factorises it with each package as the runs do
(:func:`~breakwater.stepping.factorisations.lu_solver`) and times ``--solves`` back-solves of
one random right-hand side with each, alternating the packages in rounds (this machine's
speed drifts). Printed: the factorisation's CPU time, the median back-solve's, the
factors' entries, and the ratios MUMPS/PETSc, with the largest difference of the two
solutions relative to their size.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

import breakwater  # noqa: F401  (loads the PETSc of the dolfinx wheel first)
from breakwater.casefile.case import load_case
from breakwater.model.layout import MonolithicLayout
from breakwater.stepping.bulk import BulkOperators, interface_dofs
from breakwater.stepping.factorisations import Factorisations, factor_entries, lu_solver

PACKAGES = ("petsc", "mumps")


def _factorise(A: PETSc.Mat, package: str) -> tuple[PETSc.KSP, float]:
    """A factorised by ``package`` as the runs factorise it; the factorisation's CPU (s)."""
    c0 = time.process_time()
    ksp = lu_solver(A, package)
    return ksp, time.process_time() - c0


def main() -> None:
    """Build A, factorise and back-solve with both packages, print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--case", default=None, help="a built-in case or a case file")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--solves", type=int, default=200)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    if MPI.COMM_WORLD.size != 1:
        raise SystemExit("PETSc's own LU factorises on one rank: run without mpiexec")
    model, spec, _, _ = load_case(args.case, args.set).build(MPI.COMM_WORLD)
    layout = MonolithicLayout(model)
    bulk = BulkOperators(model, layout)
    factorisations = Factorisations(bulk, interface_dofs(model, layout), spec.beta1,
                                    spec.beta2, interface_solves=False)
    A = factorisations.factorisation(spec.dt).A  # assembled as the runs assemble it
    rhs = layout.vec.duplicate()
    rhs.setRandom()
    solvers = {p: _factorise(A, p) for p in PACKAGES}
    out = {p: layout.vec.duplicate() for p in PACKAGES}
    times: dict[str, list[float]] = {p: [] for p in PACKAGES}
    per_round = max(1, args.solves // args.rounds)
    for _ in range(args.rounds):
        for p in PACKAGES:
            ksp = solvers[p][0]
            for _ in range(per_round):
                c0 = time.process_time()
                ksp.solve(rhs, out[p])
                times[p].append(time.process_time() - c0)
    x, y = out["petsc"].array, out["mumps"].array
    n, nnz = A.getSize()[0], int(A.getInfo()["nz_used"])
    print(f"A: {n} unknowns, {nnz} entries ({args.case or 'goda'} {' '.join(args.set)})")
    print(f"{'package':8s} {'factorisation CPU (s)':>22s} {'back-solve CPU (µs)':>20s} "
          f"{'factor entries':>15s}")
    row = {}
    for p in PACKAGES:
        ksp, fact = solvers[p]
        solve = statistics.median(times[p])
        row[p] = (fact, solve)
        print(f"{p:8s} {fact:22.3f} {1e6 * solve:20.1f} {factor_entries(ksp):15.4g}")
    print(f"MUMPS/PETSc: factorisation {row['mumps'][0] / row['petsc'][0]:.2f}×, back-solve "
          f"{row['mumps'][1] / row['petsc'][1]:.2f}×; the solutions differ by "
          f"{np.abs(x - y).max() / np.abs(y).max():.1e} of their size")
    for ksp, _ in solvers.values():
        ksp.destroy()
    for v in (rhs, *out.values()):
        v.destroy()
    factorisations.destroy()
    bulk.destroy()


if __name__ == "__main__":
    main()
