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
step: a few sparse matrix-vector products for r₀, one back-solve for z and one product
with X, block by body (X is zero, exactly, where a body's rows meet another body's
unknowns), or a second back-solve ``A⁻¹(r₀ − E f_c)`` where that is cheaper
(:meth:`~breakwater.stepping.factorisations.Factorisations.keep_X`). Per Newton
iteration: the contact forces and their Jacobian on the interface unknowns and a dense
solve of size n_I. The Newton is a PETSc SNES on the interface unknowns (every rank
solves the same small system, so every rank takes the same decisions), with the
convergence test and the slip-reversal pre-check of the reference path.

The parts: :class:`~breakwater.stepping.bulk.BulkOperators` (M, K, the loads and r₀),
:class:`~breakwater.stepping.factorisations.Factorisations` (A, X and S per Δt),
:class:`~breakwater.stepping.interfacenewton.InterfaceNewton` (the SNES on y) and
:mod:`breakwater.stepping.interface` (where y lives on each rank, f_c on it);
:class:`CondensedNewton` builds them and runs a step through them.

The contact forces come from providers
(:class:`~breakwater.stepping.interface.ContactForces`: ``vector()`` and ``matrix()`` on
the interface unknowns at the state Functions, summed over the list a
:data:`~breakwater.stepping.interface.ContactFactory` builds). Conforming pairs in 2D use
:class:`~breakwater.contact.nodal.NodalContactForces`, the interface forms' nodal
quadrature evaluated on arrays (and ``left_product(X)``, the product X_II ∂f_c/∂y from
its node-by-node structure); :class:`InterfaceAssembler` assembles the UFL of
``forms/`` over the contact facets, for everything else.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import dolfinx
import numpy as np
import ufl
from dolfinx import fem, la
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from breakwater.common.errors import PenetrationError
from breakwater.common.parallel import single_threaded_blas
from breakwater.common.timings import Timings
from breakwater.contact.general import SurfaceContact
from breakwater.contact.general3d import SurfaceContact3D
from breakwater.model.layout import MonolithicLayout
from breakwater.model.model import ContactModel
from breakwater.stepping.bulk import BulkOperators, interface_dofs
from breakwater.stepping.factorisations import Factorisations
from breakwater.stepping.interface import (
    BodyGuard,
    ContactFactory,
    ContactForces,
    ContactSum,
    Guard,
    InterfaceUnknowns,
    StateForces,
)
from breakwater.stepping.interfacenewton import InterfaceNewton
from breakwater.stepping.solver import NewtonOptions
from breakwater.stepping.stepsolver import PairMemory, StepSolver

__all__ = ["CondensedNewton", "ContactFactory", "ContactForces", "GeneralPairs",
           "InterfaceAssembler"]


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

    def left_product(self, X: np.ndarray) -> None:
        """None: the product is formed from :meth:`matrix` (no structure to use)."""
        return None

    def resolution(self, y: np.ndarray) -> float:
        """0: no estimate (the forms' round-off is left to the Newton's stall test)."""
        return 0.0

    def active_jacobian(self) -> None:
        """None: the assembled matrix has no such form here."""
        return None

    def begin_step(self) -> None:
        """Nothing to keep: the forms are assembled at the state Functions."""

    def at(self, y: np.ndarray) -> bool:
        """False: Δa must hold the iterate (the forms read it)."""
        return False

    def end_step(self) -> None:
        """Nothing kept."""

    def matrix(self) -> np.ndarray:
        """The Jacobian at the interface unknowns, dense."""
        out = np.zeros(self.n * self.n)
        for compiled, A, keep, flat in self._matrices:
            A.data[:] = 0.0
            fem.assemble_matrix(A, compiled)
            out += np.bincount(flat, weights=A.data[keep], minlength=self.n * self.n)
        self.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        return out.reshape(self.n, self.n)


def _surface_guard(pair: SurfaceContact) -> Guard:
    """A general pair's slip guard (``precheck(x, step, bulk)``) as a StateForces guard."""
    return lambda x, step, v_pred, dv_dx, bulk: pair.precheck(x, step, bulk)


class CondensedNewton(StepSolver):
    """The fast path's :class:`~breakwater.stepping.stepsolver.StepSolver` (see the module doc).

    In :class:`~breakwater.stepping.gn22.GN22`, :meth:`solve` takes Newton's start from
    Δa, writes the converged Δa and returns the iterations, or raises ConvergenceError.
    The bulk's operators are :attr:`bulk` (assembled once) and :attr:`factorisations`
    (per Δt); the Newton on the interface unknowns is :attr:`newton`
    (:class:`~breakwater.stepping.interfacenewton.InterfaceNewton`), the contact forces
    on them :attr:`contact`.

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
            arrays (:class:`~breakwater.contact.slipguard.SlipGuard`) for the conforming
            pairs of the assembled provider (``contact`` None), a pre-check of Newton's
            steps; the providers ``contact`` builds guard their own pairs.
        contact: Builds the contact forces
            (:class:`~breakwater.stepping.interface.ContactForces`, summed); None: the
            UFL of ``interface_residual`` assembled over the contact facets
            (:class:`InterfaceAssembler`).
        surface_guard: The slip guard of the general pairs (their ``precheck``), also
            a pre-check. The nodes every guard corrected count in ``newton.flips``.
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
        self.layout = layout = MonolithicLayout(model)
        self.I = interface_dofs(model, layout) \
            if interface_residual is not None or model.surface_pairs else np.zeros(0, np.int64)
        self.n = len(self.I)
        self.interface = InterfaceUnknowns(layout, self.I)
        self.timings = Timings()
        self.bulk = BulkOperators(model, layout, timings=self.timings)
        self.factorisations = Factorisations(self.bulk, self.I, beta1, beta2,
                                             timings=self.timings)
        self.providers: list[ContactForces] = []
        if interface_residual is not None:
            self.providers = list(contact(layout, self.I)) if contact is not None else [
                StateForces(InterfaceAssembler(
                    model, layout, ufl.extract_blocks(interface_residual), self.da,
                    self.interface.positions, self.I), self.interface, self.da,
                    BodyGuard(guard, self.interface, layout, self.da)
                    if guard is not None else None)]
        # General pairs (contact.general; general3d in 3-D, typed as the 2-D kind here).
        kind: Any = SurfaceContact3D if model.gdim == 3 else SurfaceContact
        self.surfaces: list[SurfaceContact] = [
            kind(model, p, layout, self.I, (self.u, self.v, self.a, self.da), dt, beta1, beta2)
            for p in model.surface_pairs]
        # Frictionless pairs too (inert at μ = 0): the relaxation's held stage sets μ = 100.
        self.providers += [StateForces(sp, self.interface, self.da,
                                       _surface_guard(sp) if surface_guard else None)
                           for sp in self.surfaces]
        for sp in self.surfaces:
            sp.timings = self.timings  # its search time: timings["contact_search"]
        self.contact = ContactSum(self.n, self.providers, self.timings)
        self.general = GeneralPairs(self.surfaces, self.timings)
        self._vecs = {k: layout.vec.duplicate() for k in ("u", "v", "a", "r0", "z", "da", "w")}
        self.guard = guard
        self.newton = InterfaceNewton(self.n, self.contact, "gn22", options or NewtonOptions(),
                                      force_scale, self.timings)
        self.consistent = bool(model.surface_pairs)
        """Whether the bulk's Δa balances Newton's interface iterate y (:meth:`solve`).

        Off, Δa's bulk rows take z − X f_c(y), which balances z_I − X_II f_c(y), not y:
        they differ by the Newton's residual G, whose force S G the Newton converged,
        but which leaves the force A_BI G in the bulk rows. S is soft where the bulk
        follows the interface (a body's rigid modes: S ~ M there) and A_BI ~ ½β₂Δt² K:
        the whole static residual at the relaxation's c (7e-6 ‖f‖ on the non-matching
        patch test, σ off by 6e-6 p: :mod:`breakwater.statics.pseudostep` turns it on),
        and at Δt = 1e-3 s a drift of the same patch's exact static state by 1.2e-8 p
        in 20 steps (4e-11 p on). On, the bulk balances the interface forces f_c − S G
        instead (the Newton's last residual force). On for models with general pairs;
        off for the conforming pairs alone (their histories bit for bit as before)."""

    @property
    def floor_accepts(self) -> int:
        """Solves accepted at their round-off floor (the interface Newton's)."""
        return self.newton.floor_accepts

    @floor_accepts.setter
    def floor_accepts(self, value: int) -> None:
        self.newton.floor_accepts = value

    def destroy(self) -> None:
        """Free the PETSc objects now (collective; see :meth:`NewtonSolver.destroy`)."""
        for vec in self._vecs.values():
            vec.destroy()
        self.factorisations.destroy()
        self.bulk.destroy()
        self.layout.vec.destroy()

    def add_surface_forces(self, vec: PETSc.Vec, scale: float = 1.0) -> None:
        """Add ``scale`` × the general pairs' forces at the accepted state to a vector.

        At (u, v), into the owned entries of a stacked vector (the right-hand side of a₀).
        """
        fc = np.zeros(self.n)
        for p in self.surfaces:
            fc += p.vector(accepted=True)
        vec.array[self.interface.owned_rows] += scale * fc[self.interface.owned]

    # --- one step ---------------------------------------------------------------------

    def solve(self) -> int:
        """Solve the staged step (Δa holds Newton's start); return the iterations.

        Raises:
            ConvergenceError: The step did not converge; the state at t is untouched.
        """
        dt = float(self.dt.value)
        bulk, V, T = self.bulk, self._vecs, self.timings
        fact = self.factorisations.factorisation(dt)
        with T("bulk_products"):
            for fns, vec in ((self.u, V["u"]), (self.v, V["v"]), (self.a, V["a"]),
                             (self.da, V["da"])):
                self.layout.assign(fns, vec)
        bulk.predictor_residual(V["u"], V["v"], V["a"], dt, V["r0"])
        self.factorisations.solve(fact, V["r0"], V["z"])
        if self.n == 0:  # no contact: the step is linear
            fc = np.zeros(0)
            its = 1
        else:
            # The bulk rows' residual at Newton's start, for the relative test (the
            # constant-velocity start: before the general pairs' slip predictor).
            w = V["w"]
            with T("bulk_products"):
                bulk.start_residual(V["u"], V["v"], V["a"], V["da"], V["r0"], dt, self.beta1,
                                    self.beta2, fact.A, w)
                w_norm2 = w.norm() ** 2
            z, v_I, a_I, y0, w_I = self.interface.gather(
                V["z"].array, V["v"].array, V["a"].array, V["da"].array, w.array)
            v_pred = v_I + dt * a_I  # ṽ = v₀ + Δt a₀ at the interface unknowns
            self.contact.begin()
            try:
                self.general.start(y0)
                its = self.newton.solve(fact, z, y0, w_I, w_norm2, v_pred, self.beta1 * dt)
                self.general.finish(self.newton.y, its)
            finally:
                self.contact.end()
            # The last residual evaluation was at the solution: f_c(y) is at hand.
            fc = self.newton.fc
            if self.consistent:
                # The bulk that balances y, the interface forces f_c − S G (G = y − z_I
                # + X_II f_c, the Newton's residual, S G its force F at the solution):
                # the step's residual is then the force the Newton converged, not A_BI G.
                fc = fc - self.newton.F
        out = V["da"]
        if fact.X_blocks is None:  # Δa = z − X f_c = A⁻¹(r₀ − E f_c): a back-solve
            with T("bulk_products"):
                rhs = V["w"]
                rhs.array[:] = V["r0"].array
                rhs.array[self.interface.owned_rows] -= fc[self.interface.owned]
            self.factorisations.solve(fact, rhs, out)
        else:
            with T("bulk_products"):
                da = out.array
                da[:] = V["z"].array
                fact.subtract_X(fc, da, self.newton.support)  # Δa = z − X f_c, by body block
        with T("bulk_products"):
            # At the interface, Newton's converged iterate itself (z_I − X_II f_c equals it
            # only to the residual): the friction law, whose stick tangent is μp/χ, was
            # evaluated and converged there.
            out.array[self.interface.owned_rows] = self.newton.y[self.interface.owned]
            out.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
            fem_petsc.assign(out, self.da)
        return its

    def accept(self) -> None:
        """The solved step is accepted (:meth:`GeneralPairs.accept`)."""
        self.general.accept()

    def memory(self) -> list[PairMemory]:
        """:meth:`GeneralPairs.memory`."""
        return self.general.memory()

    def restore(self, memory: list[PairMemory]) -> None:
        """:meth:`GeneralPairs.restore`."""
        self.general.restore(memory)


class GeneralPairs:
    """The general pairs' part of a fast step around its Newton.

    Args:
        surfaces: The pairs.
        timings: Where their work is timed (``interface_assembly``).
    """

    def __init__(self, surfaces: Sequence[SurfaceContact], timings: Timings) -> None:
        self.surfaces, self.timings = surfaces, timings

    def start(self, y0: np.ndarray) -> None:
        """Newton's start: each slave node's last slip velocity kept (in place)."""
        with self.timings("interface_assembly"):
            for sp in self.surfaces:
                sp.memory.predict(y0)

    def finish(self, y: np.ndarray, its: int) -> None:
        """Check the converged y and keep its slip velocities.

        Raises:
            PenetrationError: y leaves a slave node beyond what a pair's search sees
                (:meth:`SurfaceContact.penetration`; the same decision on every rank:
                every rank holds the same interface values).
        """
        with self.timings("interface_assembly"):
            for p in self.surfaces:
                why = p.penetration(y)
                if why is not None:
                    raise PenetrationError(why, 0, its)
            for p in self.surfaces:
                p.memory.converged(y)

    def accept(self) -> None:
        """The solved step is accepted: the pairs keep its slip velocities."""
        for sp in self.surfaces:
            sp.memory.accept()

    def memory(self) -> list[PairMemory]:
        """Per pair, what its next step depends on beyond u, v, a (a checkpoint's).

        ``slip``: its slave nodes' last slip velocities (Newton's start); ``facets``:
        the master facets its searches use (:meth:`SurfaceForces.reach
        <breakwater.contact.general.SurfaceForces.reach>`: the set only grows, and the
        Newton on the unknowns within reach rounds off by it; a resumed run that
        started from none differed from the uninterrupted one from its first step, by
        8e-12 of u_x and 3e-3 of a small strain).
        """
        return [{"slip": sp.memory.saved(),
                 "facets": [int(f) for f in np.flatnonzero(sp.in_use.mask)]}
                for sp in self.surfaces]

    def restore(self, memory: list[PairMemory]) -> None:
        """Set what :meth:`memory` returned (a resumed run).

        A checkpoint written before the facets were saved holds the slip velocities
        alone: the facets are then marked again as the steps go.
        """
        for sp, saved in zip(self.surfaces, memory, strict=True):
            if not isinstance(saved, dict):
                sp.memory.load(saved)
                continue
            sp.memory.load(saved["slip"])
            mask = sp.in_use.mask
            facets = np.asarray(saved["facets"], dtype=np.int64)
            if np.any((facets < 0) | (facets >= len(mask))):
                raise ValueError(f"contact '{sp.spec.name}': the checkpoint's master "
                                 f"facets are not this mesh's ({len(mask)} facets)")
            mask[:] = False
            mask[facets] = True
