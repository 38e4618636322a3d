"""One pseudo step of the relaxation: the GN22 stepper from u_k at a pseudo step size.

The state of :mod:`breakwater.statics.relaxation` and its single step: a GN22 stepper
on the fast solver (:class:`~breakwater.stepping.condensed.CondensedNewton`), started at
u_k with (v₀, a₀) chosen for the stage and a pseudo step Δτ from the mass weight
c = ½β₂Δτ² (:meth:`PseudoStepper.start`), and u_k advanced to the solved u₁
(:meth:`PseudoStepper.advance`, which measures the static residual ‖M (u₁ − u_k)‖/c);
the pairs' friction set for a stage (:meth:`PseudoStepper.friction`); and the model
estimates the step sizes come from (c_max from the lowest frequency, c₀ from the search
radius, the pseudo time τ from the stick band). The control of c over the steps of a
stage is :mod:`breakwater.statics.relaxation`'s.
"""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Iterator, Sequence
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.contact import searchkernels
from breakwater.contact.conforming import mean_facet_length
from breakwater.contact.coupling import BulkStiffness
from breakwater.contact.general3d import reference_gaps3d, smallest_gap
from breakwater.model.model import ContactModel
from breakwater.stepping.gn22 import GN22, GN22Parameters, force_scale
from breakwater.stepping.solver import NewtonOptions

if TYPE_CHECKING:
    from breakwater.contact.surfacesearch import SurfaceSearch

__all__ = ["FALL", "GROWTH", "LANDING", "NONE_HELD", "RATIO", "PseudoStepper", "SlipOrigin",
           "no_state_advice"]

ANY = (np.zeros((0, 2)), np.zeros(0))
"""searchkernels.frozen's normals and depths for a projection onto any master facet."""

RATIO = 1e4
"""c_max ω_min²: the contraction of the lowest mode per step at c_max is 1/(1 + RATIO)."""

GROWTH = 100.0
"""Growth of c per step (while the increments stay below a tenth of the search radius)."""

FALL = 0.1
"""A body that starts apart moves this fraction of the search radius per step at c₀."""

LANDING = 10.0
"""Search radii within which :meth:`SlipOrigin.reference_gaps` finds a landing point: the
farthest a relaxation's stage lets a body fall (``MAX_STEPS`` steps of a tenth of one)."""

class PseudoStepper:
    """The pseudo-transient stepper of a model and its state (see the module docstring).

    Args:
        model: The contact model (undamped for the relaxation).
        options: Newton settings of the pseudo steps.
        stick_band: The frictional stage's stick band χτ, as a fraction of the mean
            slave facet length.

    Raises:
        MeshError: A pair cannot start from the meshed configuration (its static check,
            :meth:`breakwater.model.pairs.Pair.static_check`, run by the GN22 stepper).

    Attributes:
        stepper: The GN22 stepper (its u is u_k).
        solver: Its fast solver.
        providers: The general pairs' contact forces.
        steps: Pseudo steps advanced, over every stage.
        c: c of the last converged step of a stage.
    """

    def __init__(self, model: ContactModel, options: NewtonOptions | None,
                 stick_band: float) -> None:
        self.model = m = model
        self.c_max = RATIO / _lowest_frequency_squared(m)
        g = float(np.linalg.norm(m.gravity.value))
        self.reach = _reach(m)
        self.c0 = min(self.c_max, FALL * self.reach / g) if g > 0 else self.c_max / GROWTH**2
        self.β2 = GN22Parameters().beta2
        friction = _pair_friction(m)
        self.has_friction = any(μ > 0 for μ, _, _ in friction)
        self.τ = min((stick_band * h / χ for _, χ, h in friction), default=1.0)
        Δτ_max = np.sqrt(2 * self.c_max / self.β2)
        self.β1 = 0.5 * self.β2 * Δτ_max / self.τ
        self.stepper = GN22(m, Δτ_max, GN22Parameters(self.β1, self.β2, allow_conditional=True),
                            newton=options, solver="fast")
        solver = self.stepper.fast
        assert solver is not None  # solver="fast"
        self.solver = solver
        solver.consistent = True
        self.providers = self.stepper.surfaces
        self._origins = [SlipOrigin(p) for p in self.providers]
        self._vecs = (solver.layout.vec.duplicate(), solver.layout.vec.duplicate())
        # The step in defect form (:meth:`start`): f_c at the step's start taken out of
        # the contact forces and put into the load.
        self._offset = _Offset(solver.n)
        solver.providers.append(self._offset)
        solver.bulk.offset = solver.layout.vec.duplicate()
        self.scale = force_scale(m)
        self.steps = 0
        self.c = self.c_max  # c of the last converged step
        self.tolerance = 1e-9  # the static residual, as a fraction of self.scale

    def destroy(self) -> None:
        """Free the stepper's PETSc objects."""
        for vec in self._vecs:
            vec.destroy()
        offset, self.solver.bulk.offset = self.solver.bulk.offset, None
        if offset is not None:
            offset.destroy()
        self.solver.providers.remove(self._offset)
        self.stepper.destroy()

    @contextlib.contextmanager
    def friction(self, μ: float | None, stretch: float = 1.0) -> Iterator[None]:
        """Every pair's friction coefficient μ (None: their own), χ times ``stretch``, inside."""
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

    def start(self, c: float, frictional: bool) -> None:
        """The GN22 start of a step from u_k (in ``u``): v₀, a₀ and Newton's start Δa₀.

        Frictionless: at rest. Frictional: ``c a₁ = u₁ − u_k`` and ``v₁ = u₁/τ_c``
        with τ_c = ½β₂Δτ/β₁ (the derivatives of u₁ and v₁ in Δa are c and β₁Δτ).
        Newton starts at u₁ = u_k (Δa₀ = −a₀), whose residual is the static residual
        there (in defect form, :meth:`_defect`). It started at GN22's predictor Δa₀ = 0:
        u₁ = u_k + c a₀, a move of the size of u_k itself (for a body meshed apart, its
        fall), whose residual (1e8–1e10 N/m after a fall of 0.01–0.4 m) let the Newton's
        relative test accept iterates 0.2 N/m off balance: a block landed from 0.39 m
        kept 2e-5 of its weight in net friction, and from 5 cm its state differed from
        the one meshed in contact by 2e-5 of its displacements (now 1e-9).
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
            d.x.array[:] = -a.x.array
        for p, origin in zip(self.providers, self._origins, strict=True):
            # The slip v = u/τ from the landing point, not from the meshed position.
            p.slip_origin = origin.at(τ) if frictional else None
        self._defect()

    def _defect(self) -> None:
        """The staged step in defect form: f_c at Newton's start moved into the load.

        The step's residual is unchanged, but its parts are not: the predictor's residual
        becomes the static residual at the start, f − K u − f_c(u) (small near the
        equilibrium, formed in force space), and the Newton's contact forces their change
        over the step, so that z = A⁻¹ r₀ and X f_c, otherwise each of the size of the
        whole contact force, no longer cancel in Δa. With the consistent bulk
        (``CondensedNewton.consistent``, the fix of the static residual) it takes the
        non-matching patch test's σ error from 2e-10 to 5e-11 p (measured; alone it
        did not help: the error was the bulk's, not this cancellation's).
        """
        solver = self.solver
        offset = solver.bulk.offset
        assert offset is not None
        self._offset.f0[:] = 0.0
        x, _ = self._vecs
        solver.layout.assign(self.stepper.da, x)
        (y0,) = solver.interface.gather(x.array)  # Newton's start
        solver.contact.begin()
        try:
            f0 = solver.contact.vector(y0)
        finally:
            solver.contact.end()
        self._offset.f0[:] = f0
        offset.zeroEntries()
        offset.array[solver.interface.owned_rows] = -f0[solver.interface.owned]

    def advance(self, c: float) -> tuple[float, float]:
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
        self.steps += 1
        return self._max(x.array), y.norm() / c

    def gaps(self) -> list[float]:
        """Per general pair, the smallest normal gap of its slave nodes now (collective).

        Along the master's normal at each node's closest point within :data:`LANDING`
        search radii (a node beyond the master's end is left out); inf: none there. The
        same on every rank (the pair's gathered state).
        """
        out = []
        for p in self.providers:
            u = p.interface_values(self.stepper.u)
            x = p.node_X + u[p.node_pos]
            out.append(smallest_gap(cast(Any, p), x, u, LANDING * p.radius)
                       if self.model.gdim == 3 else _smallest_gap(p, x, u))
        return out

    def _max(self, x: np.ndarray) -> float:
        return float(self.model.comm.allreduce(np.abs(x).max(initial=0.0), op=MPI.MAX))

    def rest(self) -> None:
        """The state of the last step at its solution: a₁ = 0, u₁ = u_k, v₁ = u_k/τ.

        (A frictional step's start, :meth:`start`.)
        """
        self.start(self.c, True)

    def add_slave_velocities(self, v: list[fem.Function], y: np.ndarray) -> None:
        """V += y, y given at the interface unknowns (every entry this rank holds)."""
        self.solver.interface.add(v, y)


def _smallest_gap(p: SurfaceSearch, x: np.ndarray, u: np.ndarray) -> float:
    """:meth:`PseudoStepper.gaps` of a 2-D pair's slave nodes at ``x`` (state ``u``)."""
    xm = np.ascontiguousarray(p.master.X + u[p.pos_m], dtype=float)
    facet, N0, t, on = searchkernels.frozen(x, xm, xm, LANDING * p.radius, *ANY)
    d = x - np.einsum("kn,knd->kd", N0, xm[np.maximum(facet, 0)])
    gap = d[:, 0] * t[:, 1] - d[:, 1] * t[:, 0]
    return float(gap[on & (facet >= 0)].min(initial=np.inf))


class SlipOrigin:
    """The frictional stage's slip measured from the landing point (a pair's ``slip_origin``).

    The stage's law acts on the total slip over the pseudo time τ, v = u/τ: at a slave
    node, ``(u_k − ū_m)/τ`` along the master's tangent. A body meshed a gap g₀ n̄ above
    its support closes it as it lands, u_k − ū_m = −g₀ n̄ + the slip: where the load
    turns the support's tangent t by θ, the fall counted as a slip g₀θ (found by a user:
    a block meshed 1 cm above a base with E = 1e9 Pa, θ up to 2e-6 rad at its corners,
    fell 70 χτ "along" the tangent: the state carried a net friction of 5.5e-3 of its
    weight, measured on it unbalanced). The slip is measured from the landing point:
    ``v₁ + d_k/τ``, d_k the node's separation from the master as meshed along its
    normal there (:meth:`reference_gaps`). Nil (round-off) for bodies meshed in contact
    along a flat interface.

    Args:
        pair: The general pair.
    """

    def __init__(self, pair: SurfaceSearch) -> None:
        self.pair = pair
        self._gaps: np.ndarray | None = None
        self._offset = np.zeros(pair.n + 1)
        self._τ: float | None = None
        self._kept: tuple[np.ndarray, np.ndarray] | None = None  # (v₁, v₁ + offset)

    def reference_gaps(self) -> np.ndarray:
        """Per slave node, ``((X_k − X̄)·n̄) n̄``, ``(nodes, gdim)``.

        X̄ the closest point of the master surface as meshed (a node beyond its end:
        the nearest end in 2-D, none in 3-D,
        :func:`~breakwater.contact.general3d.reference_gaps3d`), n̄ its normal there,
        within :data:`LANDING` search radii (farther: 0, no landing point).
        """
        if self._gaps is None and self.pair.node_X.shape[1] == 3:
            self._gaps = reference_gaps3d(cast(Any, self.pair), LANDING * self.pair.radius)
        if self._gaps is None:
            p = self.pair
            X, mX = p.node_X, np.ascontiguousarray(p.master.X, dtype=float)
            facet, N0, t0, _ = searchkernels.frozen(X, mX, mX, LANDING * p.radius, *ANY)
            d = X - np.einsum("kn,knd->kd", N0, mX[np.maximum(facet, 0)])
            n = np.stack([t0[:, 1], -t0[:, 0]], axis=1)
            self._gaps = np.where((facet >= 0)[:, None], np.sum(d * n, axis=1)[:, None] * n,
                                  0.0)
        return self._gaps

    def at(self, τ: float) -> SlipOrigin:
        """Set for the pseudo time τ (of the step being started); self returned."""
        if τ != self._τ:
            pos = self.pair.node_pos
            keep = pos >= 0
            self._offset[pos[keep]] = self.reference_gaps()[keep] / τ
            self._τ, self._kept = τ, None
        return self

    def __call__(self, v1: np.ndarray) -> np.ndarray:
        """v₁ + d/τ at the slave nodes' unknowns (the same array for the same v₁)."""
        kept = self._kept
        if kept is None or kept[0] is not v1:
            self._kept = kept = (v1, v1 + self._offset)
        return kept[1]


class _Offset:
    """A constant force −f0 among the contact forces (:meth:`PseudoStepper._defect`)."""

    def __init__(self, n: int) -> None:
        self.f0 = np.zeros(n)

    def begin(self) -> None:
        """Nothing to take."""

    def end(self) -> None:
        """Nothing to release."""

    def add_vector(self, y: np.ndarray, out: np.ndarray) -> None:
        """Subtract f0."""
        out -= self.f0

    def add_left_product(self, y: np.ndarray, X: np.ndarray, out: np.ndarray) -> bool:
        """A constant: nothing."""
        return True

    def matrix(self, y: np.ndarray) -> np.ndarray:
        """A constant: zero."""
        return np.zeros((len(self.f0), len(self.f0)))

    def active_jacobian(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A constant: no unknowns coupled."""
        return np.zeros(0, np.int64), np.zeros((0, 0))

    def resolution(self, y: np.ndarray) -> float:
        """Exact: 0."""
        return 0.0

    def precheck(self, x: np.ndarray, step: np.ndarray, v_pred: np.ndarray,
                 dv_dx: float, bulk: BulkStiffness | None = None) -> int:
        """No guard."""
        return 0

    def true_law(self, crawl: bool = True) -> bool:
        """A constant: False."""
        return False

    def regularise(self, stretch: float) -> bool:
        """No friction: False."""
        return False


# --- model estimates -----------------------------------------------------------------

def _extent(model: ContactModel, body: int) -> float:
    """The bounding-box diagonal of a body (m)."""
    lo, hi = model.bounding_box(body)
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


NONE_HELD = ("initial state: no frictional static state ({}), and friction holds every body "
             "(none to hold in place and release at t = 0: the held state would start the "
             "dynamics out of equilibrium); {}")
"""The frictional stage failed and friction holds every body: the held state (μ, χ ×100)
is no equilibrium of the dynamics (a plank across a narrow pedestal, its frictional stage
stalled at 2e-8 of the load, started vibrating on it: the ledger off by 24 %, a push
slid it 42 % too far, nothing said; bad run k1)."""


def no_state_advice(model: ContactModel) -> str:
    """What a case without a static state can set: its loads left out of it, or none.

    The static state carries every load of the initial state at its value at t = 0: a
    load that jumps there (a rectangular pulse, a push) is one that no friction or
    contact may hold, and the advice was only to start undeformed (which drops the
    gravity state too; found by a user).
    """
    loads = model.initial.loads
    held = len(model.loads) if loads is None else len(loads)
    return ((f"leave loads out of it (it carries {held} at t = 0: [initial] loads = [] "
             "keeps none), or " if held else "")
            + "set [initial] undeformed = true to start from the undeformed state at rest")
