"""A = M + β₁Δt C + ½β₂Δt² K factorised per Δt, with the bulk's elimination X and S.

For a fixed Δt the matrix of a GN22 step's unknown Δa never changes (the bulk is
linear: :mod:`breakwater.stepping.bulk`). :class:`Factorisations` assembles A from M and
K, factorises it (:func:`lu_package`: PETSc's own LU on one rank in 2D, else MUMPS)
once per distinct Δt, with ``X = A⁻¹ E`` (a column per
contact-surface unknown: :mod:`breakwater.stepping.elimination`, kept whole or only its
interface rows X_II, as memory allows) and the interface Schur complement
``S = (X_II)⁻¹``, and keeps the last few (cut-backs come back to the same Δt); the
back-solves ``A⁻¹ r`` of the steps use them.

Memory (:mod:`breakwater.common.memory`): a factorisation for a new Δt first frees the
oldest kept ones while it would not fit in the node's available memory, and a
factorisation that could not be completed is refused in one line
(:func:`check_factorisation`) instead of giving the steps infinite or wrong solutions.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from breakwater.common.errors import BreakwaterError
from breakwater.common.memory import fits
from breakwater.common.timings import Timings
from breakwater.stepping.bulk import BulkOperators
from breakwater.stepping.elimination import Elimination, XBlock

__all__ = ["Factorisation", "Factorisations", "check_factorisation", "factor_entries",
           "lu_package", "lu_solver"]


def lu_package(comm: MPI.Comm, tdim: int) -> str:
    """The LU package of the step matrix A: ``"petsc"`` on one rank in 2D, else ``"mumps"``.

    Measured (2026-11-26, one rank, one BLAS thread, the same A, CPU time;
    ``benchmarks/lu_package.py``, record ``benchmarks/records/2026-11-26-lu-package.md``):
    PETSc's own LU (nested dissection ordering, no pivoting: A is symmetric positive
    definite) back-solves 1.8 to 3.1× faster than MUMPS on the 2D Goda meshes, from the
    prototype storm's 1514 unknowns (26 against 79 µs) to refinement 9 (23 against
    51 ms), and factorises in about the same CPU time (2.1 against 2.3 s at refinement 9;
    MUMPS's takes 1.3 s of wall time on two threads there). In 3D its factorisation
    took 3.6× MUMPS's CPU time (3.9 against 1.1 s on ``goda3d``) for the same back-solve
    (16.7 against 17.2 ms); under MPI only MUMPS factorises in parallel.
    """
    return "petsc" if comm.size == 1 and tdim == 2 else "mumps"


def lu_solver(A: PETSc.Mat, package: str, prefix: str | None = None) -> PETSc.KSP:
    """A direct solver of A by ``package`` (:func:`lu_package`'s), factorised.

    PETSc's own LU with nested-dissection ordering; MUMPS with its defaults.

    Args:
        A: The matrix.
        package: ``"petsc"`` or ``"mumps"``.
        prefix: The PETSc options prefix whose options are read before factorising
            (None: none read).
    """
    ksp = PETSc.KSP().create(A.getComm())
    if prefix is not None:
        ksp.setOptionsPrefix(prefix)
    ksp.setOperators(A)
    ksp.setType("preonly")
    pc = ksp.getPC()
    pc.setType("lu")
    pc.setFactorSolverType(package)
    if package == "petsc":
        pc.setFactorOrdering("nd")
    if prefix is not None:
        ksp.setFromOptions()
    ksp.setUp()
    return ksp


def factor_entries(ksp: PETSc.KSP) -> float:
    """The entries of A's LU factors (MUMPS: INFOG(29), all ranks'; PETSc: its own).

    Both back-solves read each entry once: their cost is proportional to it.
    """
    pc = ksp.getPC()
    F = pc.getFactorMatrix()
    if pc.getFactorSolverType() == "mumps":
        info = F.getMumpsInfog(29)
        return float(info) if info >= 0 else -1e6 * info  # < 0: millions
    return float(F.getInfo()["nz_used"])


def _factor_bytes(ksp: PETSc.KSP) -> float:
    """The memory of A's factors on this rank, in bytes.

    MUMPS: its INFO(16) (MB). PETSc's LU: a value and a column index per allocated
    entry (its ``memory`` is 0 without PETSc's logging).
    """
    pc = ksp.getPC()
    F = pc.getFactorMatrix()
    if pc.getFactorSolverType() == "mumps":
        return max(F.getMumpsInfo(16), 0) * 2.0**20
    return F.getInfo()["nz_allocated"] * (8.0 + np.dtype(PETSc.IntType).itemsize)


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
    chunks: int = 0  # X's columns solved in this many chunks (0: whole, X may be kept)
    bytes: float = 0.0  # this rank's memory for it: A's factors, X's blocks, X_II and S

    # X's columns of a set of interface unknowns by block (subtract_X's ``support``).
    _columns: tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray]]] | None = field(
        default=None, init=False, repr=False, compare=False)

    def subtract_X(self, fc: np.ndarray, out: np.ndarray,
                   support: np.ndarray | None = None) -> None:
        """``out −= X f_c`` on the owned rows (``out``: the owned part of a stacked vector).

        Block by block: the rows of each body only meet its own interface unknowns.
        ``support``: the interface unknowns outside which f_c is zero (a Newton on the
        unknowns a general pair's contact may reach, :mod:`breakwater.stepping.reach`):
        the product over their columns alone, kept while the set stays.
        """
        assert self.X_blocks is not None, "X is not kept: solve A Δ = E f_c instead"
        if support is None:
            for b in self.X_blocks:
                out[b.rows] -= b.X @ fc[b.cols]
            return
        kept = self._columns
        if kept is None or not np.array_equal(kept[0], support):
            parts = []
            for b in self.X_blocks:
                sel = np.flatnonzero(np.isin(b.cols, support))
                parts.append((b.cols[sel], np.asfortranarray(b.X[:, sel])))
            self._columns = kept = (support.copy(), parts)
        for b, (cols, X) in zip(self.X_blocks, kept[1], strict=True):
            if len(cols):
                out[b.rows] -= X @ fc[cols]


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
            estimated cost (:meth:`keep_X`). Either way X is built whole only where it
            fits (:attr:`Elimination.X_MEMORY
            <breakwater.stepping.elimination.Elimination.X_MEMORY>`).
        available: The node's available memory (bytes) that the X's and
            :attr:`CACHE_MEMORY` are fractions of; None: measured before each
            factorisation (:func:`~breakwater.common.memory.available_bytes`).
    """

    #: The share of the node's available memory a new factorisation (as large as the
    #: last) may take before the oldest kept ones are freed to make room.
    CACHE_MEMORY = 0.8

    #: Time per entry of A's factors in a back-solve over the time per entry of X's
    #: body blocks in the product ``X f_c``; both are memory-bound. Measured on the
    #: Goda case (1 rank, one BLAS thread, the same factorisation, CPU time, 2026-11-25):
    #: 3.1 at refinement 3 (3.0 ms for 3.0e6 factor entries against 0.69 ms for
    #: 2.15e6), 2.95 at refinement 9 (57 ms for 3.48e7 against 28.5 ms for 5.13e7;
    #: benchmarks/records/2026-11-25-xblocks.md); with PETSc's LU (:func:`lu_package`,
    #: another machine, 2026-11-26): 3.8 at refinement 3 (1.50 ms for 2.58e6 against
    #: 0.33 ms for 2.15e6), 2.5 at 6 and 2.6 at 9 (23.2 ms for 3.09e7 against 14.8 ms for
    #: 5.13e7; benchmarks/records/2026-11-26-lu-package.md). The smallest, rounded down.
    SOLVE_PER_PRODUCT = 2.5

    def __init__(self, bulk: BulkOperators, interface: np.ndarray, beta1: float,
                 beta2: float, cache: int = 4, timings: Timings | None = None,
                 interface_solves: bool = True, keep_X: bool | None = None,
                 available: float | None = None) -> None:
        self.bulk = bulk
        self.model, self.layout = bulk.model, bulk.layout
        self.timings = timings or Timings()
        self._interface_solves_on = interface_solves
        self._keep_X = keep_X
        self.available = available
        self.interface = interface
        self.elimination = Elimination(self.model.comm, self.layout.offsets, self.layout.start,
                                       interface)
        self.beta1, self.beta2 = beta1, beta2
        self.package = lu_package(self.model.comm, self.model.mesh.topology.dim)
        self._cache: OrderedDict[float, Factorisation] = OrderedDict()
        self.cache_size = cache

    def factorisation(self, dt: float) -> Factorisation:
        """A = M + β₁Δt C + ½β₂Δt² K factorised, X and S (cached by Δt)."""
        if dt in self._cache:
            self._cache.move_to_end(dt)
            return self._cache[dt]
        with self.timings("factorisation"):
            self._make_room()
            return self._factorise(dt)

    def _make_room(self) -> None:
        """Free the oldest kept factorisations while one more would not fit (collective).

        A new factorisation takes what the last took (the same pattern of A, the same
        interface): MUMPS's memory and X's blocks.
        """
        while self._cache:
            last = next(reversed(self._cache.values()))
            if fits(self.model.comm, last.bytes, self.CACHE_MEMORY, self.available):
                return
            self._free_oldest()

    def _free_oldest(self) -> None:
        _, old = self._cache.popitem(last=False)
        old.ksp.destroy()
        old.A.destroy()

    def _factorise(self, dt: float) -> Factorisation:
        A = self.bulk.M.duplicate(copy=True)
        d = self.model.damping
        A.scale(1.0 + self.beta1 * dt * d.alpha)
        A.axpy(0.5 * self.beta2 * dt**2 + self.beta1 * dt * d.beta, self.bulk.K)
        A.zeroRowsColumns((self.layout.start + self.bulk.bc_rows).astype(PETSc.IntType), diag=1.0)
        # Its one product per step (the bulk rows' residual at Newton's start, for the
        # relative test; on one rank from the state's products instead, BulkOperators.
        # start_residual) row by row, without PETSc's "inode" grouping of rows: 3.4×
        # faster on these P2 matrices (0.93 against 0.27 ms at refinement 3). M and K keep
        # the grouping: the row sums differ from it in the last bit, and the predictor's
        # products feed the state, whose 2-rank equality (tests/test_mpi.py) the χ = 1e-10
        # stick tangent holds to 5e-11 with it and 3.6e-10 without (2026-11-23).
        A.setOption(PETSc.Mat.Option.USE_INODES, False)  # type: ignore[arg-type]
        ksp = lu_solver(A, self.package, self.model.options_prefix("bulk"))
        check_factorisation(ksp, "the step matrix A = M + β₁Δt C + ½β₂Δt² K")
        blocks: list[XBlock] | None
        chunks = 0
        if self._interface_solves_on and len(self.interface):
            blocks, X_II, chunks = self.elimination.solve(ksp, self.available)
            if blocks is not None and not self.keep_X(ksp, blocks):
                blocks = None
            S = np.linalg.inv(X_II)
        else:
            blocks = []
            X_II = S = np.zeros((len(self.interface), len(self.interface)))
        # (X_II and S too: on a large interface, n_I² each on every rank)
        kept = sum(b.X.nbytes for b in blocks or ()) + X_II.nbytes + S.nbytes
        fact = Factorisation(ksp, A, blocks, X_II, S, chunks, _factor_bytes(ksp) + kept)
        self._cache[dt] = fact
        if len(self._cache) > self.cache_size:
            self._free_oldest()
        return fact

    def keep_X(self, ksp: PETSc.KSP, blocks: list[XBlock]) -> bool:
        """Whether the product with X's blocks is cheaper than a second back-solve.

        Both read their operands once per step: the product ``X f_c`` the entries of
        X's blocks (each rank its own rows: the largest count), the back-solve
        ``A⁻¹(r₀ − E f_c)`` those of A's LU factors (:func:`factor_entries`; MUMPS's, all
        of them: on 2 ranks a back-solve was measured to take as much CPU per rank as
        serially, 3.0–3.8 against 2.9 ms at refinement 3), each
        :attr:`SOLVE_PER_PRODUCT` times slower. In 2D the blocks grow as N^1.5
        (n_I ~ √N), the factors as N log N: the back-solve wins on fine enough meshes.
        The same decision on every rank.
        """
        if self._keep_X is not None:
            return self._keep_X
        comm = self.model.comm
        factors = comm.allreduce(factor_entries(ksp), op=MPI.MAX)
        entries = comm.allreduce(sum(b.X.size for b in blocks), op=MPI.MAX)
        return bool(entries <= self.SOLVE_PER_PRODUCT * factors)

    def describe(self) -> dict[str, object]:
        """How the last factorisation eliminates the bulk, for the summary (``solver.elimination``).

        ``X``: ``"kept"`` (the step's Δa = z − X f_c), ``"second back-solve"`` (cheaper
        than the product with X) or ``"interface rows only"`` (X did not fit in memory:
        solved in ``chunks``, a second back-solve per step); ``memory_gb``: this rank's
        LU factors and kept X (not collective: rank 0's in the summary). The same for
        a resumed run as for the uninterrupted one (not the cache's size, which a
        resumed run has filled with fewer step sizes).
        """
        if not self._cache:
            return {}
        last = next(reversed(self._cache.values()))
        kind = ("kept" if last.X_blocks is not None else
                "interface rows only" if last.chunks else "second back-solve")
        return {"X": kind, "chunks": last.chunks, "memory_gb": last.bytes / 1e9}

    def solve(self, fact: Factorisation, rhs: PETSc.Vec, out: PETSc.Vec) -> None:
        """Out = A⁻¹ rhs."""
        with self.timings("back_solves"):
            fact.ksp.solve(rhs, out)

    def destroy(self) -> None:
        """Free the PETSc objects of the factorisations kept."""
        while self._cache:
            self._free_oldest()


def check_factorisation(ksp: PETSc.KSP, what: str) -> None:
    """Refuse, in one line, a factorisation that could not be completed (collective).

    A failed factorisation does not raise: its back-solves return infinities (a MUMPS
    error, e.g. INFOG(1) = -13 when an allocation fails, or a zero pivot of PETSc's
    LU, leaves the factors unusable); inside a SNES it raises PETSc's error 76 with
    PETSc's traceback (:meth:`~breakwater.stepping.solver.NewtonSolver.solve` asks this
    function why).

    Raises:
        BreakwaterError: The package's error code and what it means, on every rank.

    """
    pc = ksp.getPC()
    failed = int(pc.getFailedReason())  # type: ignore[call-overload]  # an int at run time
    # (Inside a SNES the PC's reason is reset by the time the error is raised: MUMPS's
    # own status, INFOG(1) < 0, is the one kept.)
    mumps = pc.getFactorSolverType() == "mumps"
    info = pc.getFactorMatrix().getMumpsInfog(1) if mumps else 0
    comm = ksp.getComm().tompi4py()
    failed, info = comm.allreduce(failed, op=MPI.MAX), comm.allreduce(info, op=MPI.MIN)
    if not failed and info >= 0:
        return
    if not mumps:
        reasons = {1: "a structurally zero pivot", 2: "a zero pivot",
                   3: "it ran out of memory"}
        raise BreakwaterError(f"the factorisation of {what} failed (PETSc's LU, reason "
                              f"{failed}: {reasons.get(failed, 'see PCFailedReason')})")
    causes = {-8: "its workspace was too small", -9: "its workspace was too small",
              -13: "a memory allocation failed", -19: "it needs more memory than allowed",
              -10: "the matrix is singular"}
    cause = causes.get(info, "see MUMPS's user guide for INFOG(1)")
    raise BreakwaterError(f"the factorisation of {what} failed (MUMPS INFOG(1) = {info}: "
                          f"{cause}): the model is too large for the memory of this machine "
                          "or its ranks; use a coarser mesh or more nodes"
                          if info in (-8, -9, -13, -19) else
                          f"the factorisation of {what} failed (PETSc reason {failed}, MUMPS "
                          f"INFOG(1) = {info}: {cause})")
