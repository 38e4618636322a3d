"""The initial state of a run: static equilibrium, bodies held up to t = 0, initial velocities.

The dynamics starts at t = 0 from a static equilibrium under gravity and the loads of
the initial state (every load at its value at t = 0 unless the case says otherwise,
:class:`~breakwater.config.runspec.InitialSpec`), at rest except for the bodies given an
initial velocity. :func:`initial_state` finds it in up to three stages:

1. **Frictionless** (:func:`breakwater.stepping.gn22.solve_static`). When it exists it is an
   exact equilibrium of the velocity-regularised friction law, which carries no shear
   at zero slip velocity: the dynamics then starts exactly at rest (the Goda case). It
   does not exist when a tangential force acts on a body held by contact (a block on
   an incline, a sustained side push): its Newton iteration then fails.
2. **Frictional.** First the interfaces are *bonded* (a tangential penalty spring
   ``k_b = ε_n`` in the residual: a nearly linear problem that always has a solution).
   A contact pair whose bonded tangential resultant exceeds μ times its normal
   resultant cannot be held by friction: it stays bonded (stage 3). On the other
   pairs the friction law of ``forms/contact.py`` (:class:`forms.ContactLaw`, the
   one the dynamics uses) acts on the slip *increment* from the unloaded state,
   divided by a pseudo time τ: ``t_T = −μ p φ(Δu_T/τ)``, as if the initial loads
   were applied over τ. τ is chosen so that the law's stick band is ``χτ = δ``, with
   ``δ`` = :data:`STICK_BAND` times the mean interface facet length (a slip far below
   anything the run resolves), and Newton uses the dynamics' slip guard
   (:mod:`breakwater.contact.slipguard`, with ``∂v/∂u = 1/τ``). The resulting state carries
   the shear by friction, with the bodies' elastic shear deformation in it; the
   dynamics then takes over with the velocity law, whose creep under a force below
   μN is ``v = χF/sqrt((μN)² − F²)``.
3. **Held.** A body on a pair that cannot hold it (no frictional equilibrium, e.g. a
   block on an incline steeper than the friction angle) is held in place up to t = 0
   by the bonding spring, with one warning naming it; at t = 0 the dynamics releases
   it (the spring is not in the dynamic residual) and it slides from rest. It is
   released in the state of incipient sliding (:func:`_release`): its pair's slave
   nodes slip at :data:`~breakwater.contact.conforming.RELEASE` χ along the sliding direction
   (the law then carries μp at t = 0), and its displacements are those of the body
   sliding as a rigid one with the acceleration that leaves (μN rather than the bonded
   shear at the interface, the inertia of that acceleration in the body). The stepper's
   a₀ is then that acceleration and GN22, exact for a constant acceleration, gives
   the rigid block's ½ a t² whatever Δt. Released at rest from the held state, the
   first step saw no friction (v = 0: a₀ frictionless, of which GN22 keeps
   (1 − β₁)Δt as a velocity error, +1.4 % of the slide at Δt = 1e-3) and the bonded
   shear's elastic release reversed slip velocities for a few steps.

Where some pair has friction, ``[initial] loading = "frictional"`` (the default,
:class:`~breakwater.config.runspec.InitialSpec`) starts at stage 2: gravity and the
initial loads are applied with friction active, so that nothing slides on the way to a
frictionless equilibrium (the Goda caisson's base corners slip ±0.021 mm in the
frictionless state, ±0.0007 mm in the frictional one). ``"frictionless"`` tries stage 1
first; stage 2 then runs only when stage 1 fails and some contact pair has friction.
Stage 3 runs only for the pairs that need it (or for every pair if the frictional
Newton fails). The Newton tolerance is ``[initial] tolerance`` (of the load norm, 1e-9
by default). No static state at all is an error (:class:`~breakwater.common.errors.
ConvergenceError`) naming ``[initial] undeformed``: with it set, the run starts from
the undeformed state at rest instead (``kind = "undeformed"``), without a static solve.

A model with general contact pairs (:mod:`breakwater.contact.general`) gets its state in
the same three stages from :func:`breakwater.statics.relaxation.relax` (pseudo-transient
relaxation with the fast solver: their forces are not UFL forms).
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common.errors import ConvergenceError
from breakwater.contact.conforming import (
    creep_velocities,
    interface_nodes,
    mean_facet_length,
    release_velocities,
)
from breakwater.contact.slipguard import SlipGuard
from breakwater.model.model import ContactModel, PairData
from breakwater.statics.relaxation import FALLBACK, no_state_advice, relax
from breakwater.statics.release import free_part
from breakwater.statics.rigidmodes import free_mode, joined, static_needed
from breakwater.stepping.gn22 import force_scale, solve_static, tangential_stiffness
from breakwater.stepping.solver import NewtonOptions, NewtonSolver

__all__ = ["STICK_BAND", "InitialState", "initial_state", "initial_velocities",
           "unsupported", "velocity_conflict"]

log = logging.getLogger("breakwater.statics.initial")

STICK_BAND = 1e-8
"""Stick band of the frictional static state, as a fraction of the mean interface facet
length: the slip below which the friction law is smooth (2.5e-10 m on a 25 mm
facet). Far below any displacement the run resolves, yet 1e3× wider than the band of a
GN22 step's Newton (χ·½β₂Δt²/(β₁Δt) ≈ 5e-15 m at χ = 1e-10 m/s, Δt = 1e-4 s)."""

BONDING = 1.0
"""Tangential spring of a bonded (or held) interface, as a multiple of the pair's ε_n."""


@dataclass
class InitialState:
    """The state the dynamics starts from.

    Attributes:
        u: Displacements (one Function per body).
        v: Initial velocities (one Function per body; zero at rest).
        iterations: Newton iterations of every static solve.
        kind: ``"frictionless"``, ``"frictional"`` or ``"held"`` (some body held in
            place up to t = 0); ``"undeformed"`` where the case asks for no static
            state (``[initial] undeformed``).
        held: Names of the bodies held in place up to t = 0 (released at t = 0).
        relaxation: With general pairs (:mod:`breakwater.statics.relaxation`): its
            ``pseudo_steps`` and wall time ``seconds``; else None.

    """

    u: list[fem.Function]
    v: list[fem.Function]
    iterations: int
    kind: str = "frictionless"
    held: list[str] = field(default_factory=list)
    relaxation: dict[str, float] | None = None

    def summary(self) -> dict[str, Any]:
        """The entries of the ``static`` summary that describe how the state was found."""
        out: dict[str, Any] = {"initial_state": self.kind, "held_bodies": list(self.held)}
        if self.relaxation is not None:
            out["relaxation_steps"] = int(self.relaxation["pseudo_steps"])
        return out


@contextlib.contextmanager
def _initial_loads(model: ContactModel) -> Iterator[None]:
    """Loads not in the initial state set to zero inside the block (restored after)."""
    keep = model.initial.loads
    saved = [float(ld.amplitude.value) for ld in model.loads]
    try:
        if keep is not None:
            for k, ld in enumerate(model.loads):
                if k not in keep:
                    ld.amplitude.value = 0.0
        yield
    finally:
        for ld, value in zip(model.loads, saved, strict=True):
            ld.amplitude.value = value


_AXES = "xyz"


def unsupported(model: ContactModel, calibrating: bool = False) -> str | None:
    """Why the static state cannot exist: a body held by nothing (None: every body is).

    The bodies that contact pairs join form groups; a group none of whose bodies has a
    ``[fixed]`` group is free to move as a whole, and has no static state under gravity
    or the initial state's loads (its static Newton failed after 40 iterations, and the
    run advised starting undeformed without saying why). With ``[initial] undeformed``
    or nothing loading it, it starts at rest (a free body may then fall or be struck).
    A group whose fixed groups leave a rigid mode free (rollers in x only): refused by
    :func:`~breakwater.statics.rigidmodes.free_mode`, naming the mode. With
    ``calibrating`` (a shear modulus to calibrate first) both are refused whatever the
    initial state: the calibration's stiffness is singular then.
    """
    static = static_needed(model)
    if not (static or calibrating):
        return None
    root = joined(model)
    held = {root[b.index] for b in model.bodies if model.fixed_on(b.spec.name)}
    for b in model.bodies:
        if root[b.index] not in held:
            touching = [o.spec.name for o in model.bodies
                        if o is not b and root[o.index] == root[b.index]]
            on = f" or on the bodies it touches ({', '.join(touching)})" if touching else ""
            why = ("so the calibration's stiffness is singular (add its contact pair or a "
                   "[fixed] group)" if calibrating else "so it has no static state under "
                   "gravity and the initial loads (add its contact pair or a [fixed] group, "
                   "or start it at rest undeformed: [initial] undeformed = true)")
            return (f"bodies.{b.spec.name}: the body is held by nothing: no [fixed] group "
                    f"on it{on}, {why}")
    return free_mode(model, calibrating) or (_nothing_beneath(model) if static else None)


def gravity_problem(model: ContactModel) -> str | None:
    """Why gravity leaves a body with nothing beneath it (None: it does not; collective).

    The build refuses it (:func:`unsupported`); ``run`` asks again, for a gravity set on
    the built model: ``model.gravity = (0.0, 9.81)`` failed in the static Newton after
    40 iterations, advising to leave the loads out or start undeformed.
    """
    return _nothing_beneath(model) if static_needed(model) else None


LEVEL = 1e-3
"""A body's contact interfaces are along gravity when the mean |n · g/|g|| over them all
is below this (their normals perpendicular to gravity, within 0.06°)."""


def _nothing_beneath(model: ContactModel) -> str | None:
    """A body whose contact interfaces all run along gravity or lie above it (None: none).

    A body without a ``[fixed]`` group whose conforming pairs (none pressed: gap ≥ 0)
    have no part beneath it, their normals perpendicular to gravity or the other body
    on the side gravity pulls away from, has nothing to carry its weight: a z-up mesh
    run with y-down gravity, or gravity given upwards (``[0, 9.81, 0]``); the static
    Newton failed after 40 iterations, advising to leave the loads out or start
    undeformed. Collective.
    """
    g = np.asarray(model.gravity.value, dtype=float)
    if not np.any(g) or not model.pairs:
        return None
    down = ufl.as_vector([float(v) for v in g / np.linalg.norm(g)])
    # Per body and pair: ∫ |n·ĝ|, the part of it beneath the body (∫ (n_out·ĝ)₊, n_out the
    # body's outward normal: the master's is n, the slave's −n) and the area.
    on: dict[int, list[tuple[str, float, float, float]]] = {}
    for p in model.pairs:
        if p.spec.gap < 0:
            continue
        level = model.assemble(model.form(abs(ufl.dot(p.n, down)) * p.dS))
        signed = model.assemble(model.form(ufl.dot(p.n, down) * p.dS))
        area = model.assemble(model.form(fem.Constant(model.mesh, 1.0) * p.dS))
        for b, sign in ((p.slave, -1.0), (p.master, 1.0)):
            beneath = 0.5 * (level + sign * signed)
            on.setdefault(b, []).append((p.spec.interface, level, beneath, area))
    # Pressed (a negative gap) or on a general pair: friction may carry it.
    held = {b for p in model.pairs if p.spec.gap < 0 for b in (p.slave, p.master)}
    held |= {b for s, m, _ in model.pair_bodies()[len(model.pairs):] for b in (s, m)}
    for b, pairs in on.items():
        body = model.bodies[b]
        if model.fixed_on(body.spec.name) or b in held:
            continue
        area = sum(a for *_, a in pairs)
        names = ", ".join(f"'{n}'" for n, *_ in pairs)
        gravity = tuple(float(v) for v in g)
        if area > 0 and sum(v for _, v, _, _ in pairs) < LEVEL * area:
            return (f"bodies.{body.spec.name}: nothing beneath it: its contact interfaces "
                    f"({names}) all run along gravity {gravity}, so no "
                    "contact carries its weight: a mesh drawn with z up? breakwater is y "
                    "up: rotate it, (x, y, z) -> (x, z, -y) (gmsh's affineTransform), or "
                    "start it at rest undeformed ([initial] undeformed = true)")
        if area > 0 and sum(v for _, _, v, _ in pairs) < LEVEL * area:
            up = gravity[1] > 0 and not any(gravity[k] for k in range(len(gravity)) if k != 1)
            return (f"bodies.{body.spec.name}: nothing beneath it: gravity {gravity} pulls "
                    f"it off its contact interfaces ({names}), so no contact carries its "
                    "weight: "
                    + ("gravity points up? breakwater is y up: gravity = "
                       f"[0.0, {-gravity[1]:g}{', 0.0' if len(gravity) == 3 else ''}]"
                       if up else "check gravity's direction")
                    + " (or start it at rest undeformed: [initial] undeformed = true)")
    return None


def velocity_conflict(model: ContactModel, body: str, velocity: Sequence[float]) -> str | None:
    """Why a uniform initial velocity contradicts a body's fixed boundaries (None: it does not).

    A fixed boundary holds its displacement components at zero for all time, so their
    velocity is zero at t = 0 too: a uniform velocity with a component along a fixed one
    starts the body with a velocity jump at that boundary (the stepper zeroes the fixed
    DOFs' increments, and the energy ledger counts a kinetic energy that no force put
    in). A component along a free direction (a roller) is consistent.
    """
    for group, comps in model.fixed_on(body):
        held = [c for c in comps if velocity[c] != 0.0]
        if held:
            axes = ", ".join(_AXES[c] for c in held)
            shown = ", ".join(f"{x:g}" for x in velocity)
            return (f"body '{body}' is fixed in {axes} on '{group}', so its initial velocity "
                    f"[{shown}] m/s cannot have a {axes} component (give it only along the "
                    "free components, or remove the fixed boundary)")
    return None


def initial_velocities(model: ContactModel) -> list[fem.Function]:
    """The bodies' uniform initial velocities (``model.initial.velocities``; else zero).

    Raises:
        ValueError: A velocity along a component that a fixed boundary of the body holds
            (:func:`velocity_conflict`).
    """
    v = model.functions("v_initial")
    for f, b in zip(v, model.bodies, strict=True):
        vel = model.initial.velocity(b.spec.name)
        if vel is not None:
            why = velocity_conflict(model, b.spec.name, vel)
            if why is not None:
                raise ValueError(why)
            f.x.array.reshape(-1, model.gdim)[:] = np.asarray(vel, dtype=float)
    return v


def initial_state(model: ContactModel, options: NewtonOptions | None = None) -> InitialState:
    """The static initial state under gravity and the loads of the initial state (collective).

    Call it with the loads at t = 0 (``model.set_time(0.0)``). See the module docstring.

    Args:
        model: The contact model (``model.initial`` says which loads are in the state
            and the initial velocities).
        options: Newton settings of the static solves.

    Returns:
        The initial state.

    Raises:
        ConvergenceError: No static state could be found (not even with the bodies
            held).
    """
    spec = model.initial
    if spec.undeformed:
        log.info("initial state: undeformed, at rest ([initial] undeformed = true)")
        return InitialState(model.functions("u"), initial_velocities(model), 0, "undeformed")
    o = options or NewtonOptions()
    options = replace(o, atol=min(o.atol, spec.tolerance),
                      floor_atol=min(o.floor_atol, spec.tolerance))
    with _initial_loads(model):
        if model.surface_pairs:
            v = initial_velocities(model)
            r = relax(model, v, STICK_BAND, options, spec.tolerance, spec.loading)
            return InitialState(r.u, v, r.iterations, r.kind, r.held,
                                {"pseudo_steps": r.steps, "seconds": r.seconds})
        frictional = spec.loading == "frictional" and any(
            float(p.law.friction.μ.value) > 0 for p in model.pairs)
        try:
            if frictional:
                state = _frictional(model, options, 0)
            else:
                try:
                    u, its = solve_static(model, options=options)
                    state = InitialState(u, initial_velocities(model), its)
                except ConvergenceError as e:
                    if not model.pairs:
                        raise
                    log.debug("no frictionless static state (%s): solving with friction", e)
                    if model.comm.rank == 0:
                        log.warning(FALLBACK)
                    try:
                        state = _frictional(model, options, e.iterations)
                    except (ConvergenceError, PETSc.Error) as f:
                        raise ConvergenceError(f"{e}; with friction: {f}", e.reason,
                                               e.iterations + getattr(f, "iterations", 0)
                                               ) from f
        except (ConvergenceError, PETSc.Error) as e:
            raise ConvergenceError(
                f"initial state: no static equilibrium ({e}); {no_state_advice(model)}",
                getattr(e, "reason", -1), getattr(e, "iterations", 0)) from e
    return state


def _bonded_term(pair: PairData, u: Sequence, w: Sequence, k: float) -> ufl.Form:
    """A tangential spring ``k`` between the two sides of a pair, ∫ k Δu_T·δw_T dS."""
    jump = forms.tangential_part(u[pair.slave]("+") - u[pair.master]("-"), pair.n)
    δw = forms.tangential_part(w[pair.slave]("+") - w[pair.master]("-"), pair.n)
    return k * ufl.dot(jump, δw) * pair.dS


def _resultants(model: ContactModel, pair: PairData, u: Sequence[fem.Function],
                k: float) -> tuple[float, np.ndarray]:
    """Normal resultant ∫p and tangential resultant ∫k Δu_T of a bonded pair (N/m).

    The tangential resultant is the spring's pull on the master: the direction in
    which the shear pushes the slave.
    """
    us, um = u[pair.slave]("+"), u[pair.master]("-")
    normal = model.assemble(model.form(pair.law.pressure(us, um, pair.n) * pair.dS))
    t_T = k * forms.tangential_part(us - um, pair.n)
    shear = [model.assemble(model.form(t_T[i] * pair.dS)) for i in range(model.gdim)]
    return normal, np.array(shear)


def _solve(model: ContactModel, F: ufl.Form, u: list[fem.Function], options: NewtonOptions | None,
           stabilise: Sequence[PairData], precheck: Any = None) -> int:
    """Newton on F with the Jacobian-only weak tangential spring of ``solve_static``."""
    F_t = F
    for p in stabilise:
        F_t += _bonded_term(p, u, model.w, 1e-2 * tangential_stiffness(model, p))
    solver = NewtonSolver(model, F, u, "initial", options, force_scale(model), precheck=precheck,
                          jacobian_of=F_t)
    try:
        return solver.solve()
    finally:
        solver.destroy()


def _frictional(model: ContactModel, options: NewtonOptions | None, tried: int) -> InitialState:
    """Stages 2 and 3 of the module docstring."""
    pairs = model.pairs
    k_b = [BONDING * float(p.ε_n.value) for p in pairs]
    # The bonded state: from a small penetration along gravity (as solve_static).
    u = model.functions("u")
    g = model.gravity.value
    if np.any(g):
        for p in pairs:
            u[p.slave].x.array.reshape(-1, model.gdim)[:] = 1e-9 * g / np.linalg.norm(g)
    bulk = model.bulk_residual(u)
    normal = [forms.contact_residual(model.traction(p, u, None), model.w[p.slave]("+"),
                                     model.w[p.master]("-"), p.dS) for p in pairs]
    bonded = bulk + sum(n + _bonded_term(p, u, model.w, k)
                        for n, p, k in zip(normal, pairs, k_b, strict=True))
    its = tried + _solve(model, bonded, u, options, ())
    # The pairs that friction cannot hold: bonded tangential resultant above μN.
    hold = []
    for p, k in zip(pairs, k_b, strict=True):
        N, shear = _resultants(model, p, u, k)
        T, μ = float(np.linalg.norm(shear)), float(p.law.friction.μ.value)
        if T - μ * N > 1e-6 * max(N, T):
            hold.append((p, N, shear, μ))
    held_pairs = {id(p) for p, *_ in hold}
    free = [p for p in pairs if id(p) not in held_pairs]
    v = initial_velocities(model)
    τ = 0.0
    if free:
        u_bonded = [f.x.array.copy() for f in u]
        try:
            n, τ = _friction_solve(model, u, options, free, k_b, bulk, normal)
            its += n
            creep_velocities(model, free, u, v, τ)
        except ConvergenceError as e:
            # No frictional equilibrium on the remaining pairs: hold them all.
            log.debug("no frictional static state (%s): every pair held", e)
            its += e.iterations
            for f, x in zip(u, u_bonded, strict=True):
                f.x.array[:] = x
            for p in free:
                N, shear = _resultants(model, p, u, BONDING * float(p.ε_n.value))
                hold.append((p, N, shear, float(p.law.friction.μ.value)))
            free = []
    if hold:
        its += _release(model, u, v, options, [(p, d) for p, _, d, _ in hold], free, τ)
    held: list[str] = []
    for p, N, shear, μ in hold:
        T = float(np.linalg.norm(shear))
        body = model.bodies[p.slave].spec.name
        if model.comm.rank == 0:
            unit = "N" if model.gdim == 3 else "N/m"  # (3D: the whole body's; was N/m)
            log.warning("initial state: body '%s' cannot be held by friction on '%s' "
                        "(tangential force %.4g %s, μN = %.4g %s): held in place up to "
                        "t = 0 and released at t = 0", body, p.spec.interface, T, unit,
                        μ * N, unit)
        if body not in held:
            held.append(body)
    return InitialState(u, v, its, "held" if held else "frictional", held)


def _friction_solve(model: ContactModel, u: list[fem.Function], options: NewtonOptions | None,
                    free: Sequence[PairData], k_b: Sequence[float], bulk: ufl.Form,
                    normal: Sequence[ufl.Form]) -> tuple[int, float]:
    """The frictional static solve, from the bonded state in ``u`` (stage 2).

    Returns:
        The Newton iterations and the pseudo time τ.
    """
    free_ids = {id(p) for p in free}
    # One pseudo time: every free pair's stick band χτ is at most STICK_BAND × its facet
    # length, and the slip guard sees the same velocities v = u/τ for every pair.
    τ = min(STICK_BAND * mean_facet_length(model, p) / float(p.law.friction.χ.value)
            for p in free)
    v = [f / τ for f in u]
    F = bulk
    for k, p in enumerate(model.pairs):
        if id(p) in free_ids:  # the law of the dynamics, slip increment over τ as velocity
            F += forms.contact_residual(model.traction(p, u, v), model.w[p.slave]("+"),
                                        model.w[p.master]("-"), p.dS)
        else:
            F += normal[k] + _bonded_term(p, u, model.w, k_b[k])
    guard = SlipGuard([n for n in interface_nodes(model) if id(n.pair) in free_ids])
    step = model.functions("initial_step")

    def precheck(x: PETSc.Vec, y: PETSc.Vec) -> None:
        y.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        fem_petsc.assign(y, step)
        fem_petsc.assign(x, u)
        if guard([f.x.array / τ for f in u], [f.x.array for f in step], 1.0 / τ):
            fem_petsc.assign(step, y)

    return _solve(model, F, u, options, free, precheck), τ


def _release(model: ContactModel, u: list[fem.Function], v: list[fem.Function],
             options: NewtonOptions | None, held: Sequence[tuple[PairData, np.ndarray]],
             free: Sequence[PairData], τ: float) -> int:
    """Stage 3's start: the held bodies in the state of incipient sliding (collective).

    Each held pair's slave nodes get the slip velocity :data:`~breakwater.contact.conforming.
    RELEASE` χ along the body's sliding direction d (the held pairs' shear
    resultant less its components along the directions the body's ``[fixed]`` groups
    hold, :func:`~breakwater.statics.release.free_part`, as the general pairs': before,
    a block on rollers released with a velocity along them and α off by d_z²), so
    that the law carries the friction of sliding, μp, at t = 0. The displacements are
    then solved for the state in which the body slides as a rigid
    one: the held pairs carry that friction, each held slave body has the uniform
    acceleration α d, α from the body's resultant along d (updated at every Newton
    iterate, so that the residual never drives its free rigid mode along d, which the
    Jacobian holds with the weak spring of :func:`_solve`), the free pairs keep the
    law of stage 2. The dynamics then starts in that motion: ``GN22.initialise``'s a₀
    is α d on the body, and a rigid block slides ½ α t² from t = 0. From the held
    state instead (its bonded shear, not μp), an elastic body starts with the wave of
    the shear's release, whose slip-velocity reversals carry less than μN for the
    first steps. If the Newton fails, the held state is kept (with the velocities).

    Returns:
        The Newton iterations.
    """
    bodies: dict[int, np.ndarray] = {}
    for p, shear in held:
        bodies[p.slave] = bodies.get(p.slave, 0.0) + shear
    for i in list(bodies):  # less what its [fixed] groups hold (as the general pairs')
        bodies[i] = free_part(model, i, bodies[i])
        if not np.any(bodies[i]):  # held along all of it: no slide
            del bodies[i]
    pairs = [p for p, _ in held]
    moving = [p for p in pairs if p.slave in bodies]
    release_velocities(model, moving, [bodies[p.slave] / np.linalg.norm(bodies[p.slave])
                                       for p in moving], v)
    held_ids = {id(p) for p in pairs}
    v_τ = [f / τ for f in u] if free else None
    F = model.bulk_residual(u)
    traction = []
    for p in model.pairs:
        t = model.traction(p, u, v if id(p) in held_ids else v_τ)
        traction.append(t)
        F += forms.contact_residual(t, model.w[p.slave]("+"), model.w[p.master]("-"), p.dS)
    updates = []
    for i, shear in bodies.items():
        b = model.bodies[i]
        d = fem.Constant(model.mesh, np.asarray(shear / np.linalg.norm(shear)))
        a = fem.Constant(model.mesh, np.zeros(model.gdim))
        F += forms.inertia(b.ρ, a, model.w[i], b.dx)
        # The body's resultant along d without its inertia: gravity, loads, contacts.
        force = forms.body_force(b.ρ, model.gravity, d, b.dx)
        for ld in model.loads:
            if ld.body == i:
                force += forms.surface_traction(ld.traction, d, ld.ds)
        for p, t in zip(model.pairs, traction, strict=True):
            if i in (p.slave, p.master):
                force += (1.0 if i == p.slave else -1.0) * ufl.dot(t, d) * p.dS
        mass = model.assemble(model.form(b.ρ * b.dx))
        updates.append((a, d, model.form(force), mass))

    def accelerate() -> None:
        for a, d, force, mass in updates:
            a.value = model.assemble(force) / mass * d.value

    guard = SlipGuard([n for n in interface_nodes(model) if id(n.pair) not in held_ids])
    step = model.functions("release_step")

    def precheck(x: PETSc.Vec, y: PETSc.Vec) -> None:
        y.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        fem_petsc.assign(x, u)
        accelerate()
        if free:
            fem_petsc.assign(y, step)
            if guard([f.x.array / τ for f in u], [f.x.array for f in step], 1.0 / τ):
                fem_petsc.assign(step, y)

    accelerate()
    held_state = [f.x.array.copy() for f in u]
    try:
        return _solve(model, F, u, options, pairs, precheck)
    except (ConvergenceError, PETSc.Error) as e:
        log.debug("no state of incipient sliding (%s): released from the held state", e)
        for f, x in zip(u, held_state, strict=True):
            f.x.array[:] = x
        return getattr(e, "iterations", 0)
