"""The GN22 time stepper (Katona & Zienkiewicz 1985; the paper's §4, eqs. 24-28).

The unknown of each step is the acceleration increment ``Δa``::

    a₁ = a₀ + Δa
    v₁ = v₀ + Δt a₀ + β₁ Δt Δa
    u₁ = u₀ + Δt v₀ + ½Δt² a₀ + ½β₂ Δt² Δa

(:func:`gn22_kinematics`, the one place these are written) and
``M a₁ + C v₁ + K u₁ + f_c(u₁, v₁) = f(t₁)`` is solved for ``Δa`` by Newton. The
scheme is unconditionally stable for β₂ ≥ β₁ ≥ ½; β₁ = ½ is second-order accurate,
β₁ > ½ adds numerical damping. Like dolfiny's ``odeint``, the integrator is an object
(stage, solve, update) whose ``t`` and ``Δt`` are ``fem.Constant`` s, so the forms
compile once for the whole run, whatever the step size.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass

import dolfinx
import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common.errors import MeshError
from breakwater.common.jit import kernel
from breakwater.contact.conforming import InterfaceNodes, interface_nodes, mean_facet_length
from breakwater.contact.nodal import NodalContactForces, nodal_contact_applies
from breakwater.contact.pairstate import conforming_pairs
from breakwater.contact.slipguard import SlipGuard
from breakwater.model.model import ContactModel, PairData
from breakwater.model.pairs import Pair
from breakwater.stepping.condensed import CondensedNewton
from breakwater.stepping.factorisations import check_factorisation
from breakwater.stepping.solver import NewtonOptions, NewtonSolver
from breakwater.stepping.stepsize import error_constant
from breakwater.stepping.stepsolver import StepSolver


@dataclass(frozen=True)
class GN22Parameters:
    """GN22 parameters.

    Attributes:
        beta1: β₁ (Newmark γ); ½ is second order, larger damps high frequencies.
        beta2: β₂ (2 × Newmark β).
        allow_conditional: Accept β₁ < ½ or β₂ < β₁ (conditionally stable or
            unstable schemes), for studies only.

    """

    beta1: float = 0.6
    beta2: float = 0.605
    allow_conditional: bool = False

    def __post_init__(self) -> None:
        if not self.allow_conditional and not (self.beta2 >= self.beta1 >= 0.5):
            raise ValueError(
                f"GN22 needs beta2 >= beta1 >= 0.5 for unconditional stability (got "
                f"beta1={self.beta1}, beta2={self.beta2}); set allow_conditional to insist")
        if self.beta1 <= 0 or self.beta2 <= 0:
            raise ValueError("GN22 needs beta1 > 0 and beta2 > 0")


def gn22_kinematics(u, v, a, Δa, Δt, β1, β2):
    """The GN22 update of one step (the paper's eqs. 24-26): ``(u₁, v₁, a₁)`` from Δa.

    ::

        u₁ = u₀ + (Δt v₀ + ½Δt² a₀ + ½β₂ Δt² Δa)
        v₁ = v₀ + (Δt a₀ + β₁ Δt Δa)
        a₁ = a₀ + Δa

    Works on UFL expressions (``Δt`` may be a ``fem.Constant``), where it gives the
    unknowns of the step's residual, and on NumPy arrays (``f.x.array``, ``Δt`` a
    float), where it gives the accepted state; the increments are added last, so that
    ``u₀ + Δu`` is the same in-place ``u += Δu`` on arrays.

    Args:
        u: Displacement u₀.
        v: Velocity v₀.
        a: Acceleration a₀.
        Δa: Acceleration increment (the unknown of the step).
        Δt: Time step.
        β1: β₁.
        β2: β₂.

    Returns:
        ``(u₁, v₁, a₁)``.
    """
    du = Δt * v + 0.5 * Δt**2 * a + 0.5 * β2 * Δt**2 * Δa
    dv = Δt * a + β1 * Δt * Δa
    return u + du, v + dv, a + Δa


@kernel
def gn22_update(u: np.ndarray, v: np.ndarray, a: np.ndarray, Δa: np.ndarray, Δt: float,
                β1: float, β2: float) -> None:
    """:func:`gn22_kinematics` on arrays, in place and in one pass (compiled).

    The same floating-point operations in the same order, so the same numbers as
    ``u, v, a = gn22_kinematics(u, v, a, Δa, Δt, β1, β2)``.
    """
    c_a = 0.5 * Δt**2
    c_u = 0.5 * β2 * Δt**2
    c_v = β1 * Δt
    for i in range(u.shape[0]):
        du = Δt * v[i] + c_a * a[i] + c_u * Δa[i]
        dv = Δt * a[i] + c_v * Δa[i]
        u[i] = u[i] + du
        v[i] = v[i] + dv
        a[i] = a[i] + Δa[i]


def force_scale(model: ContactModel) -> float:
    """A force norm of the problem: ‖f‖ of gravity and loads at t = 0 (else 1)."""
    b = fem_petsc.assemble_vector(model.form(ufl.extract_blocks(model.external_load())),
                                  kind="mpi")
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    norm = b.norm()
    b.destroy()
    return norm if norm > 0 else 1.0


def solve_static(model: ContactModel, u: Sequence[fem.Function] | None = None,
                 options: NewtonOptions | None = None,
                 tangential_stabilisation: float = 1e-2) -> tuple[list[fem.Function], int]:
    """Frictionless static equilibrium under gravity and the loads at t = 0.

    A frictionless state is an exact equilibrium of the velocity-regularised law,
    which carries no shear at zero velocity, so the dynamics then starts at rest.
    A body held only by frictionless contact can slide as a rigid body, which makes
    the Jacobian singular. The Jacobian is therefore taken from the residual plus a
    weak tangential spring ``k_t = tangential_stabilisation · ε_n`` on the
    interfaces, while the residual itself has no spring: the iteration converges
    linearly to the frictionless equilibrium, at a rate of about ``k_t / (k_t + E/h)``
    per iteration, and leaves the rigid tangential position where the initial guess
    put it. The spring is ``k_t = tangential_stabilisation · min(ε_n, E/h)``, with E
    the softer body's Young's modulus and h the mean interface facet length: weak
    against the bodies, so that few iterations are needed however stiff the penalty,
    yet not so weak that the rigid position is ill-conditioned. On the Goda case this
    takes 6 iterations, starts the dynamics with |a₀| < 1e-6 m/s² and gives the same
    state serially and on 2 ranks to 2e-16 m (a spring of 1e-6 ε_n gave 8e-12 m).

    Args:
        model: The contact model.
        u: Initial guess (one Function per body); zero when None.
        options: Newton settings.
        tangential_stabilisation: ``k_t / ε_n`` (0: plain Newton).

    Returns:
        The displacements and the Newton iterations.
    """
    u = list(u) if u is not None else model.functions("u")
    if model.surface_pairs:
        # Their forces are not UFL forms: breakwater.statics.relaxation finds their static state.
        raise ValueError("general contact pairs: the static state is found by "
                         "breakwater.statics.initial.initial_state (pseudo-transient relaxation)")
    g = model.gravity.value
    if not any(f.x.array.any() for f in u) and np.any(g):
        # A small penetration along gravity so that every contact starts active.
        for p in model.pairs:
            u[p.slave].x.array.reshape(-1, model.gdim)[:] = 1e-9 * g / np.linalg.norm(g)
    F = model.residual(u)
    F_t = F
    if tangential_stabilisation > 0:
        for p in model.pairs:
            k_t = tangential_stabilisation * tangential_stiffness(model, p)
            jump = forms.tangential_part(u[p.slave]("+") - u[p.master]("-"), p.n)
            δw = forms.tangential_part(model.w[p.slave]("+") - model.w[p.master]("-"), p.n)
            F_t += k_t * ufl.dot(jump, δw) * p.dS
    solver = NewtonSolver(model, F, u, "static", options, force_scale(model), jacobian_of=F_t)
    try:
        return u, solver.solve()
    finally:
        solver.destroy()


def tangential_stiffness(model: ContactModel, pair: PairData) -> float:
    """min(ε_n, E/h) of a pair: the softer body's E over the mean facet size."""
    E = min(model.bodies[i].spec.material.E for i in (pair.slave, pair.master))
    return min(float(pair.ε_n.value), E / mean_facet_length(model, pair))


def initial_acceleration(model: ContactModel, solver: StepSolver, u: Sequence[fem.Function],
                         v: Sequence[fem.Function], a: Sequence[fem.Function],
                         amplitudes: Sequence[float] | None = None) -> None:
    """Solve M a₀ = f(t₀) − C v₀ − K u₀ − f_c(u₀, v₀) for a₀, into ``a``.

    The loads are the model's at its current time, or at ``amplitudes`` (the loads of
    the initial state: :meth:`GN22.initialise` sets those left out of it to 0). f_c
    includes the forces the UFL residual does not hold (the general pairs', from
    ``solver``), so that a₀ vanishes in their static state
    (:mod:`breakwater.statics.relaxation`).

    A load left out of the initial state but non-zero at t₀ jumps there: a₀ does not
    see it, the first step's end does, so it is applied over the first step, as GN22
    applies any jump between two step ends. Taking it in a₀ (the acceleration at t₀⁺)
    put its stiff modes' M⁻¹f into the step's explicit part ½(1 − β₂)Δt² a₀: with
    stiffness-proportional damping, which overdamps the stiff modes, the first step's
    strain energy then rose from 0.11 to 2.14 J/m for a work of −0.07 J/m on the Goda
    case (its pulse made rectangular, left out of the state), the ledger's numerical
    dissipation −56 % of the work at the end (now +1.3 %), and the pulse's impulse 2 %
    too large (the momentum rule's (1 − β₁)Δt f(t₀) on top of the pulse's own).
    """
    m = model
    if amplitudes is not None:
        now = [float(ld.amplitude.value) for ld in m.loads]
        try:
            for ld, value in zip(m.loads, amplitudes, strict=True):
                ld.amplitude.value = value
            initial_acceleration(m, solver, u, v, a)
        finally:
            for ld, value in zip(m.loads, now, strict=True):
                ld.amplitude.value = value
        return
    for f in a:
        f.x.array[:] = 0.0
    trial = ufl.TrialFunctions(m.W)
    M = fem_petsc.assemble_matrix(m.form(ufl.extract_blocks(m.mass(trial))), bcs=m.bcs,
                                  kind="mpi")
    M.assemble()
    R = m.form(ufl.extract_blocks(m.residual(u, v, a)))
    b = fem_petsc.assemble_vector(R, kind="mpi")
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    b.scale(-1.0)
    # The general pairs' forces are not in the UFL residual.
    solver.add_surface_forces(b, -1.0)
    fem_petsc.set_bc(b, fem.bcs_by_block(fem.extract_function_spaces(R), m.bcs), alpha=0.0)
    ksp = PETSc.KSP().create(m.comm)  # type: ignore[arg-type]
    ksp.setOptionsPrefix("breakwater_mass_")
    ksp.setOperators(M)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    ksp.setUp()
    check_factorisation(ksp, "the mass matrix M (the initial acceleration)")
    x = b.duplicate()
    ksp.solve(b, x)
    x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    fem_petsc.assign(x, a)
    for obj in (ksp, M, b, x):
        obj.destroy()


class GN22:
    """GN22 integrator of a contact model.

    Args:
        model: The contact model.
        dt: Time step (s).
        parameters: β₁, β₂.
        t0: Initial time (s).
        newton: Newton settings.
        flip_guard: Stop nodal slip velocities from reversing within one Newton step
            (:mod:`breakwater.contact.slipguard`); needed for small χ.
        solver: ``"fast"``: the bulk factorised once per Δt and Newton on the contact
            surfaces only (:mod:`breakwater.stepping.condensed`); ``"reference"``: Newton on the
            whole residual, assembled and factorised at every iteration.

    Raises:
        MeshError: A pair cannot start from the meshed configuration
            (:meth:`breakwater.model.pairs.Pair.static_check`).
    """

    SOLVERS = ("fast", "reference")

    def __init__(self, model: ContactModel, dt: float, parameters: GN22Parameters | None = None,
                 t0: float = 0.0, newton: NewtonOptions | None = None,
                 flip_guard: bool = True, solver: str = "fast") -> None:
        if solver not in self.SOLVERS:
            raise ValueError(f"solver must be one of {', '.join(self.SOLVERS)} (got {solver!r})")
        if solver == "reference" and model.surface_pairs:
            raise ValueError("general contact pairs (slave and master surfaces) need the "
                             "fast solver (time.solver = \"fast\")")
        self.model = model
        self.kind = solver  # (the summary's solver.kind)
        self.params = p = parameters or GN22Parameters()
        msh = model.mesh
        self.t = fem.Constant(msh, dolfinx.default_scalar_type(t0))
        self.dt = fem.Constant(msh, dolfinx.default_scalar_type(dt))
        self.u, self.v, self.a = model.functions("u"), model.functions("v"), model.functions("a")
        self.da = model.functions("da")
        self.u1, self.v1, self.a1 = (list(x) for x in zip(*(
            gn22_kinematics(u, v, a, d, self.dt, p.beta1, p.beta2)
            for u, v, a, d in zip(self.u, self.v, self.a, self.da, strict=True)), strict=True))
        self.nodes: Sequence[InterfaceNodes] = interface_nodes(model) if flip_guard else ()
        # The fast path's guard also lands slips on the friction law's curve; the
        # reference path's Newton keeps the reversal cuts alone (as it was before them).
        self.guard = SlipGuard(self.nodes, landing=solver == "fast") if self.nodes else None
        self._flips = 0  # nodes the guard cut outside the fast solver's Newton
        self.solver: StepSolver
        #: The fast path's solver, for what only it has (its bulk operators and
        #: interface unknowns: the ledger's matrices, the relaxation); None on the
        #: reference path.
        self.fast: CondensedNewton | None = None
        if solver == "fast":
            state = (self.u, self.v, self.a, self.da)
            contact = None
            if model.pairs and nodal_contact_applies(model):
                # The interface forms' nodal quadrature evaluated on arrays.
                nodes = self.nodes or interface_nodes(model)

                def contact(layout, interface):  # type: ignore[no-untyped-def]
                    return [NodalContactForces(model, nd, layout, interface, state, self.dt,
                                               p.beta1, p.beta2, guard=flip_guard)
                            for nd in nodes]
            self.solver = self.fast = CondensedNewton(
                model, state, self.dt, p.beta1, p.beta2,
                model.interface_residual(self.u1, self.v1) if model.pairs else None,
                newton, force_scale=force_scale(model),
                guard=self.guard, contact=contact,
                surface_guard=flip_guard)
        else:
            self._y = model.functions("step")
            F = model.residual(self.u1, self.v1, self.a1)
            self.solver = NewtonSolver(model, F, self.da, "gn22", newton,
                                       force_scale=force_scale(model),
                                       precheck=self._precheck if self.guard else None)
        # The general pairs the fast solver built on this stepper's state (SurfaceContact),
        # as the solver's force providers (the relaxation's); measured: self.contacts.
        self.surfaces = self.fast.surfaces if self.fast is not None else []
        # The time and the loads' amplitudes a₀ took (initialise: the loads' indices given
        # to it are those of the initial state, the others are 0; initial_acceleration).
        self.start_time, self.start_amplitudes = t0, [float(x.amplitude.value) for x in model.loads]
        self._contacts: list[Pair] | None = None
        # Every stepper refuses a pair that cannot start from the meshed configuration
        # (Pair.static_check: a general pair's bodies overlapped beyond its search).
        for pair in self.contacts:
            why = pair.static_check()
            if why is not None:
                self.destroy()
                raise MeshError(why)

    @property
    def flips(self) -> int:
        """Nodes whose slip reversal the slip guards cut, over the run."""
        return self._flips + (self.fast.newton.flips if self.fast is not None else 0)

    @flips.setter
    def flips(self, value: int) -> None:
        self._flips = value
        if self.fast is not None:
            self.fast.newton.flips = 0

    @property
    def contacts(self) -> list[Pair]:
        """Every pair at this stepper's state (u, v): conforming, then general (collective).

        The one route from a run's objects (ledger, monitor, probes, fields, snapshots,
        quality) to the pairs (:class:`breakwater.model.pairs.Pair`); built on first use.
        """
        if self._contacts is None:
            self._contacts = [*conforming_pairs(self.model, self.nodes, self.u, self.v, self.dt),
                              *self.surfaces]
        return self._contacts

    # --- initial state ------------------------------------------------------------

    def initialise(self, u0: Sequence[fem.Function] | None = None,
                   v0: Sequence[fem.Function] | None = None,
                   loads: Collection[int] | None = None) -> None:
        """Set u₀, v₀ (None: zero), a₀ with the initial state's ``loads`` (None: all) only."""
        for dst, src in ((self.u, u0), (self.v, v0)):
            for f, g in zip(dst, src or [None] * len(dst), strict=True):
                f.x.array[:] = 0.0 if g is None else g.x.array
        self.start_time = float(self.t.value)
        self.model.set_time(self.start_time)
        self.start_amplitudes = [0.0 if loads is not None and k not in loads
                                 else float(ld.amplitude.value)
                                 for k, ld in enumerate(self.model.loads)]
        initial_acceleration(self.model, self.solver, self.u, self.v, self.a, self.start_amplitudes)

    # --- one step -----------------------------------------------------------------

    def stage(self, dt: float | None = None, t1: float | None = None) -> None:
        """Prepare the step to t + Δt (or ``t1``, StepSize.landing): Δt, loads, Newton's start.

        Newton starts from the constant-velocity predictor ``Δa = −a/β₁``
        (``v₁ = v₀``) rather than ``Δa = 0`` (``a₁ = a₀``): the friction law is a
        function of the velocity, and where the interface sticks, GN22's
        accelerations alternate in sign from step to step (``a₁ ≈ −(1 − β₁)/β₁ a₀``
        under the stiff ``μp/χ`` tangent). On the Goda case this takes the mean
        Newton iterations per step from 5.2 to 3.7.
        """
        if dt is not None:
            self.dt.value = dt
        self.model.set_time(float(self.t.value + self.dt.value) if t1 is None else t1)
        for d, a in zip(self.da, self.a, strict=True):
            d.x.array[:] = -a.x.array / self.params.beta1

    def solve(self) -> int:
        """Newton on the step's residual; returns the iterations.

        Raises:
            ConvergenceError: The step did not converge; the state at t is untouched.

        """
        return self.solver.solve()

    def update(self) -> None:
        """Accept the step: (u, v, a) ← (u₁, v₁, a₁), t ← t + Δt."""
        Δt = float(self.dt.value)
        for u, v, a, d in zip(self.u, self.v, self.a, self.da, strict=True):
            gn22_update(u.x.array, v.x.array, a.x.array, d.x.array, Δt, self.params.beta1,
                        self.params.beta2)
        self.t.value += Δt
        self.solver.accept()

    def destroy(self) -> None:
        """Free the PETSc objects of the Newton solver (collective).

        See :meth:`NewtonSolver.destroy`; the stepper cannot solve afterwards.
        """
        self.solver.destroy()

    def step(self, dt: float | None = None) -> int:
        """Stage, solve and update one step; returns the Newton iterations."""
        self.stage(dt)
        its = self.solve()
        self.update()
        return its

    # --- Newton safeguard for the regularised friction law ------------------------

    def _precheck(self, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """SNES line-search pre-check: the slip guard (:mod:`breakwater.contact.slipguard`).

        Its reversal cuts alone (no landings on the law's curve: the reference Newton as
        it was). The guard gets the velocities v₁ of the iterate ``x`` and β₁Δt, the change of
        v₁ per unit Δa, and may cut the step ``y``; its corrections count in
        :attr:`flips`.
        """
        assert self.guard is not None
        y.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        fem_petsc.assign(y, self._y)
        fem_petsc.assign(x, self.da)
        Δt, β1, β2 = float(self.dt.value), self.params.beta1, self.params.beta2
        v1 = [gn22_kinematics(u.x.array, v.x.array, a.x.array, d.x.array, Δt, β1, β2)[1]
              for u, v, a, d in zip(self.u, self.v, self.a, self.da, strict=True)]
        corrected = self.guard(v1, [f.x.array for f in self._y], β1 * Δt)
        if corrected:
            self.flips += corrected
            fem_petsc.assign(self._y, y)


def local_error(stepper: GN22) -> tuple[float, float, float]:
    """The step solved by ``stepper``: its local error estimate, increment and size (collective).

    ``e = c Δt² Δa`` with c = :func:`~breakwater.stepping.stepsize.error_constant`
    (Zienkiewicz & Xie 1991) and ``Δu = Δt v + ½Δt² a + ½β₂Δt² Δa``, before
    :meth:`GN22.update`.

    Returns:
        ‖e‖∞, ‖Δu‖∞ and ‖u + Δu‖∞ over the owned DOFs of every body (the same on
        every rank).
    """
    Δt, p = float(stepper.dt.value), stepper.params
    c = error_constant(p.beta1, p.beta2) * Δt**2
    e = du = size = 0.0
    for u, v, a, d in zip(stepper.u, stepper.v, stepper.a, stepper.da, strict=True):
        n = u.function_space.dofmap.index_map.size_local * u.function_space.dofmap.index_map_bs
        if n == 0:
            continue
        dd = d.x.array[:n]
        e = max(e, c * float(np.max(np.abs(dd))))
        inc = Δt * v.x.array[:n] + 0.5 * Δt**2 * a.x.array[:n] + 0.5 * p.beta2 * Δt**2 * dd
        du = max(du, float(np.max(np.abs(inc))))
        size = max(size, float(np.max(np.abs(u.x.array[:n] + inc))))
    if stepper.model.comm.size > 1:
        norms = np.array([e, du, size])
        stepper.model.comm.Allreduce(MPI.IN_PLACE, norms, op=MPI.MAX)
        e, du, size = (float(x) for x in norms)
    return e, du, size
