"""X = A⁻¹E, the bulk's response to unit interface forces: whole by body block, or X_II alone.

For a factorised step matrix A (:mod:`breakwater.stepping.factorisations`),
:class:`Elimination` solves A X = E, a column per contact-surface unknown. Where X fits in
the node's available memory (:mod:`breakwater.common.memory`) it is solved in one
multi-right-hand-side solve and kept by body block (:func:`x_blocks`); otherwise it is
solved a chunk of columns at a time and only its interface rows X_II are kept (n_I ×
n_I instead of N × n_I: 0.2 GB on the 3D Goda block, about 40 GB at its refinement 3).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from breakwater.common.console import SlowPhase
from breakwater.common.memory import fits

__all__ = ["ALIGNMENTS", "Elimination", "XBlock", "x_blocks"]


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


class Elimination:
    """X = A⁻¹ E for the factorisations of one model: its interface rows, and X if it fits.

    Args:
        comm: The model's communicator.
        offsets: The stacked vector's local offsets by body (the layout's).
        start: The first global row owned by this rank.
        interface: Global stacked indices of the contact-surface DOFs (sorted).

    """

    #: The share of its node's available memory that X = A⁻¹E may take while it is
    #: built whole: E, X and the copy kept, three N × n_I arrays of 8 bytes per rank.
    X_MEMORY = 0.5
    #: Bytes per rank of one chunk's right-hand sides and solutions when X is built in
    #: chunks (at least one column): 104 columns of ``goda3d`` at refinement 2.3.
    CHUNK_BYTES = 2.0**29
    #: MUMPS's ICNTL(27), right-hand sides solved together (each block reads the factors
    #: once), at most: X_II of ``goda3d`` at refinement 1.5 (2108 columns, 105 084 rows)
    #: took 11.9 s in chunks of 52 with MUMPS's default block, 9.0 s in chunks of 208
    #: with blocks of 128 (2026-11-28).
    RHS_BLOCK = 128
    #: X of at least this many entries (N × n_I) is announced before its solves: the 3D
    #: Goda case's at refinement 1.5 (2.2e8) took 40 s of a first step.
    ANNOUNCE = 5e7

    def __init__(self, comm: MPI.Comm, offsets: np.ndarray, start: int,
                 interface: np.ndarray) -> None:
        self.comm, self.offsets, self.start = comm, offsets, start
        self.interface = interface
        self.size = comm.allreduce(int(offsets[-1]))  # the stacked vector's, N (collective)
        self._said_chunks = False

    def solve(self, ksp: PETSc.KSP, available: float | None
              ) -> tuple[list[XBlock] | None, np.ndarray, int]:
        """X's blocks (None: not built whole), X_II and the chunks it took (0: whole).

        Args:
            ksp: A factorised.
            available: The node's available memory (bytes) that :attr:`X_MEMORY` is a
                fraction of; None: measured now.

        """
        chunk = self._chunk_columns(available)
        if chunk is None:
            if self.comm.rank == 0 and self.size * len(self.interface) >= self.ANNOUNCE:
                logging.getLogger("breakwater").info(
                    "interface compliance X = A⁻¹E: %d back-solves of %d unknowns (%.3g GB)",
                    len(self.interface), self.size, 8e-9 * self.size * len(self.interface))
            blocks = self._interface_solves(ksp)
            return blocks, self._gather_rows(blocks), 0
        self._say_chunks(chunk)
        return None, self._interface_rows(ksp, chunk), -(-len(self.interface) // chunk)

    def _chunk_columns(self, available: float | None) -> int | None:
        """None if X may be built whole here; else the columns of each chunk (collective).

        Whole: E, X and the copy kept (3 × 8 N n_I bytes per rank) within
        :attr:`X_MEMORY` of every node's available memory.
        """
        comm = self.comm
        n_local, n_i = int(self.offsets[-1]), len(self.interface)
        if fits(comm, 3 * 8.0 * n_local * n_i, self.X_MEMORY, available):
            return None
        widest = comm.allreduce(n_local, op=MPI.MAX)
        return int(max(1, min(n_i, self.CHUNK_BYTES // (2 * 8 * max(widest, 1)))))

    def _say_chunks(self, chunk: int) -> None:
        """Log, once and on rank 0, that X is not kept and why."""
        if self._said_chunks:
            return
        self._said_chunks = True
        comm, n = self.comm, self.size
        if comm.rank == 0:
            n_i = len(self.interface)
            logging.getLogger("breakwater").info(
                "X = A⁻¹E (%d × %d, %.3g GB) does not fit in %d%% of the memory available: "
                "built %d columns at a time, keeping its interface rows; each step takes a "
                "second back-solve instead", n, n_i, 8e-9 * n * n_i, round(100 * self.X_MEMORY),
                chunk)

    def _interface_rows(self, ksp: PETSc.KSP, chunk: int) -> np.ndarray:
        """X_II, the interface rows of X = A⁻¹ E, solved ``chunk`` columns at a time.

        Only X_II is kept (n_I × n_I, gathered on every rank): X's other rows are
        dropped chunk by chunk, so the memory taken is that of one chunk, not of X.
        """
        comm = self.comm
        n_i = len(self.interface)
        n_local, start = int(self.offsets[-1]), self.start
        mine = (self.interface >= start) & (self.interface < start + n_local)
        rows = self.interface[mine] - start  # this rank's interface rows (local)
        at = np.flatnonzero(mine)  # their positions among the interface unknowns
        out = np.zeros((n_i, n_i))
        phase = SlowPhase(logging.getLogger("breakwater"), "interface compliance X_II")
        for lo in range(0, n_i, chunk):
            hi = min(n_i, lo + chunk)
            X = self._solve_columns(ksp, lo, hi)
            out[at, lo:hi] = X.getDenseArray()[rows]
            X.destroy()
            if comm.rank == 0:
                phase("%d of %d columns", hi, n_i)
        comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        return out

    def _solve_columns(self, ksp: PETSc.KSP, lo: int, hi: int) -> PETSc.Mat:
        """A⁻¹ E for E's columns lo to hi (dense, this rank's rows; the caller destroys it).

        Column j of E is the unit vector of interface unknown j (a 1 on its row). MUMPS
        takes it as a sparse right-hand side: its forward elimination then visits only
        the fronts above each 1 (PETSc passes it as the transpose of an AIJ matrix held
        on rank 0, as MUMPS asks). PETSc's own LU (one rank) takes E dense.
        """
        comm, n = self.comm, self.size
        n_local = int(self.offsets[-1])
        X = PETSc.Mat().createDense(((n_local, None), (None, hi - lo)),
                                    comm=comm)  # type: ignore[arg-type]
        X.setUp()
        F = ksp.getPC().getFactorMatrix()
        if ksp.getPC().getFactorSolverType() != "mumps":
            E = PETSc.Mat().createDense(((n_local, None), (None, hi - lo)),
                                        comm=comm)  # type: ignore[arg-type]
            E.setUp()
            rows = self.interface[lo:hi] - self.start
            mine = np.flatnonzero((rows >= 0) & (rows < n_local))
            E.getDenseArray()[rows[mine], mine] = 1.0
            E.assemble()
            F.matSolve(E, X)
            E.destroy()
            return X
        F.setMumpsIcntl(27, min(hi - lo, self.RHS_BLOCK))
        host = comm.rank == 0
        Et = PETSc.Mat().createAIJ(((hi - lo if host else 0, hi - lo), (n if host else 0, n)),
                                   nnz=(1, 1), comm=comm)  # type: ignore[arg-type]
        Et.setUp()
        if host:
            for k, row in enumerate(self.interface[lo:hi]):
                Et.setValue(k, int(row), 1.0)
        Et.assemble()
        E = PETSc.Mat().createTranspose(Et)
        F.matSolve(E, X)
        Et.destroy()
        E.destroy()
        return X

    def _interface_bodies(self) -> np.ndarray:
        """The body of each interface unknown (the same array on every rank)."""
        start, n_local = self.start, self.offsets[-1]
        mine = (self.interface >= start) & (self.interface < start + n_local)
        body = np.zeros(len(self.interface), np.int64)
        body[mine] = np.searchsorted(self.offsets, self.interface[mine] - start,
                                     side="right") - 1
        self.comm.Allreduce(MPI.IN_PLACE, body, op=MPI.SUM)
        return body

    def _interface_solves(self, ksp: PETSc.KSP) -> list[XBlock]:
        """X = A⁻¹ E (one multi-right-hand-side solve), kept by body block.

        The block of a body: its owned rows and a range of columns (aligned to one of
        :data:`ALIGNMENTS`) holding its interface unknowns; the product with the blocks
        then skips only exact zeros. Kept only if (checked on this rank) X is zero
        outside the blocks and the blocks' products give the whole X's, ``X @ f_c``, bit
        for bit (the BLAS's sums grouped as before: the χ = 1e-10 stick tangent
        magnifies the last bit into the Newton counts, 5198 → 5206 on the Goda case with
        the blocks' own sums); else X is one block.
        """
        X = self._solve_columns(ksp, 0, len(self.interface))
        out = np.array(X.getDenseArray(), copy=True)
        X.destroy()
        return x_blocks(out, self.offsets, self._interface_bodies())

    def _gather_rows(self, blocks: list[XBlock]) -> np.ndarray:
        """The interface rows of X (owned rows), gathered on every rank."""
        rows = self.interface - self.start
        out = np.zeros((len(self.interface), len(self.interface)))
        for b in blocks:
            lo, hi = b.rows.start, b.rows.stop
            at = np.flatnonzero((rows >= lo) & (rows < hi))
            out[np.ix_(at, b.cols)] += b.X[rows[at] - lo]  # blocks overlap at zeros
        self.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        return out


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
