"""M and K times the state, in one compiled pass per accepted step, for every user of them.

A step of the fast solver reads the bulk matrices several times: the predictor's
residual ``r₀ = f − M (a₀ + α ṽ) − K (ũ + β ṽ)`` (two products), the residual of
Newton's start ``A Δa − r₀`` (one product with A) and the energy ledger's bulk terms
(the kinetic and strain energies, the Rayleigh power and the numerical dissipation:
:mod:`breakwater.energy.bulkenergy`). All are linear in the state (u, v, a): with the
five products ``P = [M v, M a, K u, K v, K a]`` of the accepted state, the next step's
predictor is ``M (a + α ṽ) = Ma + α (Mv + Δt Ma)`` and ``K (ũ + β ṽ) = Ku + Δt Kv +
½Δt² Ka + β (Kv + Δt Ka)`` for any Δt (a rejected step's retries too), Newton's start
``Δa = −a/β₁`` has ``A Δa = −(c_M Ma + c_K Ka)/β₁``, and the ledger's terms at the end of
the step are dot products with P and the previous state's P. One pass over M's and K's
CSR arrays (one sparsity pattern) forms P; on a large mesh, where each pass reads the
matrices from memory, it replaces four (refinement 3 of the Goda case: 23 422 unknowns,
0.53e6 entries per matrix).

:class:`StateProducts` keeps P with copies of the state it belongs to and forms it again
when asked for another state (compared entry by entry: any change of u, v or a, by a
step, a resume or a static state, is seen). The products are the same numbers whoever
asks first (one kernel, one state): a resumed run's are the uninterrupted run's. On
several ranks each rank forms its own rows from its rows of M and K: their columns
outside its ownership range (the ghosts) read the state there, brought by one scatter
per vector, so that the state's change is judged, and the scatter made, on every rank
at once (:meth:`StateProducts.of` and :meth:`StateProducts.all` are collective). Where M
and K do not share their pattern it is off (:attr:`StateProducts.on`) and the callers use
PETSc's products. (On 2 ranks PETSc's five products took 90.8 s of the 300k-DOF goda3d
run's 25-minute loop: a product each, its own scatter and its own pass over the matrix.)

The combinations round differently from the products of the combined vectors (the
same order of round-off, ``ε Σ_j |K_ij| |x_j|`` per row): results agree with PETSc's
products to round-off, not to the bit.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from breakwater.common.arrays import equal
from breakwater.common.jit import kernel

__all__ = ["StateProducts", "is_start", "predictor_from", "start_residual_from",
           "state_products"]

#: The rows of P, in order.
ROWS = ("Mv", "Ma", "Ku", "Kv", "Ka")


@kernel
def state_products(ptr, col, m_val, k_val, u, v, a, out):  # type: ignore[no-untyped-def]
    """``out = [M v, M a, K u, K v, K a]`` from M's and K's CSR arrays (one pattern).

    Each row's sums in the row's order (as PETSc's row-by-row product sums them).

    Args:
        ptr: Row starts (n + 1,).
        col: Column of each entry.
        m_val: M's entries.
        k_val: K's entries.
        u: Displacements (n,).
        v: Velocities.
        a: Accelerations.
        out: The products, shape (5, n) (overwritten).
    """
    for i in range(ptr.shape[0] - 1):
        mv = ma = ku = kv = ka = 0.0
        for p in range(ptr[i], ptr[i + 1]):
            j = col[p]
            c, d = m_val[p], k_val[p]
            mv += c * v[j]
            ma += c * a[j]
            ku += d * u[j]
            kv += d * v[j]
            ka += d * a[j]
        out[0, i] = mv
        out[1, i] = ma
        out[2, i] = ku
        out[3, i] = kv
        out[4, i] = ka


@kernel
def predictor_from(P, dt, α, β, f, out):  # type: ignore[no-untyped-def]
    """``out = f − M (a + α ṽ) − K (ũ + β ṽ)`` from the state's products P.

    ṽ = v + Δt a, ũ = u + Δt v + ½Δt² a (the predictor of
    :meth:`~breakwater.stepping.bulk.BulkOperators.predictor_residual`).
    """
    c = 0.5 * dt**2
    for i in range(out.shape[0]):
        mv, ma, ku, kv, ka = P[0, i], P[1, i], P[2, i], P[3, i], P[4, i]
        kṽ = kv + dt * ka
        out[i] = f[i] - (ma + α * (mv + dt * ma)) - (ku + dt * kv + c * ka + β * kṽ)


@kernel
def start_residual_from(P, c_m, c_k, β1, r0, out):  # type: ignore[no-untyped-def]
    """``out = A Δa − r₀`` at Newton's start ``Δa = −a/β₁``, A = c_M M + c_K K.

    From the state's products (Ma, Ka); the Dirichlet rows are the caller's.
    """
    for i in range(out.shape[0]):
        out[i] = -(c_m * P[1, i] + c_k * P[4, i]) / β1 - r0[i]


@kernel
def is_start(da, a, β1):  # type: ignore[no-untyped-def]
    """Whether ``da`` is Newton's start ``−a/β₁`` (GN22.stage's), entry by entry."""
    for i in range(len(da)):
        if da[i] != -a[i] / β1:
            return False
    return True


class StateProducts:
    """The products P = [M v, M a, K u, K v, K a] of a state, kept while it stays.

    Args:
        M: The mass matrix (assembled, no Dirichlet conditions).
        K: The stiffness matrix (the same pattern).
        comm: The model's communicator.
    """

    def __init__(self, M: PETSc.Mat, K: PETSc.Mat, comm: MPI.Comm) -> None:
        self.comm = comm
        self._csr: list[np.ndarray] = []
        (mp, mc, mv), (kp, kc, kv) = (A.getValuesCSR() for A in (M, K))
        same = np.array_equal(mp, kp) and np.array_equal(mc, kc)
        n = M.getLocalSize()[0]
        self._ghosts = np.zeros(0, np.int64)
        self._scatter: tuple[PETSc.Scatter, PETSc.Vec, PETSc.Vec] | None = None
        if comm.allreduce(same, op=MPI.LAND):
            lo, hi = M.getOwnershipRange()
            col = np.asarray(mc, dtype=np.int64)
            outside = (col < lo) | (col >= hi)
            self._ghosts = ghosts = np.unique(col[outside])
            # Columns numbered in the extended state [owned | ghosts].
            local = np.where(outside, n + np.searchsorted(ghosts, col), col - lo)
            self._csr = [np.array(mp, dtype=np.int64), local.astype(np.int32),
                         np.array(mv, dtype=np.float64), np.array(kv, dtype=np.float64)]
            if comm.size > 1:
                whole = M.createVecRight()
                part = PETSc.Vec().createSeq(len(ghosts), comm=PETSc.COMM_SELF)
                where = PETSc.IS().createGeneral(
                    ghosts.astype(PETSc.IntType),  # type: ignore[arg-type]  # an array
                    comm=PETSc.COMM_SELF)
                into = PETSc.IS().createStride(len(ghosts), comm=PETSc.COMM_SELF)
                self._scatter = (PETSc.Scatter().create(whole, where, part, into), whole,
                                 part)
                where.destroy()
                into.destroy()
        self._n = n
        self._P = np.zeros((len(ROWS), n))
        self._state = np.full((3, n), np.nan)  # the state P belongs to (none yet)
        self._x = np.zeros((3, n + len(self._ghosts)))  # the extended state
        self.passes = 0  # the passes made (for tests)
        if self._csr:  # compiled (or loaded from numba's cache) now, not in the time loop
            ptr, col, m_val, k_val = self._csr
            state_products(ptr, col, m_val, k_val, self._x[0], self._x[1], self._x[2],
                           self._P)

    @property
    def csr(self) -> list[np.ndarray]:
        """M's and K's rows on this rank: row starts, columns, M's and K's entries (empty: off).

        The columns number the extended state (:meth:`with_ghosts`).
        """
        return self._csr

    @property
    def on(self) -> bool:
        """Whether the products are formed here (M and K share their sparsity pattern)."""
        return bool(self._csr)

    def all(self, flag: bool) -> bool:
        """Whether ``flag`` holds on every rank (collective on several ranks).

        The callers' choice between these products and PETSc's, made alike on every rank.
        """
        return bool(flag) if self.comm.size == 1 else bool(
            self.comm.allreduce(bool(flag), op=MPI.LAND))

    def with_ghosts(self, x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """The owned entries ``x`` followed by the ghosts' (the columns of :attr:`csr`).

        Collective on several ranks (a scatter).
        """
        n = self._n
        if out is None:
            out = np.empty(n + len(self._ghosts))
        out[:n] = x
        if self._scatter is not None:
            scatter, whole, part = self._scatter
            whole.array[:] = x
            scatter.scatter(whole, part, addv=PETSc.InsertMode.INSERT,
                            mode=PETSc.ScatterMode.FORWARD)
            out[n:] = part.array
        return out

    def of(self, u: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """P of the state (u, v, a) (owned entries), shape (5, n); read-only, kept.

        Collective on several ranks: formed again on every rank where any rank's state
        changed.

        Raises:
            RuntimeError: The products are off (:attr:`on`).
        """
        if not self._csr:
            raise RuntimeError("the state's products are off (M and K differ in pattern)")
        s = self._state
        same = equal(s[0], u) and equal(s[1], v) and equal(s[2], a)
        if not self.all(same):
            ptr, col, m_val, k_val = self._csr
            x: Sequence[np.ndarray] = (u, v, a)  # no ghosts (one rank): the state itself
            if self._scatter is not None:
                x = [self.with_ghosts(y, row) for y, row in zip(x, self._x, strict=True)]
            self._P.setflags(write=True)
            state_products(ptr, col, m_val, k_val, x[0], x[1], x[2], self._P)
            self._P.setflags(write=False)
            s[0], s[1], s[2] = u, v, a
            self.passes += 1
        return self._P

    def destroy(self) -> None:
        """Free the scatter's PETSc objects."""
        if self._scatter is not None:
            for obj in self._scatter:
                obj.destroy()
            self._scatter = None
