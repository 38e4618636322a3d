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

__all__ = ["ALIGNMENTS", "Factorisation", "Factorisations", "XBlock", "x_blocks"]


@dataclass
class XBlock:
    """A block of X = A⁻¹ E on this rank: some owned rows, the columns they can meet.

    A couples no two bodies (the stacked M and K are block diagonal), so the column of X
    of a body's interface unknown is zero, exactly, on the other bodies' rows: X is
    stored as (owned rows of a body) × (a range of columns holding that body's
    interface unknowns) blocks, or as one block of all its owned rows and columns.
    """

    rows: slice  # owned rows of the stacked vector
    cols: np.ndarray  # interface positions (consecutive)
    X: np.ndarray  # X[rows, cols], shape (rows, len(cols)), column-major (as MUMPS's X)


@dataclass
class Factorisation:
    """Everything that depends on Δt only: A factorised, X = A⁻¹ E and S = (X_II)⁻¹."""

    ksp: PETSc.KSP
    A: PETSc.Mat
    # The owned rows of X = A⁻¹ E by body (zero elsewhere); None: X is not kept, a
    # second back-solve is cheaper than the product with it (Factorisations.keep_X).
    X_blocks: list[XBlock] | None
    X_II: np.ndarray  # its interface rows, shape (n_I, n_I), the same on every rank
    S: np.ndarray  # (X_II)⁻¹, the interface Schur complement of A

    def subtract_X(self, fc: np.ndarray, out: np.ndarray) -> None:
        """``out −= X f_c`` on the owned rows (``out``: the owned part of a stacked vector).

        Block by block: the rows of each body only meet its own interface unknowns.
        """
        assert self.X_blocks is not None, "X is not kept: solve A Δ = E f_c instead"
        for b in self.X_blocks:
            out[b.rows] -= b.X @ fc[b.cols]


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
        keep_X: Keep X for the step's ``Δa = z − X f_c`` (True), or not (False: the
            step takes a second back-solve ``A⁻¹(r₀ − E f_c)`` instead); None: by the
            estimated cost (:meth:`keep_X`).
    """

    #: Time per entry of A's factors in a back-solve over the time per entry of X's
    #: body blocks in the product ``X f_c``; both are memory-bound. Measured on the
    #: Goda case (1 rank, one BLAS thread, the same factorisation, CPU time, 2026-11-25):
    #: 3.1 at refinement 3 (3.0 ms for 3.0e6 factor entries against 0.69 ms for
    #: 2.15e6), 2.95 at refinement 9 (57 ms for 3.48e7 against 28.5 ms for 5.13e7;
    #: benchmarks/records/2026-11-25-xblocks.md); the smaller, rounded down.
    SOLVE_PER_PRODUCT = 2.5

    def __init__(self, bulk: BulkOperators, interface: np.ndarray, beta1: float,
                 beta2: float, cache: int = 4, timings: Timings | None = None,
                 interface_solves: bool = True, keep_X: bool | None = None) -> None:
        self.bulk = bulk
        self.model, self.layout = bulk.model, bulk.layout
        self.timings = timings or Timings()
        self._interface_solves_on = interface_solves
        self._keep_X = keep_X
        self.interface = interface
        self.beta1, self.beta2 = beta1, beta2
        self._cache: OrderedDict[float, Factorisation] = OrderedDict()
        self.cache_size = cache

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
        blocks: list[XBlock] | None
        if self._interface_solves_on and len(self.interface):
            blocks = self._interface_solves(ksp)
            X_II = self._gather_rows(blocks)
            S = np.linalg.inv(X_II)
            if not self.keep_X(ksp, blocks):
                blocks = None
        else:
            blocks = []
            X_II = S = np.zeros((len(self.interface), len(self.interface)))
        fact = Factorisation(ksp, A, blocks, X_II, S)
        self._cache[dt] = fact
        if len(self._cache) > self.cache_size:
            _, old = self._cache.popitem(last=False)
            old.ksp.destroy()
            old.A.destroy()
        return fact

    def keep_X(self, ksp: PETSc.KSP, blocks: list[XBlock]) -> bool:
        """Whether the product with X's blocks is cheaper than a second back-solve.

        Both read their operands once per step: the product ``X f_c`` the entries of
        X's blocks (each rank its own rows: the largest count), the back-solve
        ``A⁻¹(r₀ − E f_c)`` those of A's LU factors (MUMPS INFOG(29), all of them: on
        2 ranks a back-solve was measured to take as much CPU per rank as serially,
        3.0–3.8 against 2.9 ms at refinement 3), each :attr:`SOLVE_PER_PRODUCT` times
        slower. In 2D the blocks grow as N^1.5 (n_I ~ √N), the factors as N log N: the
        back-solve wins on fine enough meshes. The same decision on every rank.
        """
        if self._keep_X is not None:
            return self._keep_X
        comm = self.model.comm
        info = comm.allreduce(ksp.getPC().getFactorMatrix().getMumpsInfog(29), op=MPI.MAX)
        factors = float(info) if info >= 0 else -1e6 * info  # < 0: millions
        entries = comm.allreduce(sum(b.X.size for b in blocks), op=MPI.MAX)
        return bool(entries <= self.SOLVE_PER_PRODUCT * factors)

    def _interface_bodies(self) -> np.ndarray:
        """The body of each interface unknown (the same array on every rank)."""
        start, n_local = self.layout.start, self.layout.offsets[-1]
        mine = (self.interface >= start) & (self.interface < start + n_local)
        body = np.zeros(len(self.interface), np.int64)
        body[mine] = np.searchsorted(self.layout.offsets, self.interface[mine] - start,
                                     side="right") - 1
        self.model.comm.Allreduce(MPI.IN_PLACE, body, op=MPI.SUM)
        return body

    def _interface_solves(self, ksp: PETSc.KSP) -> list[XBlock]:
        """X = A⁻¹ E (one MUMPS multi-right-hand-side solve), kept by body block.

        The block of a body: its owned rows and a range of columns (aligned to one of
        :data:`ALIGNMENTS`) holding its interface unknowns; the product with the blocks
        then skips only exact zeros. Kept only if (checked on this rank) X is zero
        outside the blocks and the blocks' products give the whole X's, ``X @ f_c``, bit
        for bit (the BLAS's sums grouped as before: the χ = 1e-10 stick tangent
        magnifies the last bit into the Newton counts, 5198 → 5206 on the Goda case with
        the blocks' own sums); else X is one block.
        """
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
        return x_blocks(out, self.layout.offsets, self._interface_bodies())

    def _gather_rows(self, blocks: list[XBlock]) -> np.ndarray:
        """The interface rows of X (owned rows), gathered on every rank."""
        rows = self.interface - self.layout.start
        out = np.zeros((len(self.interface), len(self.interface)))
        for b in blocks:
            lo, hi = b.rows.start, b.rows.stop
            at = np.flatnonzero((rows >= lo) & (rows < hi))
            out[np.ix_(at, b.cols)] += b.X[rows[at] - lo]  # blocks overlap at zeros
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


#: The ranges tried for a body's block: its rows and its interface unknowns' columns,
#: widened to multiples of each (the BLAS's column-major dgemv takes rows and columns 4
#: or 8 at a time, the rows left over one by one, in another order), the first whose
#: product keeps every bit; then all rows and columns.
ALIGNMENTS = (4, 8, 16, 32, 64, 128, 256, 512)


def _aligned(lo: int, hi: int, align: int, size: int) -> slice:
    return slice(lo // align * align, min(size, -(-hi // align) * align))


def x_blocks(X: np.ndarray, offsets: np.ndarray, body: np.ndarray) -> list[XBlock]:
    """X's owned rows by body block, where that changes no bit of ``X @ f_c``.

    Args:
        X: The owned rows of X = A⁻¹ E, column-major (as MUMPS gives it).
        offsets: The bodies' offsets in the owned part of a stacked vector.
        body: The body of each interface unknown (column).

    Returns:
        One block per body with owned rows and interface unknowns: its rows and its
        columns widened to ranges aligned to one of :data:`ALIGNMENTS` (a neighbour's
        rows in them hold zeros), outside which X is zero, if for every body the blocks'
        ``out[rows] −= block.X @ f_c`` give ``out − X @ f_c`` bit for bit (two random
        f_c); else X as one block.
    """
    m, n_i = X.shape
    whole = [XBlock(slice(0, m), np.arange(n_i), X)]
    rng = np.random.default_rng(22)
    trials = [rng.uniform(0.5, 1.5, n_i) * rng.choice((-1.0, 1.0), n_i) for _ in range(2)]
    products = [X @ fc for fc in trials]
    blocks = []
    for b in range(len(offsets) - 1):
        own = slice(int(offsets[b]), int(offsets[b + 1]))
        at = np.flatnonzero(body == b)
        if own.stop == own.start or not len(at):
            if np.any(X[own]):
                return whole
            continue
        if np.any(X[own, : at[0]]) or np.any(X[own, at[-1] + 1:]):
            return whole
        for align in (*ALIGNMENTS, max(m, n_i)):  # the last: all rows and columns
            rows = _aligned(own.start, own.stop, align, m)
            cols = _aligned(int(at[0]), int(at[-1]) + 1, align, n_i)
            # A copy: the window of all rows and columns is X itself, whose neighbour
            # rows the next lines zero (np.asfortranarray returned X's own memory there,
            # and X became zero: a singular X_II on a mesh whose blocks needed it).
            block = XBlock(rows, np.arange(cols.start, cols.stop),
                           np.array(X[rows, cols], order="F", copy=True))
            block.X[: own.start - rows.start] = 0.0  # a neighbour's rows
            block.X[own.stop - rows.start:] = 0.0
            mine = slice(own.start - rows.start, own.stop - rows.start)
            if all(np.array_equal((block.X @ fc[cols])[mine], w[own])
                   for fc, w in zip(trials, products, strict=True)):
                break
        else:
            return whole
        blocks.append(block)
    return blocks
