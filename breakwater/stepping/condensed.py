"""Fast GN22 steps: the bulk factorised once per Δt, Newton on the contact surfaces only.

The unknown of a GN22 step is the acceleration increment Δa, and the step's residual is

    R(Δa) = A Δa − r₀ + E f_c(Δa_I),      A = M + β₁Δt C + ½β₂Δt² K,

where the bulk is linear (M, C, K constant, so A is constant for a fixed Δt),
``r₀ = f(t₁) − M a₀ − C ṽ − K ũ`` is the residual of the predictor (ũ = u₀ + Δt v₀ +
½Δt² a₀, ṽ = v₀ + Δt a₀) and the contact forces f_c act on the contact-surface DOFs I only
(E injects them into the whole vector). Eliminating the bulk exactly:

    z = A⁻¹ r₀,    X = A⁻¹ E,    S = (X_II)⁻¹  (the interface Schur complement of A),

the step reduces to the n_I interface equations

    F(y) = S (y − z_I) + f_c(y) = 0,        J(y) = S + ∂f_c/∂y,

for y = Δa_I; F is the whole residual with the bulk rows in equilibrium, a force, so the
convergence test keeps its meaning. Once y converges the whole increment is
``Δa = z − X f_c(y)``. Per distinct Δt: one assembly and factorisation of A (MUMPS) and
one multi-right-hand-side solve for X (cached: cut-backs come back to the same Δt). Per
step: a few sparse matrix-vector products for r₀, one back-solve for z and one dense
product with X. Per Newton iteration: the contact forces and their Jacobian on the
interface unknowns and a dense solve of size n_I. The Newton is a PETSc SNES on the
interface unknowns (every rank solves the same small system, so every rank takes the same
decisions), with the convergence test and the slip-reversal pre-check of the reference path.

The contact forces come from providers (:class:`ContactForces`: ``vector()`` and
``matrix()`` on the interface unknowns at the state Functions, summed over the list a
:data:`ContactFactory` builds). Conforming pairs in 2D use
:class:`~breakwater.contact.nodal.NodalContactForces`, the interface forms' nodal
quadrature evaluated on arrays (and ``left_product(X)``, the product X_II ∂f_c/∂y from
its node-by-node structure); :class:`InterfaceAssembler` assembles the UFL of
``forms/`` over the contact facets, for everything else.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from typing import Protocol

import dolfinx
import numpy as np
import ufl
from dolfinx import fem, la
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from breakwater.common.errors import ConvergenceError, PenetrationError
from breakwater.common.parallel import single_threaded_blas
from breakwater.common.timings import Timings
from breakwater.contact.general import SurfaceContact
from breakwater.model.layout import MonolithicLayout
from breakwater.model.model import ContactModel
from breakwater.stepping.bulk import BulkOperators, _Factorisation, interface_dofs
from breakwater.stepping.solver import NewtonOptions, snes_reason

__all__ = ["CondensedNewton", "ContactFactory", "ContactForces", "InterfaceAssembler"]


class ContactForces(Protocol):
    """Contact forces on the interface unknowns, a part of f_c (summed over providers).

    Evaluated at the state Functions (u, v, a at t and the step's Δa, which
    :class:`CondensedNewton` sets before calling); both arrays are the same on every rank.
    """

    def vector(self) -> np.ndarray:
        """f_c on the interface unknowns, shape ``(n_I,)``."""
        ...

    def matrix(self) -> np.ndarray:
        """∂f_c/∂y on the interface unknowns, dense, shape ``(n_I, n_I)``."""
        ...


#: Builds the contact-force providers of a model from its stacked layout and the
#: interface unknowns (global stacked indices, sorted).
ContactFactory = Callable[[MonolithicLayout, np.ndarray], Sequence[ContactForces]]


class InterfaceAssembler:
    """The contact forms assembled over the contact facets into interface-sized arrays.

    Each block of the residual (one per body) and of its Jacobian (one per pair of
    bodies) is assembled by dolfinx into a small local array or CSR matrix whose
    sparsity holds the contact facets only; the entries at the interface unknowns are
    summed into dense arrays on every rank (one ``Allreduce``: ghost contributions add up
    with their owners' there, so no scatter is needed). Entries at the other DOFs of the
    facets' cells are dropped: their basis functions vanish on the facet, so they are
    zero to round-off.

    Args:
        model: The contact model.
        residual: The residual blocks (one UFL form or None per body).
        unknowns: The Functions the Jacobian is taken with respect to (Δa).
        positions: Per body, (local DOFs, interface positions) of the unknowns this rank
            holds.
        size: Number of interface unknowns.
    """

    def __init__(self, model: ContactModel, layout: MonolithicLayout,
                 residual: Sequence[ufl.Form | None], unknowns: Sequence[fem.Function],
                 positions: Sequence[tuple[np.ndarray, np.ndarray]],
                 interface: np.ndarray) -> None:
        self.comm = model.comm
        self.n = size = len(interface)
        where = [np.full(len(f.x.array), -1, np.int64) for f in unknowns]
        for w, (local, pos) in zip(where, positions, strict=True):
            w[local] = pos
        self._vectors = []
        for i, form in enumerate(residual):
            if form is None or form.empty():
                continue
            compiled = model.form(form)
            keep = np.flatnonzero(where[i] >= 0)
            self._vectors.append((compiled, np.zeros(len(where[i])), keep, where[i][keep]))
        self._matrices = []
        for i, form in enumerate(residual):
            if form is None or form.empty():
                continue
            for j, f in enumerate(unknowns):
                block = ufl.derivative(form, f, ufl.TrialFunction(f.function_space))
                block = ufl.algorithms.expand_derivatives(block)
                if block.empty():
                    continue
                compiled = model.form(block)
                A = fem.create_matrix(compiled, block_mode=la.BlockMode.expanded)
                rows = np.repeat(np.arange(len(A.indptr) - 1), np.diff(A.indptr))
                pr = self._positions(layout, interface, i, A.index_map(0), rows)
                pc = self._positions(layout, interface, j, A.index_map(1), A.indices)
                keep = np.flatnonzero((pr >= 0) & (pc >= 0))
                self._matrices.append((compiled, A, keep, pr[keep] * size + pc[keep]))

    @staticmethod
    def _positions(layout: MonolithicLayout, interface: np.ndarray, body: int,
                   imap: dolfinx.common.IndexMap, local: np.ndarray) -> np.ndarray:
        """Interface positions of local (expanded) CSR indices of a body; −1 if none."""
        bs = layout.bs[body]
        if len(local) == 0:
            return np.zeros(0, np.int64)
        # The expanded CSR index maps number scalars: global = block · bs + component.
        scalar = imap.local_to_global(np.asarray(local, np.int32))
        g = layout.stacked(body, scalar // bs).reshape(-1, bs)[np.arange(len(local)),
                                                                scalar % bs]
        at = np.minimum(np.searchsorted(interface, g), max(len(interface) - 1, 0))
        return np.where(interface[at] == g, at, -1) if len(interface) else -np.ones_like(g)

    def vector(self) -> np.ndarray:
        """The residual at the interface unknowns."""
        out = np.zeros(self.n)
        for compiled, b, keep, pos in self._vectors:
            b[:] = 0.0
            fem.assemble_vector(b, compiled)
            out[pos] += b[keep]
        self.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        return out

    def matrix(self) -> np.ndarray:
        """The Jacobian at the interface unknowns, dense."""
        out = np.zeros(self.n * self.n)
        for compiled, A, keep, flat in self._matrices:
            A.data[:] = 0.0
            fem.assemble_matrix(A, compiled)
            out += np.bincount(flat, weights=A.data[keep], minlength=self.n * self.n)
        self.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        return out.reshape(self.n, self.n)


class CondensedNewton:
    """SNES Newton of one GN22 step on the contact-surface unknowns (see the module doc).

    A drop-in for :class:`~breakwater.stepping.solver.NewtonSolver` in
    :class:`~breakwater.stepping.gn22.GN22`: :meth:`solve` takes Newton's start from Δa, writes
    the converged Δa and returns the iterations, or raises ConvergenceError.

    Args:
        model: The contact model.
        state: The GN22 state ``(u, v, a, Δa)``, one Function per body each; Δa is the
            step's unknown.
        dt: The step size constant.
        beta1: GN22 β₁.
        beta2: GN22 β₂.
        interface_residual: The contact part of the step residual, a form in Δa (None
            without contact pairs).
        options: Convergence settings.
        force_scale: Force norm that scales ``options.atol``.
        guard: Optional slip guard ``guard(v, step, dv_dx) -> corrected`` on local body
            arrays (:class:`~breakwater.contact.slipguard.SlipGuard`), the SNES pre-check.
        contact: Builds the contact forces (:class:`ContactForces`, summed); None: the
            UFL of ``interface_residual`` assembled over the contact facets
            (:class:`InterfaceAssembler`).
        surface_guard: The slip guard of the general pairs (their ``precheck``), also
            a pre-check.
    """

    def __init__(self, model: ContactModel,
                 state: tuple[Sequence[fem.Function], Sequence[fem.Function],
                              Sequence[fem.Function], Sequence[fem.Function]],
                 dt: fem.Constant, beta1: float, beta2: float,
                 interface_residual: ufl.Form | None, options: NewtonOptions | None = None,
                 force_scale: float = 1.0,
                 guard: Callable[[Sequence[np.ndarray], Sequence[np.ndarray], float], int]
                 | None = None, contact: ContactFactory | None = None,
                 surface_guard: bool = True) -> None:
        self.model = model
        # Every rank runs the same small dense algebra: one BLAS thread per rank.
        single_threaded_blas(model.comm)
        self.u, self.v, self.a, self.da = (list(x) for x in state)
        self.dt = dt
        self.beta1, self.beta2 = beta1, beta2
        self.options = o = options or NewtonOptions()
        self.layout = layout = MonolithicLayout(model)
        self.I = interface_dofs(model, layout) \
            if interface_residual is not None or model.surface_pairs else np.zeros(0, np.int64)
        self.n = n = len(self.I)
        self.timings = Timings()
        self.bulk = BulkOperators(model, layout, self.I, beta1, beta2, timings=self.timings)
        # Local (body, dof) positions of every interface entry this rank holds (owned or
        # ghost), to write y into Δa and read the assembled interface vector.
        self._write = []
        for gi in layout.global_index:
            pos = np.minimum(np.searchsorted(self.I, gi), max(n - 1, 0))
            hit = (self.I[pos] == gi) if n else np.zeros(len(gi), bool)
            self._write.append((np.flatnonzero(hit), pos[hit]))
        start, n_local = layout.start, layout.offsets[-1]
        self._owned = (self.I >= start) & (self.I < start + n_local)
        self._owned_rows = self.I[self._owned] - start
        self.providers: list[ContactForces] = []
        if interface_residual is not None:
            self.providers = list(contact(layout, self.I)) if contact is not None else [
                InterfaceAssembler(model, layout, ufl.extract_blocks(interface_residual),
                                   self.da, self._write, self.I)]
        # General pairs (breakwater.contact.general): one provider each.
        self.surfaces = [SurfaceContact(model, p, layout, self.I,
                                        (self.u, self.v, self.a, self.da), dt, beta1, beta2)
                         for p in model.surface_pairs]
        self.providers += self.surfaces
        for sp in self.surfaces:
            sp.timings = self.timings  # its search time: timings["contact_search"]
        self._vecs = {k: layout.vec.duplicate() for k in ("u", "v", "a", "r0", "z", "da", "w")}
        self.guard = guard
        self._guard_arrays = [[np.zeros_like(f.x.array) for f in self.da] for _ in range(2)]
        self.floor = o.floor_atol * force_scale
        self.floor_accepts = 0
        self.iterations = 0
        self._norms: list[float] = []
        self._fact: _Factorisation | None = None
        self._z_I = np.zeros(n)
        self._v_pred_I = np.zeros(n)
        self._fc = np.zeros(n)
        self._w_I = np.zeros(n)
        self._w_norm2 = 0.0
        self._force_norm = 0.0
        self.name = "gn22"
        # The SNES on the interface unknowns: the same small system on every rank.
        self.snes = snes = PETSc.SNES().create(PETSc.COMM_SELF)
        snes.setOptionsPrefix(model.options_prefix("contact"))
        self._x = PETSc.Vec().createSeq(n, comm=PETSc.COMM_SELF)
        self._r = self._x.duplicate()
        self._Jac = PETSc.Mat().createDense((n, n), comm=PETSc.COMM_SELF)
        self._Jac.setUp()
        snes.setFunction(self._residual, self._r)
        snes.setJacobian(self._jacobian, self._Jac)
        snes.setType("newtonls")
        snes.getLineSearch().setType("basic")
        snes.setTolerances(rtol=o.rtol, atol=o.atol * force_scale, stol=o.stol,
                           max_it=o.max_it)
        snes.setMaxFunctionEvaluations(10 * o.max_it)
        # As in NewtonSolver: the friction law makes the residual jump while the
        # stick/slip state settles, so no divergence test on its growth.
        snes.setDivergenceTolerance(1e300)
        ksp = snes.getKSP()
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        snes.setConvergenceTest(self._converged)
        self.surface_guard = surface_guard and any(p.friction for p in model.surface_pairs)
        self.surface_flips = 0
        if guard is not None or self.surface_guard:
            snes.setLineSearchPreCheck(self._precheck)
        snes.setFromOptions()

    def destroy(self) -> None:
        """Free the PETSc objects now (collective; see :meth:`NewtonSolver.destroy`)."""
        for obj in (self.snes, self._x, self._r, self._Jac, *self._vecs.values()):
            obj.destroy()
        self.bulk.destroy()
        self.layout.vec.destroy()

    def add_surface_forces(self, vec: PETSc.Vec, scale: float = 1.0) -> None:
        """Add ``scale`` × the general pairs' forces at the accepted state to a vector.

        At (u, v), into the owned entries of a stacked vector (the right-hand side of a₀).
        """
        fc = np.zeros(self.n)
        for p in self.surfaces:
            fc += p.vector(accepted=True)
        vec.array[self._owned_rows] += scale * fc[self._owned]

    # --- the interface problem --------------------------------------------------------

    def _set_interface(self, y: np.ndarray) -> None:
        """Write y into Δa at every interface entry this rank holds."""
        for f, (local, pos) in zip(self.da, self._write, strict=True):
            f.x.array[local] = y[pos]

    def _contact(self, y: np.ndarray) -> np.ndarray:
        """f_c(y) on the interface unknowns (the same on every rank)."""
        with self.timings("interface_assembly"):
            self._set_interface(y)
            out = self.providers[0].vector()
            for c in self.providers[1:]:
                out = out + c.vector()
            return out

    def _contact_jacobian(self, y: np.ndarray, X: np.ndarray) -> np.ndarray:
        """X ∂f_c/∂y on the interface unknowns (the same on every rank).

        A provider with a ``left_product(X)`` method gives the product itself (from its
        matrix's structure); the others their dense matrix.
        """
        out = np.zeros((self.n, self.n))
        dense: np.ndarray | None = None
        with self.timings("interface_assembly"):
            self._set_interface(y)
            for c in self.providers:
                product = getattr(c, "left_product", None)
                if product is not None:
                    out += product(X)
                else:
                    m = c.matrix()
                    dense = m if dense is None else dense + m
        if dense is not None:
            out += X @ dense
        return out

    def _residual(self, snes: PETSc.SNES, x: PETSc.Vec, r: PETSc.Vec) -> None:
        assert self._fact is not None
        y = x.getArray(readonly=True)
        self._fc = self._contact(y)
        # G = X_II F = y − z_I + X_II f_c(y): the same root as F = S (y − z_I) + f_c, but
        # without S's large entries of both signs, whose products carry n_I · |S| |y| of
        # round-off into F and stalled Newton above its tolerance (35 of the 1500 Goda
        # steps were accepted at the round-off floor, none now). The convergence test
        # reads the force ‖F‖ = ‖S G‖ (see _converged).
        G = y - self._z_I + self._fact.X_II @ self._fc
        r.array[:] = G
        self._force_norm = float(np.linalg.norm(self._fact.S @ G))

    def _jacobian(self, snes: PETSc.SNES, x: PETSc.Vec, J: PETSc.Mat, P: PETSc.Mat) -> None:
        assert self._fact is not None
        y = x.getArray(readonly=True)
        dense = self._contact_jacobian(y, self._fact.X_II)
        dense[np.diag_indices_from(dense)] += 1.0
        P.getDenseArray()[:] = dense
        P.assemble()

    def _converged(self, snes: PETSc.SNES, it: int, norms: tuple[float, float, float]) -> int:
        xnorm, ynorm, _ = norms
        fnorm = self._force_norm  # ‖F‖ = ‖S G‖, a force, as in the reference Newton
        if it == 0:
            # ‖F₀‖ of the relative test is the whole residual at Newton's start, bulk
            # rows included, as for the reference Newton: ‖R(Δa₀)‖² = ‖w‖² − ‖w_I‖² +
            # ‖w_I + f_c(y₀)‖² with w = A Δa₀ − r₀ (the bulk rows' residual).
            w_I = self._w_I
            whole = self._w_norm2 - w_I @ w_I + np.sum((w_I + self._fc) ** 2)
            self._norms = [math.sqrt(max(float(whole), fnorm**2))]
        else:
            self._norms.append(fnorm)
        reason, stalled = snes_reason(snes, self._norms, xnorm, ynorm, self.floor,
                                      self.options.stall_its)
        self.floor_accepts += stalled
        return reason

    def _precheck(self, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """The slip guard on the interface unknowns (SNES line-search pre-check).

        The guard works on local body arrays: the iterate's velocities
        v₁ = ṽ + β₁Δt y and the step are written at the interface entries, the only
        ones the guard reads, and the step is read back where the guard cut it.
        """
        if self.surface_guard:
            for p in self.surfaces:
                self.surface_flips += p.precheck(x.getArray(readonly=True), y.array)
        if self.guard is None:
            return
        dv_dx = self.beta1 * float(self.dt.value)
        velocity = self._v_pred_I + dv_dx * x.getArray(readonly=True)
        step = y.getArray(readonly=True)
        v_arrays, step_arrays = self._guard_arrays
        for va, sa, (local, pos) in zip(v_arrays, step_arrays, self._write, strict=True):
            va[local] = velocity[pos]
            sa[local] = step[pos]
        if self.guard(v_arrays, step_arrays, dv_dx):
            owned = np.concatenate([sa[:n] for sa, n in zip(step_arrays, self.layout.sizes,
                                                            strict=True)])
            y.array[:] = self._interface_array(owned)[0]

    # --- one step ---------------------------------------------------------------------

    def solve(self) -> int:
        """Solve the staged step (Δa holds Newton's start); return the iterations.

        Raises:
            ConvergenceError: The step did not converge; the state at t is untouched.
        """
        dt = float(self.dt.value)
        bulk, V, T = self.bulk, self._vecs, self.timings
        self._fact = fact = bulk.factorisation(dt)
        with T("bulk_products"):
            for fns, vec in ((self.u, V["u"]), (self.v, V["v"]), (self.a, V["a"]),
                             (self.da, V["da"])):
                self.layout.assign(fns, vec)
        bulk.predictor_residual(V["u"], V["v"], V["a"], dt, V["r0"])
        bulk.solve(fact, V["r0"], V["z"])
        if self.n == 0:  # no contact: the step is linear
            self._fc = np.zeros(0)
            its = 1
        else:
            # The bulk rows' residual at Newton's start, for the relative test.
            w = V["w"]
            with T("bulk_products"):
                fact.A.mult(V["da"], w)
                w.axpy(-1.0, V["r0"])
                self._w_norm2 = w.norm() ** 2
            z, v_pred, y0, self._w_I = self._interface_array(
                V["z"].array, V["v"].array + dt * V["a"].array, V["da"].array, w.array)
            self._z_I, self._v_pred_I = z, v_pred
            self._x.array[:] = y0
            assembly = T.seconds["interface_assembly"]
            t0 = time.perf_counter()
            self.snes.solve(None, self._x)
            T.seconds["newton"] += time.perf_counter() - t0 - (
                T.seconds["interface_assembly"] - assembly)
            reason: int = self.snes.getConvergedReason()  # type: ignore[assignment]
            its = self.snes.getIterationNumber()
            if reason <= 0:
                raise ConvergenceError(
                    f"{self.name}: Newton did not converge (SNES reason {reason}, {its} "
                    f"iterations, residual {self.snes.getFunctionNorm():.3e})", reason, its)
            self._check_penetration(its)
        self.iterations += its
        with T("bulk_products"):
            # The last residual evaluation was at the solution: f_c(y) is at hand.
            out = V["da"]
            out.array[:] = V["z"].array - fact.X @ self._fc
            # At the interface, Newton's converged iterate itself (z_I − X_II f_c equals it
            # only to the residual): the friction law, whose stick tangent is μp/χ, was
            # evaluated and converged there.
            out.array[self._owned_rows] = self._x.getArray(readonly=True)[self._owned]
            out.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
            fem_petsc.assign(out, self.da)
        return its

    def _check_penetration(self, its: int) -> None:
        """Reject a converged step that leaves a general pair's slave node unseen.

        Raises:
            PenetrationError: :meth:`SurfaceContact.penetration` of some pair (the same
                decision on every rank: every rank holds the same interface values).
        """
        with self.timings("interface_assembly"):
            y = self._x.getArray(readonly=True)
            for p in self.surfaces:
                why = p.penetration(y)
                if why is not None:
                    raise PenetrationError(why, 0, its)

    def _interface_array(self, *owned: np.ndarray) -> list[np.ndarray]:
        """Owned stacked arrays at the interface unknowns, on every rank (one reduction)."""
        out = np.zeros((len(owned), self.n))
        for row, arr in zip(out, owned, strict=True):
            row[self._owned] = arr[self._owned_rows]
        self.model.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        return list(out)
