"""A = M + β₁Δt C + ½β₂Δt² K factorised per Δt, with the bulk's elimination X and S.

For a fixed Δt the matrix of a GN22 step's unknown Δa never changes (the bulk is
linear: :mod:`breakwater.stepping.bulk`). :class:`Factorisations` assembles A from M and
K, factorises it (MUMPS) once per distinct Δt, with ``X = A⁻¹ E`` (one multi-right-hand-
side solve: a column per contact-surface unknown) and the interface Schur complement
``S = (X_II)⁻¹``, and keeps the last few (cut-backs come back to the same Δt); the
back-solves ``A⁻¹ r`` of the steps use them.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from breakwater.common.timings import Timings
from breakwater.stepping.bulk import BulkOperators

__all__ = ["Factorisation", "Factorisations"]


@dataclass
class Factorisation:
    """Everything that depends on Δt only: A factorised, X = A⁻¹ E and S = (X_II)⁻¹."""

    ksp: PETSc.KSP
    A: PETSc.Mat
    X: np.ndarray  # owned rows of A⁻¹ E, shape (n_owned, n_I)
    X_II: np.ndarray  # its interface rows, shape (n_I, n_I), the same on every rank
    S: np.ndarray  # (X_II)⁻¹, the interface Schur complement of A


class Factorisations:
    """A factorised per distinct Δt, with X and S (cached).

    Args:
        bulk: M, K and the Dirichlet rows (A's rows and columns of the fixed DOFs are
            the identity's).
        interface: Global stacked indices of the contact-surface DOFs (sorted).
        beta1: GN22 β₁.
        beta2: GN22 β₂.
        cache: Factorisations kept (distinct Δt).
        timings: Where the factorisations (``factorisation``, X included) and the
            back-solves (``back_solves``) are timed.
        interface_solves: Compute X and S (False: A only, for the benchmark's floor).
    """

    def __init__(self, bulk: BulkOperators, interface: np.ndarray, beta1: float,
                 beta2: float, cache: int = 4, timings: Timings | None = None,
                 interface_solves: bool = True) -> None:
        self.bulk = bulk
        self.model, self.layout = bulk.model, bulk.layout
        self.timings = timings or Timings()
        self._interface_solves_on = interface_solves
        self.interface = interface
        self.beta1, self.beta2 = beta1, beta2
        self._cache: OrderedDict[float, Factorisation] = OrderedDict()
        self._cache_size = cache

    def factorisation(self, dt: float) -> Factorisation:
        """A = M + β₁Δt C + ½β₂Δt² K factorised, X and S (cached by Δt)."""
        if dt in self._cache:
            self._cache.move_to_end(dt)
            return self._cache[dt]
        with self.timings("factorisation"):
            return self._factorise(dt)

    def _factorise(self, dt: float) -> Factorisation:
        A = self.bulk.M.duplicate(copy=True)
        d = self.model.damping
        A.scale(1.0 + self.beta1 * dt * d.alpha)
        A.axpy(0.5 * self.beta2 * dt**2 + self.beta1 * dt * d.beta, self.bulk.K)
        A.zeroRowsColumns((self.layout.start + self.bulk.bc_rows).astype(PETSc.IntType), diag=1.0)
        # Its one product per step (the bulk rows' residual at Newton's start, for the
        # relative test) row by row, without PETSc's "inode" grouping of rows: 3.4×
        # faster on these P2 matrices (0.93 against 0.27 ms at refinement 3). M and K keep
        # the grouping: the row sums differ from it in the last bit, and the predictor's
        # products feed the state, whose 2-rank equality (tests/test_mpi.py) the χ = 1e-10
        # stick tangent holds to 5e-11 with it and 3.6e-10 without (2026-11-23).
        A.setOption(PETSc.Mat.Option.USE_INODES, False)  # type: ignore[arg-type]
        ksp = PETSc.KSP().create(self.model.comm)  # type: ignore[arg-type]
        ksp.setOptionsPrefix(self.model.options_prefix("bulk"))
        ksp.setOperators(A)
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType("lu")
        pc.setFactorSolverType("mumps")
        ksp.setFromOptions()
        ksp.setUp()
        if self._interface_solves_on and len(self.interface):
            X = self._interface_solves(ksp, A)
            X_II = self._gather_rows(X)
            S = np.linalg.inv(X_II)
        else:
            X = np.zeros((self.layout.offsets[-1], len(self.interface)))
            X_II = S = np.zeros((len(self.interface), len(self.interface)))
        fact = Factorisation(ksp, A, X, X_II, S)
        self._cache[dt] = fact
        if len(self._cache) > self._cache_size:
            _, old = self._cache.popitem(last=False)
            old.ksp.destroy()
            old.A.destroy()
        return fact

    def _interface_solves(self, ksp: PETSc.KSP, A: PETSc.Mat) -> np.ndarray:
        """X = A⁻¹ E: one solve per contact-surface DOF (one MUMPS multi-RHS solve)."""
        comm = self.model.comm
        n_i = len(self.interface)
        n_local = self.layout.offsets[-1]
        start = self.layout.start
        E = PETSc.Mat().createDense(((n_local, None), (None, n_i)),
                                    comm=comm)  # type: ignore[arg-type]
        E.setUp()
        E.zeroEntries()
        mine = (self.interface >= start) & (self.interface < start + n_local)
        cols = np.flatnonzero(mine)
        for row, col in zip(self.interface[mine], cols, strict=True):
            E.setValue(int(row), int(col), 1.0)
        E.assemble()
        X = E.duplicate()
        ksp.getPC().getFactorMatrix().matSolve(E, X)
        out = np.array(X.getDenseArray(), copy=True)
        E.destroy()
        X.destroy()
        return out

    def _gather_rows(self, X: np.ndarray) -> np.ndarray:
        """The interface rows of X (owned rows), gathered on every rank."""
        start, n_local = self.layout.start, self.layout.offsets[-1]
        mine = (self.interface >= start) & (self.interface < start + n_local)
        out = np.zeros((len(self.interface), X.shape[1]))
        out[mine] = X[self.interface[mine] - start]
        self.model.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        return out

    def solve(self, fact: Factorisation, rhs: PETSc.Vec, out: PETSc.Vec) -> None:
        """Out = A⁻¹ rhs."""
        with self.timings("back_solves"):
            fact.ksp.solve(rhs, out)

    def destroy(self) -> None:
        """Free the PETSc objects of the factorisations kept."""
        for f in self._cache.values():
            f.ksp.destroy()
            f.A.destroy()
        self._cache.clear()
