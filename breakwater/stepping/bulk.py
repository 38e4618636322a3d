"""The bulk of a GN22 step: M, K and the loads assembled once, A factorised per Δt.

The bulk is linear, with constant M, C = αM + βK and K, so for a fixed Δt the matrix
of the step's unknown Δa, ``A = M + β₁Δt C + ½β₂Δt² K``, never changes.
:class:`BulkOperators` assembles M, K and the load vectors (at unit amplitude) once,
forms the predictor's residual from matrix-vector products, and factorises A (MUMPS)
once per distinct Δt, with ``X = A⁻¹ E`` (one solve per contact-surface unknown) and
the interface Schur complement ``S = (X_II)⁻¹`` (cached: cut-backs come back to the same
Δt). :class:`~breakwater.model.layout.MonolithicLayout` is the index bookkeeping of the
stacked vectors; :class:`~breakwater.common.timings.Timings` the wall time of each part,
for the benchmark.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem, la
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from breakwater.common.timings import Timings
from breakwater.contact.surfaces import surface_dofs
from breakwater.model.layout import MonolithicLayout
from breakwater.model.mesh import group_tag
from breakwater.model.model import ContactModel

__all__ = ["BulkOperators", "body_index", "interface_dofs"]


def body_index(model: ContactModel, space: object) -> int:
    """The body whose function space is (or contains) the C++ space ``space``."""
    return next(i for i, b in enumerate(model.bodies)
                if b.V._cpp_object.contains(space))


@dataclass
class _Factorisation:
    """Everything that depends on Δt only."""

    ksp: PETSc.KSP
    A: PETSc.Mat
    X: np.ndarray  # owned rows of A⁻¹ E, shape (n_owned, n_I)
    X_II: np.ndarray  # its interface rows, shape (n_I, n_I), the same on every rank
    S: np.ndarray  # (X_II)⁻¹, the interface Schur complement of A


class BulkOperators:
    """M, K (and C) assembled once, the load vectors at unit amplitude, A factorised per Δt.

    Args:
        model: The contact model.
        layout: Its stacked-vector layout.
        interface: Global stacked indices of the contact-surface DOFs (sorted).
        beta1: GN22 β₁.
        beta2: GN22 β₂.
        cache: Factorisations kept (distinct Δt).
    """

    def __init__(self, model: ContactModel, layout: MonolithicLayout, interface: np.ndarray,
                 beta1: float, beta2: float, cache: int = 4,
                 timings: Timings | None = None, interface_solves: bool = True) -> None:
        self.model, self.layout = model, layout
        self.timings = timings or Timings()
        self._interface_solves_on = interface_solves
        self.interface = interface
        self.beta1, self.beta2 = beta1, beta2
        trial = ufl.TrialFunctions(model.W)

        def matrix(form: ufl.Form) -> PETSc.Mat:
            mat = fem_petsc.assemble_matrix(model.form(ufl.extract_blocks(form)), kind="mpi")
            mat.assemble()
            return mat

        self.M = matrix(model.mass(trial))
        self.K = matrix(model.stiffness(trial))
        self._loads = self._load_vectors()
        # Dirichlet rows of the stacked vector (owned positions).
        self.bc_rows = self._bc_rows()
        self._cache: OrderedDict[float, _Factorisation] = OrderedDict()
        self._cache_size = cache
        self._work = [self.M.createVecLeft() for _ in range(3)]
        self.factorisations = 0

    def _load_vectors(self) -> list[tuple[fem.Constant | None, PETSc.Vec]]:
        """Gravity and each surface load at unit amplitude: f(t) = Σ amplitude_k(t) f_k."""
        m = self.model
        w = m.w
        loads = []
        gravity = sum(_body_force(b, m.gravity, w[i]) for i, b in enumerate(m.bodies))
        loads.append((None, self._vector(gravity)))
        for ld in m.loads:
            unit = ufl.dot(ld.unit, w[ld.body]) * ld.ds
            loads.append((ld.amplitude, self._vector(unit)))
        return loads

    def _vector(self, form: ufl.Form) -> PETSc.Vec:
        """A linear form assembled into a stacked vector (bodies it does not touch: 0)."""
        out = self.layout.vec.duplicate()
        out.zeroEntries()
        for block in ufl.extract_blocks(form):
            if block is None:
                continue
            compiled = self.model.form(block)
            body = body_index(self.model, compiled.function_spaces[0])
            vec = fem.assemble_vector(compiled)
            vec.scatter_reverse(la.InsertMode.add)
            lo, hi = self.layout.offsets[body], self.layout.offsets[body + 1]
            out.array[lo:hi] = vec.array[: hi - lo]
        return out

    def _bc_rows(self) -> np.ndarray:
        rows = []
        for bc in self.model.bcs:
            body = body_index(self.model, bc.function_space)
            dofs, ghost_start = bc.dof_indices()
            dofs = dofs[:ghost_start]
            rows.append(self.layout.owned_local(body, dofs))
        return np.unique(np.concatenate(rows)) if rows else np.zeros(0, np.int64)

    @property
    def load_vectors(self) -> list[tuple[fem.Constant | None, PETSc.Vec]]:
        """Gravity's load vector (amplitude None: 1), then each load's at unit amplitude.

        F(t) = Σ amplitude_k(t) f_k, the loads in the model's order with their
        amplitude Constants (the energy ledger's external work).
        """
        return self._loads

    def load(self, out: PETSc.Vec) -> None:
        """F at the loads' current amplitudes (the model's ``set_time``)."""
        out.zeroEntries()
        for amplitude, vec in self._loads:
            out.axpy(1.0 if amplitude is None else float(amplitude.value), vec)

    def predictor_residual(self, u: PETSc.Vec, v: PETSc.Vec, a: PETSc.Vec, dt: float,
                           out: PETSc.Vec) -> None:
        """r₀ = f(t₁) − M a₀ − C ṽ − K ũ, zero on Dirichlet rows.

        With C = αM + βK this is f − M (a₀ + α ṽ) − K (ũ + β ṽ): two products.
        """
        with self.timings("bulk_products"):
            self._predictor_residual(u, v, a, dt, out)

    def _predictor_residual(self, u: PETSc.Vec, v: PETSc.Vec, a: PETSc.Vec, dt: float,
                            out: PETSc.Vec) -> None:
        ma, ku, tmp = self._work
        α, β = self.model.damping.alpha, self.model.damping.beta
        ṽ = v.array + dt * a.array
        ma.array[:] = a.array + α * ṽ
        ku.array[:] = u.array + dt * v.array + 0.5 * dt**2 * a.array + β * ṽ
        self.load(out)
        self.M.mult(ma, tmp)
        out.axpy(-1.0, tmp)
        self.K.mult(ku, tmp)
        out.axpy(-1.0, tmp)
        out.array[self.bc_rows] = 0.0

    def factorisation(self, dt: float) -> _Factorisation:
        """A = M + β₁Δt C + ½β₂Δt² K factorised, X and S (cached by Δt)."""
        if dt in self._cache:
            self._cache.move_to_end(dt)
            return self._cache[dt]
        with self.timings("factorisation"):
            return self._factorise(dt)

    def _factorise(self, dt: float) -> _Factorisation:
        A = self.M.duplicate(copy=True)
        d = self.model.damping
        A.scale(1.0 + self.beta1 * dt * d.alpha)
        A.axpy(0.5 * self.beta2 * dt**2 + self.beta1 * dt * d.beta, self.K)
        A.zeroRowsColumns((self.layout.start + self.bc_rows).astype(PETSc.IntType), diag=1.0)
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
        fact = _Factorisation(ksp, A, X, X_II, S)
        self.factorisations += 1
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

    def solve(self, fact: _Factorisation, rhs: PETSc.Vec, out: PETSc.Vec) -> None:
        """Out = A⁻¹ rhs."""
        with self.timings("back_solves"):
            fact.ksp.solve(rhs, out)

    def destroy(self) -> None:
        """Free the PETSc objects."""
        for f in self._cache.values():
            f.ksp.destroy()
            f.A.destroy()
        self._cache.clear()
        for obj in (self.M, self.K, *self._work, *(v for _, v in self._loads)):
            if obj is not None:
                obj.destroy()


def _body_force(body, gravity, w):  # type: ignore[no-untyped-def]
    return body.ρ * ufl.dot(gravity, w) * body.dx


def interface_dofs(model: ContactModel, layout: MonolithicLayout) -> np.ndarray:
    """Global stacked indices of the DOFs on every contact facet, both sides, sorted.

    Dirichlet DOFs are left out (their increment is zero).
    """
    fdim = model.mesh.topology.dim - 1
    local = []
    for p in model.pairs:
        tag = group_tag(model.mesh_data, p.spec.interface, fdim)
        for i in (p.slave, p.master):
            body = model.bodies[i]
            blocks = fem.locate_dofs_topological(body.V, fdim, body.facet_tags.find(tag))
            bs = body.V.dofmap.index_map_bs
            dofs = (blocks[:, None] * bs + np.arange(bs)).ravel()
            local.append(layout.global_index[i][dofs])
    bc = []
    for condition in model.bcs:
        dofs, _ = condition.dof_indices()
        bc.append(layout.global_index[body_index(model, condition.function_space)][dofs])
    local.append(surface_dofs(model, layout))
    mine = np.unique(np.concatenate(local))
    every = np.unique(np.concatenate(model.comm.allgather(mine)))
    fixed = np.unique(np.concatenate(model.comm.allgather(
        np.concatenate(bc) if bc else np.zeros(0, np.int64))))
    return np.setdiff1d(every, fixed)
