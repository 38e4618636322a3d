r"""The step matrix's back-solve on the ranks of the run: PETSc's LU, MUMPS, SuperLU_dist.

Run on purpose, never in CI::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/distributed_lu.py --set mesh.refinement=3
    OPENBLAS_NUM_THREADS=1 .venv/bin/mpiexec -n 2 .venv/bin/python benchmarks/distributed_lu.py \
        --set mesh.refinement=3

Issue 22 asks 2 ranks to run the Goda case 1.4× faster than one; the fast solver's step
is one back-solve with A = M + β₁Δt C + ½β₂Δt² K plus products (the benchmark
records of ``timeloop.py``). On one rank the runs take PETSc's own LU (sequential), under
MPI MUMPS (:func:`~breakwater.stepping.factorisations.lu_package`). This builds the case's
A as the runs do and times, on the ranks of the run, the factorisation and the median of
``--solves`` back-solves of one random right-hand side (wall time between barriers) with
each package available (PETSc's LU on one rank only). On one rank it also times the
back-solve of each body's block of A alone (A is block diagonal by body: the bodies meet
through the contact terms only, which the fast solver keeps out of A): what a partition
that gave each rank whole bodies would take.
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
from breakwater.common.parallel import single_threaded_blas
from breakwater.model.layout import MonolithicLayout
from breakwater.stepping.bulk import BulkOperators, interface_dofs
from breakwater.stepping.factorisations import Factorisations, lu_solver


def _back_solve(ksp: PETSc.KSP, b: PETSc.Vec, x: PETSc.Vec, solves: int,
                comm: MPI.Comm) -> float:
    """The median wall time of ``solves`` back-solves (s), between barriers."""
    times = []
    for _ in range(solves):
        comm.Barrier()
        t0 = time.perf_counter()
        ksp.solve(b, x)
        comm.Barrier()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _packages(comm: MPI.Comm) -> list[str]:
    """The LU packages to time: PETSc's own on one rank, the distributed ones always."""
    return (["petsc"] if comm.size == 1 else []) + ["mumps", "superlu_dist"]


def main() -> None:
    """Build A, factorise and back-solve with each package, print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--case", default=None, help="a built-in case or a case file")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--solves", type=int, default=50)
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *a, **k: None)
    single_threaded_blas(comm)
    model, spec, _, _ = load_case(args.case, args.set).build(comm)
    layout = MonolithicLayout(model)
    bulk = BulkOperators(model, layout)
    factorisations = Factorisations(bulk, interface_dofs(model, layout), spec.beta1,
                                    spec.beta2, interface_solves=False)
    A = factorisations.factorisation(spec.dt).A  # assembled as the runs assemble it
    n = A.getSize()[0]
    say(f"A: {n} unknowns on {comm.size} rank(s) ({args.case or 'goda'} {' '.join(args.set)})")
    b = layout.vec.duplicate()
    b.setRandom()
    x = {}
    for package in _packages(comm):
        comm.Barrier()
        t0 = time.perf_counter()
        ksp = lu_solver(A, package)
        comm.Barrier()
        factorisation = time.perf_counter() - t0
        x[package] = b.duplicate()
        solve = _back_solve(ksp, b, x[package], args.solves, comm)
        say(f"  {package:13s} factorisation {factorisation:8.3f} s, back-solve "
            f"{1e3 * solve:9.3f} ms")
        ksp.destroy()
    first, *rest = x
    for package in rest:
        d = x[package].copy()
        d.axpy(-1.0, x[first])
        say(f"  {package} and {first}: solutions differ by {d.norm() / x[first].norm():.1e}")
        d.destroy()
    if comm.size == 1:
        offsets = np.asarray(layout.offsets)
        blocks = [PETSc.IS().createStride(int(offsets[k + 1] - offsets[k]), int(offsets[k]),
                                          1, comm=PETSc.COMM_SELF)
                  for k in range(len(offsets) - 1)]
        for k, rows in enumerate(blocks):
            Ak = A.createSubMatrix(rows, rows)
            bk, xk = Ak.createVecs()
            bk.setRandom()
            ksp = lu_solver(Ak, "petsc")
            solve = _back_solve(ksp, bk, xk, args.solves, comm)
            say(f"  body '{model.bodies[k].spec.name}' alone: {Ak.getSize()[0]} unknowns "
                f"({Ak.getSize()[0] / n:.0%}), PETSc LU back-solve {1e3 * solve:9.3f} ms")
            for obj in (ksp, Ak, bk, xk, rows):
                obj.destroy()
    for v in (b, *x.values()):
        v.destroy()
    factorisations.destroy()
    bulk.destroy()


if __name__ == "__main__":
    main()
