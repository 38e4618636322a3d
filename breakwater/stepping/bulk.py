"""The bulk of a GN22 step: M, K and the loads assembled once, the predictor's residual.

The bulk is linear, with constant M, C = αM + βK and K, so for a fixed Δt the matrix
of the step's unknown Δa, ``A = M + β₁Δt C + ½β₂Δt² K``, never changes.
:class:`BulkOperators` assembles M, K and the load vectors (at unit amplitude) once and
forms the predictor's residual from matrix-vector products (A is factorised per Δt by
:mod:`breakwater.stepping.factorisations`). :func:`interface_dofs` gives the
contact-surface unknowns. The stacked vectors' index bookkeeping is
:class:`~breakwater.model.layout.MonolithicLayout`; the wall time of each part,
:class:`~breakwater.common.timings.Timings`.
"""

from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem, la
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from breakwater.common.jit import kernel
from breakwater.common.timings import Timings
from breakwater.contact.surfaces import surface_dofs
from breakwater.model.layout import MonolithicLayout
from breakwater.model.mesh import group_tag
from breakwater.model.model import ContactModel
from breakwater.model.parts import StageWatch
from breakwater.stepping.stateproducts import (
    StateProducts,
    is_start,
    predictor_from,
    start_residual_from,
)

__all__ = ["BulkOperators", "body_index", "interface_dofs"]


def body_index(model: ContactModel, space: object) -> int:
    """The body whose function space is (or contains) the C++ space ``space``."""
    return next(i for i, b in enumerate(model.bodies)
                if b.V._cpp_object.contains(space))


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
        #: M and K times the state, one pass per state (:mod:`.stateproducts`).
        self.products = StateProducts(self.M, self.K, model.comm)
        self.offset: PETSc.Vec | None = None
        """A constant force added to F (None: none): the relaxation's contact forces at
        the start of a pseudo step (:mod:`breakwater.statics.pseudostep`)."""

    def _load_vectors(self) -> list[tuple[fem.Constant | None, PETSc.Vec]]:
        """Gravity and each surface load at unit amplitude: f(t) = Σ amplitude_k(t) f_k.

        A load whose field changes at given times (``LoadData.version``) keeps its
        compiled form, assembled again by :meth:`refresh` when its stage changes.
        """
        m = self.model
        w = m.w
        loads = []
        gravity = sum(_body_force(b, m.gravity, w[i]) for i, b in enumerate(m.bodies))
        loads.append((None, self._vector(self._compile(gravity))))
        self._staged: dict[int, list[tuple[fem.Form, int]]] = {}
        for k, ld in enumerate(m.loads):
            compiled = self._compile(ufl.dot(ld.unit, w[ld.body]) * ld.ds)
            loads.append((ld.amplitude, self._vector(compiled)))
            if ld.parameters is not None:
                self._staged[k] = compiled
        self._watch = StageWatch(m.loads)
        return loads

    def _compile(self, form: ufl.Form) -> list[tuple[fem.Form, int]]:
        """A linear form's blocks compiled, each with the body it belongs to."""
        out = []
        for block in ufl.extract_blocks(form):
            if block is None:
                continue
            compiled = self.model.form(block)
            out.append((compiled, body_index(self.model, compiled.function_spaces[0])))
        return out

    def _vector(self, compiled: list[tuple[fem.Form, int]],
                out: PETSc.Vec | None = None) -> PETSc.Vec:
        """Compiled blocks assembled into a stacked vector (bodies they miss: 0)."""
        if out is None:
            out = self.layout.vec.duplicate()
        out.zeroEntries()
        for form, body in compiled:
            vec = fem.assemble_vector(form)
            vec.scatter_reverse(la.InsertMode.add)
            lo, hi = self.layout.offsets[body], self.layout.offsets[body + 1]
            out.array[lo:hi] = vec.array[: hi - lo]
        return out

    def refresh(self) -> bool:
        """Assemble again the vectors of the loads whose field changed (collective).

        Every rank sets the loads' stages from the same time, so every rank takes the
        same branch.

        Returns:
            Whether a vector changed.
        """
        changed = self._watch.changed()
        for k in changed:
            self._vector(self._staged[k], self._loads[k + 1][1])
        return bool(changed)

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
        amplitude Constants (the energy ledger's external work); a staged load's at its
        current stage (:meth:`refresh`).
        """
        self.refresh()
        return self._loads

    def load(self, out: PETSc.Vec) -> None:
        """F at the loads' current amplitudes and stages (the model's ``set_time``)."""
        self.refresh()
        out.zeroEntries()
        for amplitude, vec in self._loads:
            out.axpy(1.0 if amplitude is None else float(amplitude.value), vec)
        if self.offset is not None:
            out.axpy(1.0, self.offset)

    def predictor_residual(self, u: PETSc.Vec, v: PETSc.Vec, a: PETSc.Vec, dt: float,
                           out: PETSc.Vec) -> None:
        """r₀ = f(t₁) − M a₀ − C ṽ − K ũ, zero on Dirichlet rows.

        With C = αM + βK this is f − M (a₀ + α ṽ) − K (ũ + β ṽ): from the state's
        products (:attr:`products`, one pass per state), else two products.
        """
        with self.timings("bulk_products"):
            self._predictor_residual(u, v, a, dt, out)

    def _predictor_residual(self, u: PETSc.Vec, v: PETSc.Vec, a: PETSc.Vec, dt: float,
                            out: PETSc.Vec) -> None:
        α, β = self.model.damping.alpha, self.model.damping.beta
        if self.products.on:  # from the state's products (one pass per state)
            self.load(out)
            f = out.array
            predictor_from(self.products.of(u.array, v.array, a.array), dt, α, β, f, f)
            f[self.bc_rows] = 0.0
            return
        ma, ku, tmp = self._work
        predictor_vectors(u.array, v.array, a.array, dt, α, β, ma.array, ku.array)
        self.load(out)
        self.M.mult(ma, tmp)
        out.axpy(-1.0, tmp)
        self.K.mult(ku, tmp)
        out.axpy(-1.0, tmp)
        out.array[self.bc_rows] = 0.0

    def start_residual(self, u: PETSc.Vec, v: PETSc.Vec, a: PETSc.Vec, da: PETSc.Vec,
                       r0: PETSc.Vec, dt: float, beta1: float, beta2: float, A: PETSc.Mat,
                       out: PETSc.Vec) -> None:
        """``out = A Δa − r₀``, the bulk rows' residual at Newton's start.

        At GN22's start ``Δa = −a/β₁`` from the state's products: A Δa is
        ``−(c_M Ma + c_K Ka)/β₁`` (:func:`~breakwater.stepping.stateproducts.start_residual_from`;
        A = c_M M + c_K K as :class:`~breakwater.stepping.factorisations.Factorisations`
        forms it), with the Dirichlet rows A's identity's: Δa − r₀ there. The product with
        A where the products are off, the staged Δa is another, or a fixed DOF
        accelerates (A's zeroed columns).
        """
        rows, products = self.bc_rows, self.products
        d, x, r, w = da.array, a.array, r0.array, out.array
        if not (products.on and products.all(is_start(d, x, beta1) and not x[rows].any())):
            A.mult(da, out)
            out.axpy(-1.0, r0)
            return
        α, β = self.model.damping.alpha, self.model.damping.beta
        start_residual_from(products.of(u.array, v.array, x), 1.0 + beta1 * dt * α,
                            0.5 * beta2 * dt**2 + beta1 * dt * β, beta1, r, w)
        w[rows] = d[rows] - r[rows]

    def destroy(self) -> None:
        """Free the PETSc objects."""
        for obj in (self.M, self.K, *self._work, *(v for _, v in self._loads)):
            if obj is not None:
                obj.destroy()
        self.products.destroy()


@kernel
def predictor_vectors(u, v, a, dt, α, β, ma, ku):  # type: ignore[no-untyped-def]
    """The predictor's products' vectors: ``ma = a + α ṽ``, ``ku = ũ + β ṽ`` (compiled).

    ṽ = v + Δt a and ũ = u + Δt v + ½Δt² a, each sum in NumPy's order of the
    expressions it replaces (the same numbers to the bit; no temporaries).
    """
    c = 0.5 * dt**2
    for i in range(len(u)):
        ṽ = v[i] + dt * a[i]
        ma[i] = a[i] + α * ṽ
        ku[i] = u[i] + dt * v[i] + c * a[i] + β * ṽ


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
