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
increments stay below that. Converged when the static residual at the new iterate,
``‖M (u − u_k)‖/c``, is below :data:`TOLERANCE` times the load norm ‖f‖. Damping is
switched off (a static state carries none).

Stages, as :mod:`breakwater.statics.initial` for conforming pairs (and for every pair of a
model with both kinds):

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
   friction of 1e-4 μp holds it. The state is the frictionless one to that fraction
   (on the Goda mesh the corner's static slip equals the conforming frictionless
   state's to 0.3 %) and the dynamics starts from it at rest, as from stage 1
   (``kind = "frictionless"``).
2. **Frictional** (if some pair has friction): the friction law acts on the total slip
   from the unloaded state over a pseudo time τ (``v = u/τ``, as ``initial.py`` stage
   2), with τ such that the stick band χτ is ``stick_band``
   (:data:`breakwater.statics.initial.STICK_BAND`) times the interface facet length. The step's
   velocity is set up for it: with u₀ = u_k, the GN22 start (v₀, a₀) is chosen so that
   ``c a₁ = u₁ − u_k`` (the mass term above) and ``v₁ = u₁/τ``, and β₁ = ½β₂Δτ_max/τ (τ
   at c_max; smaller c give a smaller τ, a narrower stick band, until c settles). The
   slave nodes in contact then start with that slip velocity (the law's creep, a
   fraction of χ), so that the friction of the static state is carried at t = 0.
3. **Held** (stage 2 fails, or no friction): every pair's friction coefficient is
   raised to :data:`HELD_FRICTION` for the relaxation (the bodies are held in place up
   to t = 0); a warning names each body whose pair carries a tangential resultant
   above μN, and the dynamics, with the real μ, releases it at t = 0. It is released
   in the state of incipient sliding (:meth:`_Relaxation.slide`; models with general
   pairs only): pseudo steps with the real μ from the held state, in the frame of the
   body's acceleration α d (d its sliding direction, α from its resultant along d),
   so that its pairs carry the friction of sliding and its deformation is that of the
   sliding body, not the held state's shear (whose release, in an elastic body,
   reversed slip velocities at the first steps: +1.3 % of the slide of a pushed block
   with E = 1e9 at Δt = 1e-3). Its slave nodes then start sliding at :data:`RELEASE` χ
   along their tangent in the sliding direction (1e-8 m/s at the paper's χ: from
   rest), where the law carries μλ: the first step sees the friction of sliding
   (with v = 0 it would see none, a₀ would be F/m instead of (F − μN)/m, and GN22
   would keep (1 − β₁)Δt times the difference as a velocity error).

If even the held state does not relax (a body that starts too far from its support to
land within the relaxation: it falls by at most a tenth of the search radius per step
and a stage stops after :data:`STALL` steps without progress), the run starts from the
undeformed state at rest (``kind = "undeformed"``), with one warning, and the dynamics
drops the body.

:func:`relax` is called by :func:`breakwater.statics.initial.initial_state` for models with
general pairs; a₀ of the stepper's initialisation then vanishes (it includes the
general pairs' forces).
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import time
from collections.abc import Iterator, Sequence

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common.errors import ConvergenceError
from breakwater.contact.conforming import RELEASE, creep_velocities, mean_facet_length
from breakwater.model.model import ContactModel, Damping
from breakwater.stepping.condensed import CondensedNewton
from breakwater.stepping.gn22 import GN22, GN22Parameters, force_scale
from breakwater.stepping.solver import NewtonOptions

__all__ = ["GROWTH", "HELD_FRICTION", "MAX_STEPS", "RATIO", "RELEASE", "RESIDUAL_FRICTION",
           "STALL", "TOLERANCE", "Relaxed", "relax"]

log = logging.getLogger("breakwater.statics.relaxation")

RATIO = 1e4
"""c_max ω_min²: the contraction of the lowest mode per step at c_max is 1/(1 + RATIO)."""

GROWTH = 100.0
"""Growth of c per step (while the increments stay below a tenth of the search radius)."""

TOLERANCE = 1e-8
"""Converged when the static residual ‖M (u₁ − u_k)‖/c is below this fraction of ‖f‖.

Ten times the Newton tolerance of a step (``NewtonOptions.atol``): a body resting on
non-matching meshes without friction carries a tangential out-of-balance of the
discretisation (1.5e-9 ‖f‖ measured on the sliding-block example) that no frictionless
state removes; it slides by the same amount at every step."""

RESIDUAL_FRICTION = 1e-4
"""Friction coefficient of the nearly frictionless stage (1b in the module doc)."""

MAX_STEPS = 100
"""Pseudo steps allowed per stage."""

STALL = 4
"""A stage fails when its increment has not halved over this many steps at one c."""

HELD_FRICTION = 100.0
"""Friction coefficient of every pair while the bodies are held (stage 3); the
regularisation χ is multiplied by it too, so that the stick tangent μp/χ stays that of
μ = 1 (the Newton of a step converges as in stage 2)."""


@dataclasses.dataclass
class _Result:
    """One stage's outcome."""

    u: list[np.ndarray]
    steps: int
    iterations: int


class _Relaxation:
    """The pseudo-transient stepper of a model (see the module docstring)."""

    def __init__(self, model: ContactModel, options: NewtonOptions | None,
                 stick_band: float) -> None:
        self.model = m = model
        self.c_max = RATIO / _lowest_frequency_squared(m)
        g = float(np.linalg.norm(m.gravity.value))
        self.reach = _reach(m)
        self.c0 = min(self.c_max, 0.1 * self.reach / g) if g > 0 else self.c_max / GROWTH**2
        self.β2 = GN22Parameters().beta2
        friction = _pair_friction(m)
        self.has_friction = any(μ > 0 for μ, _, _ in friction)
        self.τ = min((stick_band * h / χ for _, χ, h in friction), default=1.0)
        Δτ_max = np.sqrt(2 * self.c_max / self.β2)
        self.β1 = 0.5 * self.β2 * Δτ_max / self.τ
        self.stepper = GN22(m, Δτ_max, GN22Parameters(self.β1, self.β2, allow_conditional=True),
                            newton=options, solver="fast")
        solver = self.stepper.solver
        assert isinstance(solver, CondensedNewton)
        self.solver = solver
        self.providers = self.stepper.surfaces
        self._vecs = (solver.layout.vec.duplicate(), solver.layout.vec.duplicate())
        self.scale = force_scale(m)
        self.steps = 0
        self.c = self.c_max  # c of the last converged step
        self.sliding: dict[int, np.ndarray] = {}  # held slave body → its sliding direction

    def destroy(self) -> None:
        """Free the stepper's PETSc objects."""
        for vec in self._vecs:
            vec.destroy()
        self.stepper.destroy()

    # --- one stage --------------------------------------------------------------------

    @contextlib.contextmanager
    def friction(self, μ: float | None, stretch: float = 1.0) -> Iterator[None]:
        """Every pair's friction coefficient μ (None: their own) inside the block.

        Their regularisation χ is multiplied by ``stretch``.
        """
        saved = [(p, p.spec, p.law) for p in self.providers]
        conforming = [(p.law.friction, float(p.law.friction.μ.value),
                       float(p.law.friction.χ.value)) for p in self.model.pairs]
        try:
            for p in self.providers:
                p.spec = dataclasses.replace(
                    p.spec, friction=p.spec.friction if μ is None else μ,
                    regularisation=p.spec.regularisation * stretch)
                p.law = forms.ContactLaw.of(p.spec)
            for law, μ0, χ0 in conforming:
                law.μ.value = μ0 if μ is None else μ
                law.χ.value = χ0 * stretch
            yield
        finally:
            for p, spec, law in saved:
                p.spec, p.law = spec, law
            for law, μ0, χ0 in conforming:
                law.μ.value, law.χ.value = μ0, χ0

    def _start(self, c: float, frictional: bool) -> None:
        """The GN22 start of a step from u_k (in ``u``): v₀, a₀ and Δa = 0.

        Frictionless: at rest. Frictional: ``c a₁ = u₁ − u_k`` and ``v₁ = u₁/τ_c``
        with τ_c = ½β₂Δτ/β₁ (the derivatives of u₁ and v₁ in Δa are c and β₁Δτ).
        """
        s = self.stepper
        Δτ = np.sqrt(2 * c / self.β2)
        s.dt.value = Δτ
        if frictional:
            τ = 0.5 * self.β2 * Δτ / self.β1
            # (c − ½Δτ²) a₀ − Δτ v₀ = 0 and (Δτ − ½Δτ²/τ) a₀ + (1 − Δτ/τ) v₀ = u_k/τ.
            A = np.array([[c - 0.5 * Δτ**2, -Δτ], [Δτ - 0.5 * Δτ**2 / τ, 1 - Δτ / τ]])
            ka, kv = np.linalg.solve(A, [0.0, 1.0 / τ])
        else:
            ka = kv = 0.0
        for u, v, a, d in zip(s.u, s.v, s.a, s.da, strict=True):
            v.x.array[:] = kv * u.x.array
            a.x.array[:] = ka * u.x.array
            d.x.array[:] = 0.0

    def _advance(self, c: float) -> tuple[float, float]:
        """u_k ← u₁ of the solved step.

        Returns:
            max|u₁ − u_k| and the static residual at u₁, ‖M (u₁ − u_k)‖/c (Dirichlet
            rows left out).
        """
        s, bulk, layout = self.stepper, self.solver.bulk, self.solver.layout
        Δτ = float(s.dt.value)
        x, y = self._vecs
        for u, v, a, d, lo, hi in zip(s.u, s.v, s.a, s.da, layout.offsets[:-1],
                                      layout.offsets[1:], strict=True):
            du = Δτ * v.x.array + 0.5 * Δτ**2 * a.x.array + c * d.x.array
            u.x.array[:] += du
            x.array[lo:hi] = du[: hi - lo]
        bulk.M.mult(x, y)
        y.array[bulk.bc_rows] = 0.0
        return self._max(x.array), y.norm() / c

    def _max(self, x: np.ndarray) -> float:
        return float(self.model.comm.allreduce(np.abs(x).max(initial=0.0), op=MPI.MAX))

    def stage(self, frictional: bool) -> _Result:
        """Relax from the undeformed state (a 1e-9 m penetration along gravity).

        Raises:
            ConvergenceError: A step's Newton failed, or the increments do not vanish.
        """
        m, s = self.model, self.stepper
        for u in s.u:
            u.x.array[:] = 0.0
        g = m.gravity.value
        if np.any(g):
            slaves = {m.body(p.slave).index for p in m.surface_pairs}
            slaves |= {p.slave for p in m.pairs}
            for i in slaves:
                s.u[i].x.array.reshape(-1, m.gdim)[:] = 1e-9 * g / np.linalg.norm(g)
        c, its, history = self.c0, 0, []
        solved = 0.0  # c of the last solved step
        for k in range(1, MAX_STEPS + 1):
            self._start(c, frictional)
            try:
                its += s.solve()
            except ConvergenceError as e:
                if c > solved > 0:
                    # A grown step overshot the contact state: retry at a tenth of it
                    # (not below the last c that converged); u_k is unchanged.
                    its += e.iterations
                    log.debug("relaxation step %d: c = %.3e s² failed, retried at %.3e s²",
                              k, c, max(solved, c / 10))
                    c = max(solved, c / 10)
                    continue
                raise ConvergenceError(f"relaxation step {k}: {e}", e.reason,
                                       its + e.iterations) from e
            solved = c
            inc, residual = self._advance(c)
            self.steps += 1
            log.debug("relaxation step %d: c = %.3e s², max|Δu| = %.3e m, residual %.3e, "
                      "%d Newton iterations", k, c, inc, residual / self.scale, its)
            if residual <= TOLERANCE * self.scale:
                self.c = c
                return _Result([u.x.array.copy() for u in s.u], k, its)
            history.append((c, inc))
            same = history[-STALL - 1:]
            if len(same) > STALL and all(h[0] == c for h in same) and inc > 0.5 * same[0][1]:
                break
            if inc < 0.1 * self.reach:
                c = min(c * GROWTH, self.c_max)
        raise ConvergenceError(f"relaxation: no static state (max|Δu| = {inc:.3e} m after "
                               f"{k} steps)", -1, its)

    # --- the held bodies released -------------------------------------------------

    def slide(self) -> int:
        """Relax the held bodies (:attr:`sliding`) into the state of incipient sliding.

        The held stage's friction (μ = :data:`HELD_FRICTION`) carries the bonded shear;
        released, the body slides with the friction μλ and the acceleration α d (d the
        sliding direction, α from its resultant). Pseudo steps with the real μ from the
        held state, each started with a₀ = α d and v₀ = −½Δτ α d on the body (so that
        u₁ − u_k = c Δa: the static residual of the stage, in the frame of the body's
        acceleration, and v₁ ≈ ½Δτ α d, far above χ: the friction of sliding), α updated
        after each step from the body's resultant along d. As :func:`breakwater.statics.initial.
        _release` for conforming pairs: GN22 then starts in the motion of sliding.

        Returns:
            The Newton iterations.

        Raises:
            ConvergenceError: A step failed or the steps did not converge.
        """
        m, s = self.model, self.stepper
        c, its = self.c / GROWTH**2, 0
        bodies = []
        for i, total in self.sliding.items():
            b = m.bodies[i]
            d = total / np.linalg.norm(total)
            dc = fem.Constant(m.mesh, d)
            force = forms.body_force(b.ρ, m.gravity, dc, b.dx)
            for ld in m.loads:
                if ld.body == i:
                    force += forms.surface_traction(ld.traction, dc, ld.ds)
            ext = m.assemble(m.form(force))
            mass = m.assemble(m.form(b.ρ * b.dx))
            slaves = [p for p in self.providers if m.body(p.spec.slave).index == i]
            # At first the held state's pressure with the friction of sliding against d.
            contact = 0.0
            for p in slaves:
                normal, _ = p.resultants(accepted=True)
                contact += float(normal @ d) - p.spec.friction * float(np.linalg.norm(normal))
            bodies.append([i, d, ext, mass, slaves, (ext + contact) / mass])
        with self.friction(None):
            for k in range(1, MAX_STEPS + 1):
                self._start(c, False)
                Δτ = float(s.dt.value)
                for i, d, _, _, _, α in bodies:
                    s.v[i].x.array.reshape(-1, m.gdim)[:] = -0.5 * Δτ * α * d
                    s.a[i].x.array.reshape(-1, m.gdim)[:] = α * d
                its += s.solve()
                for body in bodies:
                    i, d, ext, mass, slaves, _ = body
                    contact = sum(float(p.resultant(accepted=False) @ d) for p in slaves)
                    body[5] = (ext + contact) / mass
                inc, residual = self._advance(c)
                self.steps += 1
                log.debug("sliding step %d: max|Δu| = %.3e m, residual %.3e, α = %s", k, inc,
                          residual / self.scale, [b[5] for b in bodies])
                if residual <= TOLERANCE * self.scale:
                    return its
                c = min(c * GROWTH, self.c)
        raise ConvergenceError(f"relaxation: no state of incipient sliding after {k} steps",
                               -1, its)

    # --- after a stage --------------------------------------------------------------

    def _rest(self) -> None:
        """The state of the last step at its solution: a₁ = 0, u₁ = u_k, v₁ = u_k/τ."""
        s = self.stepper
        self._start(self.c, True)
        for a, d in zip(s.a, s.da, strict=True):
            d.x.array[:] = -a.x.array

    def _add_slave_velocities(self, v: list[fem.Function], y: np.ndarray) -> None:
        """V += y, y given at the interface unknowns (every entry this rank holds)."""
        solver = self.solver
        for f, gi in zip(v, solver.layout.global_index, strict=True):
            at = np.minimum(np.searchsorted(solver.I, gi), max(solver.n - 1, 0))
            hit = np.flatnonzero(solver.I[at] == gi) if solver.n else np.zeros(0, int)
            f.x.array[hit] += y[at[hit]]

    def creep(self, v: list[fem.Function]) -> None:
        """Add the slave nodes' slip velocity of the frictional state to ``v``."""
        s = self.stepper
        self._rest()
        y = np.zeros(self.solver.n)
        for p in self.providers:
            pos, v_T = p.slip_velocities()
            keep = pos >= 0
            y[pos[keep]] = v_T[keep]
        self._add_slave_velocities(v, y)
        if self.model.pairs:
            u = [fem.Function(f.function_space) for f in s.u]
            for f, g in zip(u, s.u, strict=True):
                f.x.array[:] = g.x.array
            τ = 0.5 * self.β2 * float(s.dt.value) / self.β1  # τ of the last step
            creep_velocities(self.model, self.model.pairs, u, v, τ)

    def held(self) -> list[str]:
        """The slave bodies whose pair's tangential resultant exceeds μN (held state).

        Each is named in a warning; :attr:`sliding` gets its sliding direction (against
        the held friction), for :meth:`slide` and :meth:`release`.
        """
        out = []
        self.sliding = {}
        self._rest()
        with self.friction(HELD_FRICTION, HELD_FRICTION):
            forces = [p.resultants(accepted=False) for p in self.providers]
        for p, (normal, friction) in zip(self.providers, forces, strict=True):
            N, T = float(np.linalg.norm(normal)), float(np.linalg.norm(friction))
            μ = p.spec.friction
            if T - μ * N > 1e-6 * max(N, T):
                if self.model.comm.rank == 0:
                    log.warning("initial state: body '%s' cannot be held by friction on '%s' "
                                "(tangential force %.4g N/m, μN = %.4g N/m): held in place up "
                                "to t = 0 and released at t = 0", p.spec.slave, p.spec.name,
                                T, μ * N)
                index = self.model.body(p.spec.slave).index
                self.sliding[index] = self.sliding.get(index, 0.0) - friction
                if p.spec.slave not in out:
                    out.append(p.spec.slave)
        if not out:  # the conforming pairs' bodies (not checked one by one)
            for pair in self.model.pairs:
                body = self.model.bodies[pair.slave].spec.name
                if self.model.comm.rank == 0:
                    log.warning("initial state: body '%s' cannot be held by friction on "
                                "'%s': held in place up to t = 0 and released at t = 0",
                                body, pair.spec.interface)
                out.append(body)
        return out

    def release(self, v: list[fem.Function]) -> None:
        """Start the held bodies' slave nodes in contact sliding (added to ``v``).

        Each gets the velocity :data:`RELEASE` χ along its tangent, in the body's
        sliding direction: the law then carries the sliding friction μλ at t = 0 (to
        5e-5), so that a₀ is the sliding acceleration rather than that without friction.
        """
        self._rest()
        y = np.zeros(self.solver.n)
        for p in self.providers:
            d = self.sliding.get(self.model.body(p.spec.slave).index)
            if d is None:
                continue
            pos, v_T = p.slip_velocities()
            size = np.linalg.norm(v_T, axis=1)[:, None]
            keep = np.all(pos >= 0, axis=1) & (size[:, 0] > 0)
            unit = v_T[keep] / size[keep]
            # Along the node's tangent, turned to the sliding direction (a node's own
            # slip in the held state may point the other way).
            unit *= np.where(unit @ d < 0, -1.0, 1.0)[:, None]
            y[pos[keep]] = RELEASE * p.spec.regularisation * unit
        self._add_slave_velocities(v, y)


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
        kind: ``"frictionless"``, ``"frictional"``, ``"held"`` or ``"undeformed"``
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
          options: NewtonOptions | None = None) -> Relaxed:
    """The static initial state of a model with general pairs (collective; module doc).

    Call it with the loads of the initial state at t = 0
    (:func:`breakwater.statics.initial.initial_state` does).

    Args:
        model: The contact model.
        v: The initial velocities; the slave nodes' creep (frictional) or release
            (held) velocities are added to them.
        stick_band: The frictional state's stick band χτ, as a fraction of the mean
            slave facet length (:data:`breakwater.statics.initial.STICK_BAND`).
        options: Newton settings of the pseudo steps.
    """
    t0 = time.perf_counter()
    with _undamped(model):
        r = _Relaxation(model, options, stick_band)
        try:
            its, kind, held = 0, "frictionless", []
            try:
                with r.friction(0.0):
                    res = r.stage(False)
            except ConvergenceError as e:
                its += e.iterations
                log.debug("no frictionless static state (%s)", e)
                res = None
            if res is None and r.has_friction:
                # The deformed normals leave a tangential out-of-balance of the order of
                # the discretisation (1e-6 of the load on the Goda case meshed
                # conforming): without friction the rigid tangential mode then drifts
                # away. A friction coefficient of RESIDUAL_FRICTION on each step's slip
                # increment arrests it (stage 1's steps from rest; the stage-2 law on the
                # total slip let the caisson slide off during the settling at
                # refinement 2); the state is the frictionless one to that fraction of
                # μp, and the dynamics starts at rest from it.
                try:
                    with r.friction(RESIDUAL_FRICTION):
                        res = r.stage(False)
                except ConvergenceError as e:
                    its += e.iterations
                    log.debug("no nearly frictionless static state (%s)", e)
            if res is None and r.has_friction:
                try:
                    res = r.stage(True)
                    kind = "frictional"
                except ConvergenceError as e:
                    its += e.iterations
                    log.debug("no frictional static state (%s): every pair held", e)
            if res is None:
                try:
                    with r.friction(HELD_FRICTION, HELD_FRICTION):
                        res = r.stage(True)
                    kind = "held"
                except ConvergenceError as e:
                    # E.g. a body that starts too far above its support to land in the
                    # relaxation: the dynamics drops it from where it is.
                    its += e.iterations
                    if model.comm.rank == 0:
                        log.warning("initial state: no static equilibrium (%s): the run "
                                    "starts from the undeformed state at rest", e)
                    res = _Result([np.zeros_like(f.x.array) for f in r.stepper.u], 0, 0)
                    kind = "undeformed"
            u = model.functions("u")
            for f, x in zip(u, res.u, strict=True):
                f.x.array[:] = x
            if kind == "frictional":
                r.creep(v)
            elif kind == "held":
                held = r.held()
                if r.sliding and not model.pairs:
                    u_held = [f.x.array.copy() for f in r.stepper.u]
                    try:
                        its += r.slide()
                        for f, g in zip(u, r.stepper.u, strict=True):
                            f.x.array[:] = g.x.array
                    except ConvergenceError as e:
                        its += e.iterations
                        log.debug("released from the held state (%s)", e)
                        for f, x in zip(r.stepper.u, u_held, strict=True):
                            f.x.array[:] = x
                r.release(v)
            steps = r.steps
        finally:
            r.destroy()
    out = Relaxed(u, its + res.iterations, kind, held, steps, time.perf_counter() - t0)
    log.info("relaxation: %d pseudo steps, %d Newton iterations, %.2f s (%s)", steps,
             out.iterations, out.seconds, kind)
    return out


# --- model estimates -----------------------------------------------------------------

def _extent(model: ContactModel, body: int) -> float:
    """The bounding-box diagonal of a body (m)."""
    x = model.bodies[body].submesh.geometry.x[:, : model.gdim]
    lo, hi = x.min(axis=0, initial=np.inf), x.max(axis=0, initial=-np.inf)
    model.comm.Allreduce(MPI.IN_PLACE, lo, op=MPI.MIN)
    model.comm.Allreduce(MPI.IN_PLACE, hi, op=MPI.MAX)
    return float(np.linalg.norm(hi - lo))


def _lowest_frequency_squared(model: ContactModel) -> float:
    """A lower estimate of ω_min² (1/s²): E/(ρL²) per body, ε_n/(ρL) per pair's slave."""
    out = []
    for i, b in enumerate(model.bodies):
        mat = b.spec.material
        out.append(mat.E / (mat.density * _extent(model, i) ** 2))
    for penalty, slave in ([(p.penalty, model.body(p.slave).index)
                            for p in model.surface_pairs]
                           + [(float(p.ε_n.value), p.slave) for p in model.pairs]):
        out.append(penalty / (model.bodies[slave].spec.material.density
                              * _extent(model, slave)))
    return min(out)


def _facet_lengths(model: ContactModel, body: str, groups: Sequence[str]
                   ) -> tuple[float, float]:
    """Mean and largest facet length of a body's facet groups (m)."""
    b = model.body(body)
    fdim = model.mesh.topology.dim - 1
    facets = model.surface_facets(body, groups)
    facets = facets[facets < b.submesh.topology.index_map(fdim).size_local]
    h = b.submesh.h(fdim, facets)
    comm = model.comm
    n = comm.allreduce(len(h))
    return comm.allreduce(float(h.sum())) / max(n, 1), comm.allreduce(h.max(initial=0.0),
                                                                         op=MPI.MAX)


def _reach(model: ContactModel) -> float:
    """The smallest contact search radius (general pairs) or interface facet length (m)."""
    out = [p.radius if p.radius is not None else
           _facet_lengths(model, p.master, p.master_groups)[1] for p in model.surface_pairs]
    out += [mean_facet_length(model, p) for p in model.pairs]
    return min(out)


def _pair_friction(model: ContactModel) -> list[tuple[float, float, float]]:
    """(μ, χ, mean slave facet length) of every pair."""
    out = [(p.friction, p.regularisation, _facet_lengths(model, p.slave, (p.slave_surface,))[0])
           for p in model.surface_pairs]
    out += [(float(p.law.friction.μ.value), float(p.law.friction.χ.value),
             mean_facet_length(model, p)) for p in model.pairs]
    return out
