"""The bulk of a GN22 step: M, K and the loads assembled once, the predictor's residual.

The bulk is linear, with constant M, C = αM + βK and K, so for a fixed Δt the matrix
of the step's unknown Δa, ``A = M + β₁Δt C + ½β₂Δt² K``, never changes.
:class:`BulkOperators` assembles M, K and the load vectors (at unit amplitude) once and
forms the predictor's residual from matrix-vector products (A is factorised per Δt by
:mod:`breakwater.stepping.factorisations`). :func:`interface_dofs` gives the
contact-surface unknowns. :class:`MonolithicLayout` is the index bookkeeping of the
stacked vectors; :class:`Timings` the wall time of each part, for the benchmark.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator, Sequence

import numpy as np
import ufl
from dolfinx import fem, la
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from breakwater.contact.surfaces import surface_dofs
from breakwater.model.mesh import group_tag
from breakwater.model.model import ContactModel

__all__ = ["BulkOperators", "MonolithicLayout", "Timings", "body_index", "interface_dofs"]


def body_index(model: ContactModel, space: object) -> int:
    """The body whose function space is (or contains) the C++ space ``space``."""
    return next(i for i, b in enumerate(model.bodies)
                if b.V._cpp_object.contains(space))


class MonolithicLayout:
    """Index bookkeeping of the stacked ("mpi" kind) vector of one Function per body.

    On each rank a stacked vector holds ``[body 0 owned, body 1 owned, ...]`` followed by
    the ghosts; its global index is the rank's ownership start plus the owned position.

    Args:
        model: The contact model.
    """

    def __init__(self, model: ContactModel) -> None:
        self.model = model
        self.comm = comm = model.comm
        spaces = [b.V for b in model.bodies]
        self.bs = [V.dofmap.index_map_bs for V in spaces]
        self.sizes = [V.dofmap.index_map.size_local * bs for V, bs in zip(spaces, self.bs,
                                                                          strict=True)]
        self.offsets = np.cumsum([0, *self.sizes])
        self.vec = fem_petsc.create_vector(spaces, kind="mpi")
        self.start = self.vec.getOwnershipRange()[0]
        # Per rank: the stacked start, and each body's owned offset and block range start.
        table = comm.allgather((self.start, list(self.offsets[:-1]),
                                [V.dofmap.index_map.local_range[0] for V in spaces]))
        self._starts = np.array([t[0] for t in table], np.int64)
        self._offsets = np.array([t[1] for t in table], np.int64)  # (ranks, bodies)
        self._ranges = np.array([t[2] for t in table], np.int64)
        # Global stacked index of every local entry (owned and ghost) of every body.
        self.global_index = []
        for i, V in enumerate(spaces):
            imap = V.dofmap.index_map
            n = imap.size_local + imap.num_ghosts
            blocks = imap.local_to_global(np.arange(n, dtype=np.int32))
            self.global_index.append(self.stacked(i, blocks))

    def stacked(self, body: int, blocks: np.ndarray) -> np.ndarray:
        """Global stacked indices of all components of global blocks of a body's space.

        Returns:
            Shape ``(len(blocks) * bs,)``: the components of each block in turn.
        """
        blocks = np.asarray(blocks, np.int64)
        bs = self.bs[body]
        starts = self._ranges[:, body]
        owner = np.searchsorted(starts, blocks, side="right") - 1
        base = self._starts[owner] + self._offsets[owner, body] \
            + (blocks - starts[owner]) * bs
        return (base[:, None] + np.arange(bs)).ravel()

    def assign(self, functions: Sequence[fem.Function], vec: PETSc.Vec) -> None:
        """Copy the owned entries of one Function per body into a stacked vector."""
        self.fill(functions, vec.array)

    def fill(self, functions: Sequence[fem.Function], out: np.ndarray) -> np.ndarray:
        """Copy the owned entries of one Function per body into ``out`` (returned).

        ``out``: the owned part of a stacked vector, or any array of that length.
        """
        for f, lo, hi in zip(functions, self.offsets[:-1], self.offsets[1:], strict=True):
            out[lo:hi] = f.x.array[: hi - lo]
        return out

    def owned_local(self, body: int, dofs: np.ndarray) -> np.ndarray:
        """Positions in the stacked vector's owned array of owned body-local DOFs."""
        return self.offsets[body] + dofs


class Timings:
    """Wall time spent in each part of the fast path (s), summed over the run.

    ``factorisation`` (A assembled and factorised, and the interface solves for X),
    ``back_solves`` (z = A⁻¹ r₀), ``bulk_products`` (r₀ and Δa = z − X f_c),
    ``interface_assembly`` (the contact forms), ``newton`` (the rest of the SNES on the
    interface: dense solves, the convergence test, the slip guard), ``contact_search``
    (the general pairs' integration points cut and projected onto the master: a part of
    ``interface_assembly``).
    """

    KEYS = ("factorisation", "back_solves", "bulk_products", "interface_assembly", "newton",
            "contact_search")

    def __init__(self) -> None:
        self.seconds = dict.fromkeys(self.KEYS, 0.0)

    @contextlib.contextmanager
    def __call__(self, key: str) -> Iterator[None]:
        """Time the block under ``key``."""
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[key] += time.perf_counter() - t0


class BulkOperators:
    """M, K (and C) assembled once, the load vectors at unit amplitude, the predictor.

    A = M + β₁Δt C + ½β₂Δt² K is factorised per Δt from M and K by
    :class:`~breakwater.stepping.factorisations.Factorisations`.

    Args:
        model: The contact model.
        layout: Its stacked-vector layout.
        timings: Where the predictor's products are timed (``bulk_products``).
    """

    def __init__(self, model: ContactModel, layout: MonolithicLayout,
                 timings: Timings | None = None) -> None:
        self.model, self.layout = model, layout
        self.timings = timings or Timings()
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
        self._work = [self.M.createVecLeft() for _ in range(3)]

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

    def destroy(self) -> None:
        """Free the PETSc objects."""
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
