"""The static initial state of a model with general contact pairs: pseudo-transient relaxation.

A general pair's forces (:class:`~breakwater.contact.general.SurfaceContact`) are not UFL
forms, and a body held only by contact has a singular stiffness, so the Newton of
:func:`breakwater.stepping.gn22.solve_static` does not apply. The static state is found instead
with the fast solver's own machinery (:mod:`breakwater.stepping.condensed`, every pair's forces
and exact Jacobian on the interface unknowns, the bulk factorised once per step size):
repeated GN22 steps from rest, each a *mass-regularised Newton step* of the static
problem. With u₀ = u_k and the state at rest, a step of pseudo size Δτ solves

    M (u − u_k)/c + K u + f_c(u) = f,        c = ½β₂Δτ²,

(a proximal-point iteration: the fixed point u = u_k is the static equilibrium). The
mass keeps a rigid mode held only by contact regular; a linear mode of frequency ω
contracts by 1/(1 + cω²) per step. c grows ×:data:`GROWTH` per step, up to
``c_max = RATIO/ω_min²`` (ω_min² estimated as the smallest of E/(ρL²) per body and
ε_n/(ρL) per pair's slave, L the body's bounding-box diagonal: a lower bound of the
lowest frequencies), from ``c₀ = 0.1 r/|g|`` (r the contact search radius, or the
interface facet length), so that a body that starts apart moves at most a tenth of the
search radius per step and cannot fall through its support; c grows only while the
increments stay below half that. A step in which a pair's gap closes by more than half
the increment (a body falling onto its support) is progress: neither a stalled step nor
one of :data:`MAX_STEPS`, so that a body lands from up to
:data:`~breakwater.statics.pseudostep.LANDING` search radii (before, a stage failed
after :data:`STALL` steps of free fall: a block meshed more than half a facet above its
support had "no static equilibrium"). Converged when the static residual at the new iterate,
``‖M (u − u_k)‖/c``, is below the tolerance (``[initial] tolerance``, default
:data:`TOLERANCE`: a time step's Newton tolerance) times the load norm ‖f‖; the steps'
Newton converges to it too, or stalls at its round-off below :data:`FLOOR` times the
load norm (accepted: the static residual, which each step measures, decides; a body
held by contact between two others, a block on a block on a base meshed apart, stalled
at 6.6e-9 of the load, above the 1e-9 asked, and had "no static equilibrium").
Damping is switched off (a static state carries none).

The pseudo steps are exact, so that the state is the equilibrium to that tolerance
whatever the penalty: the bulk balances the interface Newton's iterate
(:attr:`~breakwater.stepping.condensed.CondensedNewton.consistent`; without it the
state of the non-matching patch test was off by 4.3e-8 p in σ at ε_n = 1e10 and 4.8e-5 p
at 1e12, in the block held by contact: the Newton's residual G, measured in force by
the Schur complement, which is only the mass along the block's rigid modes, left
A_BI G in its bulk rows), each step's Newton starts at u₁ = u_k (not at GN22's
predictor, a move of the size of u_k: :meth:`~breakwater.statics.pseudostep.PseudoStepper.
start`), and each step starts in defect form (the contact forces at
its start moved into the load, :meth:`~breakwater.statics.pseudostep.PseudoStepper.
start`: the predictor's residual is then the static residual itself).

Stages, as :mod:`breakwater.statics.initial` for conforming pairs (and for every pair of a
model with both kinds). Where some pair has friction, ``[initial] loading =
"frictional"`` (the default) goes to stage 2 directly: gravity and the initial loads
are applied with friction active, so that no frictionless slide happens on the way (a
block free along its support slid 1.3e-5 m in the frictionless state of the patch test
with μ = 0.3, and the Goda caisson's corners ±0.021 mm); ``"frictionless"`` tries
stages 1 and 1b first:

1. **Frictionless** (friction off): an exact equilibrium of the velocity law at rest.
   It does not exist under a tangential force (a block on an incline): the body then
   slides by the same amount every step, and a stage whose increments do not halve over
   :data:`STALL` steps at one c (or that exceeds :data:`MAX_STEPS`) fails.
   1b. **Nearly frictionless** (if stage 1 fails and some pair has friction): every
   pair's friction coefficient set to :data:`RESIDUAL_FRICTION` for stage 1's steps
   (from rest: the friction acts on each step's slip increment, so it vanishes as the
   increments do, but arrests the rigid drift at the law's creep). The closest-point
   kinematics press along the *deformed* master
   normal, so a frictionless body on a deformed support carries a tangential
   out-of-balance of the discretisation (1e-6 of the load on the Goda caisson, whose
   crest the caisson deforms unevenly) and its rigid tangential mode slides away; a
   friction of 1e-4 μp holds it. The state is the frictionless one to that fraction (on
   the Goda mesh the corner's static slip is the conforming frictionless state's to
   0.3 %); the dynamics starts from it at rest, as from stage 1 (``kind = "frictionless"``).
2. **Frictional** (if some pair has friction): the friction law acts on the total slip
   from the unloaded state over a pseudo time τ (``v = u/τ``, as ``initial.py`` stage
   2), with τ such that the stick band χτ is ``stick_band``
   (:data:`breakwater.statics.initial.STICK_BAND`) times the interface facet length. The step's
   velocity is set up for it: with u₀ = u_k, the GN22 start (v₀, a₀) is chosen so that
   ``c a₁ = u₁ − u_k`` (the mass term above) and ``v₁ = u₁/τ``, and β₁ = ½β₂Δτ_max/τ (τ
   at c_max; smaller c give a smaller τ, a narrower stick band, until c settles). The
   slave nodes in contact start with the slip velocity carrying that friction (``start_slip``;
   along a component a ``[fixed]`` group holds, their master's nodes move). The slip is
   measured from the landing point, not from the meshed position
   (:class:`~breakwater.statics.pseudostep.SlipOrigin`): a body meshed above its support
   does not count its fall as slip.
3. **Held** (stage 2 fails, or no friction): every pair's friction coefficient is
   raised to :data:`HELD_FRICTION` for the relaxation (the bodies are held in place up
   to t = 0); a warning names each body whose pair carries a tangential resultant
   above μN, and the dynamics, with the real μ, releases it at t = 0. It is released
   in the state of incipient sliding (:func:`_slide`; models with general
   pairs only): pseudo steps with the real μ from the held state, in the frame of the
   body's acceleration α d (d its sliding direction, α from its resultant along d),
   so that its pairs carry the friction of sliding and its deformation is that of the
   sliding body, not the held state's shear (whose release, in an elastic body,
   reversed slip velocities at the first steps: +1.3 % of the slide of a pushed block
   with E = 1e9 at Δt = 1e-3). Its slave nodes then start sliding at :data:`RELEASE` χ
   along their tangent in the sliding direction (1e-8 m/s at the paper's χ: from
   rest), those with a held component too (:mod:`breakwater.statics.release`), where
   the law carries μλ: the first step sees the friction of sliding
   (with v = 0 it would see none, a₀ would be F/m instead of (F − μN)/m, and GN22
   would keep (1 − β₁)Δt times the difference as a velocity error).

If even the held state does not relax (a body that starts too far from its support to
land within the relaxation, more than :data:`~breakwater.statics.pseudostep.LANDING`
search radii: the error says so and how far; a body pulled off its support), there is
no static state: an error (:class:`~breakwater.common.errors.
ConvergenceError`) that names ``[initial] undeformed``, the key that starts the run from
the undeformed state at rest (:func:`breakwater.statics.initial.initial_state`). Before,
the run went on from the undeformed state with one warning.

:func:`relax` is called by :func:`breakwater.statics.initial.initial_state` for models with
general pairs; a₀ of the stepper's initialisation then vanishes (it includes the
general pairs' forces). This module is the control of the stages (c over the steps,
:func:`_stage`, :func:`_slide`) and the frictional state's initial velocities
(:func:`_creep`); the held bodies and their release are :mod:`breakwater.statics.release`'s
(:func:`~breakwater.statics.release.held_bodies`,
:func:`~breakwater.statics.release.release`); the pseudo step itself, its state and
the model estimates (c₀, c_max, τ) are :class:`~breakwater.statics.pseudostep.PseudoStepper`'s.
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import math
import time
from collections.abc import Iterator

import numpy as np
from dolfinx import fem

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common.errors import ConvergenceError
from breakwater.contact import friction3d
from breakwater.contact.conforming import RELEASE, creep_velocities
from breakwater.contact.general import start_slip
from breakwater.model.model import ContactModel, Damping
from breakwater.statics.pseudostep import (
    FALL,
    GROWTH,
    LANDING,
    NONE_HELD,
    RATIO,
    PseudoStepper,
    no_state_advice,
)
from breakwater.statics.release import HELD_FRICTION, held_bodies, moving_body, release
from breakwater.stepping.solver import NewtonOptions

__all__ = ["FALLBACK", "FLOOR", "GROWTH", "HELD_FRICTION", "MAX_STEPS", "RATIO", "RELEASE",
           "RESIDUAL_FRICTION", "STALL", "TOLERANCE", "Relaxed", "no_state_advice", "relax"]

log = logging.getLogger("breakwater.statics.relaxation")

TOLERANCE = 1e-9
"""Default static residual ‖f − K u − f_c(u)‖ of the state, as a fraction of ‖f‖.

A time step's Newton tolerance (``NewtonOptions.atol``); the case's ``[initial] tolerance``.
The pseudo steps are exact (:attr:`breakwater.stepping.condensed.CondensedNewton.consistent`):
the state's residual is the last step's ‖M (u₁ − u_k)‖/c plus its Newton's, whose
tolerances are set to this too."""

RESIDUAL_FRICTION = 1e-4
"""Friction coefficient of the nearly frictionless stage (1b in the module doc)."""

#: The warning of a frictionless initial state asked for and not found (both kinds of pair).
FALLBACK = ("initial state: no frictionless static equilibrium ([initial] loading = "
            "\"frictionless\"): the frictional one is used, gravity and the initial loads "
            "applied with friction active (static.initial_state = \"frictional\")")

MAX_STEPS = 100
"""Pseudo steps allowed per stage."""

STALL = 4
"""A stage fails when its increment has not halved over this many steps at one c."""

FLOOR = 1e-7
"""The pseudo steps' Newton accepts a stall below this fraction of the load norm as its
round-off (the stall test of :func:`breakwater.stepping.solver.convergence_reason`)."""

@dataclasses.dataclass
class _Result:
    """One stage's outcome."""

    u: list[np.ndarray]
    steps: int
    iterations: int


def _stage(ps: PseudoStepper, frictional: bool) -> _Result:
    """Relax from the undeformed state (a 1e-9 m penetration along gravity).

    c grows ×:data:`GROWTH` per step up to c_max while the increments stay below half
    the free fall's at c₀ (:data:`~breakwater.statics.pseudostep.FALL` search radius); a
    failed step after a grown one is retried at a tenth of it, and c grows back only
    after a stall could be found below it (:data:`STALL` + 1 steps). A step in which some
    pair's gap closes by more than half the increment (a body falling onto its support)
    is progress: it is not counted as a stalled step nor in :data:`MAX_STEPS`; a body
    lands from at most :data:`~breakwater.statics.pseudostep.LANDING` search radii.

    Raises:
        ConvergenceError: A step's Newton failed, or the increments do not vanish.
    """
    m, s = ps.model, ps.stepper
    for u in s.u:
        u.x.array[:] = 0.0
    g = m.gravity.value
    if np.any(g):
        # The bodies that move onto their support (a slave with a [fixed] group, its
        # master free: the master; the offset on a fixed body's Dirichlet entries made
        # the swapped pair's steps drift, 4.9e-11 m growing 4 % per step: no state).
        slaves = {m.body(moving_body(m, p)).index for p in m.surface_pairs}
        slaves |= {p.slave for p in m.pairs}
        for i in slaves:
            s.u[i].x.array.reshape(-1, m.gdim)[:] = 1e-9 * g / np.linalg.norm(g)
    c, its = ps.c0, 0
    history: list[tuple[float, float]] = []  # (c, max|Δu|) of the steps since progress
    solved = 0.0  # c of the last solved step
    failed, since = math.inf, 0  # the last c that failed, the steps solved since
    gaps = ps.gaps()
    k = falls = 0  # steps, and those of a fall (not counted in MAX_STEPS)
    while k - falls < MAX_STEPS and falls < LANDING / FALL:
        k += 1
        ps.start(c, frictional)
        try:
            its += s.solve()
        except ConvergenceError as e:
            if c > solved > 0:
                # A grown step overshot the contact state: retry at a tenth of it
                # (not below the last c that converged); u_k is unchanged.
                its += e.iterations
                log.debug("relaxation step %d: c = %.3e s² failed, retried at %.3e s²",
                          k, c, max(solved, c / 10))
                failed, since = c, 0
                c = max(solved, c / 10)
                continue
            raise ConvergenceError(f"relaxation step {k}: {e}", e.reason,
                                   its + e.iterations) from e
        solved, since = c, since + 1
        inc, residual = ps.advance(c)
        log.debug("relaxation step %d: c = %.3e s², max|Δu| = %.3e m, residual %.3e, "
                  "%d Newton iterations", k, c, inc, residual / ps.scale, its)
        if residual <= ps.tolerance * ps.scale:
            ps.c = c
            return _Result([u.x.array.copy() for u in s.u], k, its)
        before, gaps = gaps, ps.gaps()
        if any(0 < g0 and g0 - g1 > 0.5 * inc for g0, g1 in zip(before, gaps, strict=True)):
            # A body falling onto its support (its gap closes by the increment): progress.
            falls += 1
            history.clear()
            continue
        history.append((c, inc))
        same = history[-STALL - 1:]
        if len(same) > STALL and all(h[0] == c for h in same) and inc > 0.5 * same[0][1]:
            break
        if inc < 0.5 * FALL * ps.reach:
            # Not at c₀'s free fall (FALL r per step: whether it is below FALL r is
            # round-off, which differed between serial and 2 ranks).
            grown = min(c * GROWTH, ps.c_max)
            # Not back to a failed c before a stall below it could be found (the Goda caisson
            # meshed apart retried c_max after every success: 392 Newton iterations, now 157).
            c = c if grown >= failed and since <= STALL else grown
    left = residual / ps.scale
    why = (f"; its residual stalled at {left:.1e} of the load, above [initial] tolerance = "
           f"{ps.tolerance:g}: raise it if that is round-off" if left < 1e-6 else "")
    raise ConvergenceError(f"relaxation: no static state (max|Δu| = {inc:.3e} m after "
                           f"{k} steps{why}{_open(ps, gaps)})", -1, its)


def _open(ps: PseudoStepper, gaps: list[float]) -> str:
    """The pairs still open at a failed stage's end, and how far (for its message)."""
    out = []
    for p, gap in zip(ps.providers, gaps, strict=True):
        if gap > 0:
            reach = LANDING * p.radius
            where = (f"{gap:.3g} m from" if np.isfinite(gap) else
                     f"farther than {reach:.3g} m ({LANDING:g} search radii) from")
            out.append(f"'{p.spec.slave}' still {where} its master surface on "
                       f"'{p.spec.name}' (the relaxation lands a body from at most "
                       f"{reach:.3g} m: mesh it closer to its support)")
    return "; " + "; ".join(out) if out else ""


def _slide(ps: PseudoStepper, sliding: dict[int, np.ndarray]) -> int:
    """Relax the held bodies (``sliding``) into the state of incipient sliding.

    The held stage's friction (μ = :data:`HELD_FRICTION`) carries the bonded shear;
    released, the body slides with the friction μλ and the acceleration α d (d the
    sliding direction, α from its resultant). Pseudo steps with the real μ from the
    held state, each started with a₀ = α d and v₀ = −½Δτ α d on the body (so that
    u₁ − u_k = c Δa: the static residual of the stage, in the frame of the body's
    acceleration, and v₁ ≈ ½Δτ α d, far above χ: the friction of sliding), α updated
    after each step from the body's resultant along d. As :func:`breakwater.statics.initial.
    _release` for conforming pairs: GN22 then starts in the motion of sliding.

    Args:
        ps: The pseudo stepper, in the held state.
        sliding: Held slave body → its sliding direction
            (:func:`~breakwater.statics.release.held_bodies`).

    Returns:
        The Newton iterations.

    Raises:
        ConvergenceError: A step failed or the steps did not converge.
    """
    m, s = ps.model, ps.stepper
    c, its = ps.c / GROWTH**2, 0
    bodies = []
    for i, total in sliding.items():
        b = m.bodies[i]
        d = total / np.linalg.norm(total)
        dc = fem.Constant(m.mesh, d)
        force = forms.body_force(b.ρ, m.gravity, dc, b.dx)
        for ld in m.loads:
            if ld.body == i:
                force += forms.surface_traction(ld.traction, dc, ld.ds)
        ext = m.assemble(m.form(force))
        mass = m.assemble(m.form(b.ρ * b.dx))
        # Its pairs (a master that slides on a fixed slave counts the pair's force
        # with the sign reversed), at first the held state's pressure with the
        # friction of sliding against d.
        slaves = [(p, 1.0 if m.body(p.spec.slave).index == i else -1.0)
                  for p in ps.providers if m.body(moving_body(m, p.spec)).index == i]
        contact = 0.0
        for p, sign in slaves:
            normal, _ = p.resultants(accepted=True)
            contact += sign * float(normal @ d) - p.spec.friction * float(np.linalg.norm(normal))
        bodies.append([i, d, ext, mass, slaves, (ext + contact) / mass])
    with ps.friction(None):
        for k in range(1, MAX_STEPS + 1):
            ps.start(c, False)
            Δτ = float(s.dt.value)
            for i, d, _, _, _, α in bodies:
                s.v[i].x.array.reshape(-1, m.gdim)[:] = -0.5 * Δτ * α * d
                s.a[i].x.array.reshape(-1, m.gdim)[:] = α * d
            its += s.solve()
            for body in bodies:
                i, d, ext, mass, slaves, _ = body
                contact = sum(sign * float(p.resultant(accepted=False) @ d)
                              for p, sign in slaves)
                body[5] = (ext + contact) / mass
            inc, residual = ps.advance(c)
            log.debug("sliding step %d: max|Δu| = %.3e m, residual %.3e, α = %s", k, inc,
                      residual / ps.scale, [b[5] for b in bodies])
            if residual <= ps.tolerance * ps.scale:
                return its
            c = min(c * GROWTH, ps.c)
    raise ConvergenceError(f"relaxation: no state of incipient sliding after {k} steps",
                           -1, its)


def _creep(ps: PseudoStepper, v: list[fem.Function]) -> None:
    """Add the frictional state's slip velocities (``start_slip``'s) to ``v``."""
    s = ps.stepper
    frozen = [p._step_frozen for p in ps.providers]  # the last step's, before rest()
    ps.rest()
    y = np.zeros(ps.solver.n)
    for p, step in zip(ps.providers, frozen, strict=True):
        pos, v_T = (friction3d.start_slip(p, step) if ps.model.gdim == 3
                    else start_slip(p, step))
        y[pos] = v_T
    ps.add_slave_velocities(v, y)
    if ps.model.pairs:
        u = [fem.Function(f.function_space) for f in s.u]
        for f, g in zip(u, s.u, strict=True):
            f.x.array[:] = g.x.array
        τ = 0.5 * ps.β2 * float(s.dt.value) / ps.β1  # τ of the last step
        creep_velocities(ps.model, ps.model.pairs, u, v, τ)


@contextlib.contextmanager
def _undamped(model: ContactModel) -> Iterator[None]:
    """No Rayleigh damping inside the block (a static state carries none)."""
    saved = model.damping
    model.damping = Damping()
    try:
        yield
    finally:
        model.damping = saved


@dataclasses.dataclass
class Relaxed:
    """The static state a relaxation found.

    Attributes:
        u: Displacements (one Function per body).
        iterations: Newton iterations of every pseudo step.
        kind: ``"frictionless"``, ``"frictional"`` or ``"held"``
            (module docstring).
        held: Names of the bodies held in place up to t = 0.
        steps: Pseudo steps, over every stage.
        seconds: Wall time.
    """

    u: list[fem.Function]
    iterations: int
    kind: str
    held: list[str]
    steps: int
    seconds: float


def relax(model: ContactModel, v: list[fem.Function], stick_band: float,
          options: NewtonOptions | None = None, tolerance: float = TOLERANCE,
          loading: str = "frictional") -> Relaxed:
    """The static initial state of a model with general pairs (collective; module doc).

    Call it with the loads of the initial state at t = 0
    (:func:`breakwater.statics.initial.initial_state` does).

    Args:
        model: The contact model.
        v: The initial velocities; the slave nodes' creep (frictional) or release
            (held) velocities are added to them.
        stick_band: The frictional state's stick band χτ, as a fraction of the mean
            slave facet length (:data:`breakwater.statics.initial.STICK_BAND`).
        options: Newton settings of the pseudo steps (their ``atol`` and
            ``floor_atol``: ``tolerance`` and :data:`FLOOR`).
        tolerance: The static residual, as a fraction of the load norm.
        loading: ``"frictional"``: with friction on some pair, the frictional stage
            only (then held); ``"frictionless"``: the frictionless stages first.

    Raises:
        ConvergenceError: No static state, not even with the bodies held.
    """
    t0 = time.perf_counter()
    o = options or NewtonOptions()
    options = dataclasses.replace(o, atol=min(o.atol, tolerance),
                                  floor_atol=max(FLOOR, tolerance))
    with _undamped(model):
        r = PseudoStepper(model, options, stick_band)
        r.tolerance = tolerance
        try:
            its, kind = 0, "frictionless"
            held: list[str] = []
            res = None
            failed: list[str] = []  # why each stage before the held one failed
            if loading == "frictionless" or not r.has_friction:
                res, its = _frictionless(r, its, failed)
            if res is None and r.has_friction:
                try:
                    res = _stage(r, True)
                    kind = "frictional"
                    if loading == "frictionless" and model.comm.rank == 0:
                        log.warning(FALLBACK)
                except ConvergenceError as e:
                    its += e.iterations
                    failed.append(f"frictional: {e}")
                    log.debug("no frictional static state (%s): every pair held", e)
            if res is None:
                try:
                    with r.friction(HELD_FRICTION, HELD_FRICTION):
                        res = _stage(r, True)
                    kind = "held"
                except ConvergenceError as e:
                    # E.g. a body that starts too far above its support to land in the
                    # relaxation.
                    raise ConvergenceError(
                        f"initial state: no static equilibrium, not even with the bodies "
                        f"held ({'; '.join([*failed, f'held: {e}'])}) at [initial] "
                        f"tolerance = {tolerance:g} of the load; {no_state_advice(model)}",
                        e.reason, its + e.iterations) from e
            u = model.functions("u")
            for f, x in zip(u, res.u, strict=True):
                f.x.array[:] = x
            if kind == "frictional":
                _creep(r, v)
            elif kind == "held":
                held, sliding = held_bodies(r)
                if not held:  # then the held state is no equilibrium of the dynamics
                    raise ConvergenceError(NONE_HELD.format("; ".join(failed),
                                                            no_state_advice(model)),
                                           -1, its + res.iterations)
                if sliding and not model.pairs:
                    u_held = [f.x.array.copy() for f in r.stepper.u]
                    try:
                        its += _slide(r, sliding)
                        for f, g in zip(u, r.stepper.u, strict=True):
                            f.x.array[:] = g.x.array
                    except ConvergenceError as e:
                        its += e.iterations
                        log.debug("released from the held state (%s)", e)
                        for f, x in zip(r.stepper.u, u_held, strict=True):
                            f.x.array[:] = x
                release(r, sliding, v)
            steps = r.steps
        finally:
            r.destroy()
    out = Relaxed(u, its + res.iterations, kind, held, steps, time.perf_counter() - t0)
    log.info("relaxation: %d pseudo steps, %d Newton iterations, %.2f s (%s)", steps,
             out.iterations, out.seconds, kind)
    return out


def _frictionless(r: PseudoStepper, its: int, failed: list[str]
                  ) -> tuple[_Result | None, int]:
    """Stages 1 and 1b (module doc); None where neither relaxes (why: in ``failed``)."""
    try:
        with r.friction(0.0):
            return _stage(r, False), its
    except ConvergenceError as e:
        its += e.iterations
        failed.append(f"frictionless: {e}")
        log.debug("no frictionless static state (%s)", e)
    if not r.has_friction:
        return None, its
    # The deformed normals leave a tangential out-of-balance of the order of the
    # discretisation (1e-6 of the load on the Goda case meshed conforming): without
    # friction the rigid tangential mode then drifts away. A friction coefficient of
    # RESIDUAL_FRICTION on each step's slip increment arrests it (stage 1's steps from
    # rest; the stage-2 law on the total slip let the caisson slide off during the
    # settling at refinement 2); the state is the frictionless one to that fraction of
    # μp, and the dynamics starts at rest from it.
    try:
        with r.friction(RESIDUAL_FRICTION):
            return _stage(r, False), its
    except ConvergenceError as e:
        failed.append(f"nearly frictionless: {e}")
        log.debug("no nearly frictionless static state (%s)", e)
        return None, its + e.iterations
