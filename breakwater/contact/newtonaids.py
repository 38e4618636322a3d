"""What the interface Newton asks of a general pair beyond f_c and its Jacobian.

- :class:`SlipMemory`: Newton's start of a step with each slave node's slip velocity of
  the last accepted step kept (the frame it is measured in moves between steps).
- :func:`resolution`: the round-off of f_c at an iterate, below which the residual
  carries no information (the Newton's test converges there).
- :class:`CrawlPoints`: the slip guard's decisions, and where it linearises the law of a
  slip that crawls along the saturated law (:mod:`~breakwater.contact.guardkernels`);
  :func:`slip_guard`, the pair's guard at the nodes its law holds
  (:mod:`~breakwater.contact.coupling`).
- :class:`Regularised`: the pair's friction law with χ stretched, for the Newton's
  continuation (:mod:`breakwater.stepping.continuation`).

The first two read the pair's state at the interface unknowns
(:class:`~breakwater.contact.surfacesearch.SurfaceSearch`; every rank holds the same values,
so every rank takes the same decisions).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common.jit import kernel
from breakwater.contact import coupling, forcekernels, guardkernels

if TYPE_CHECKING:
    from breakwater.contact.surfaces import SurfacePair
    from breakwater.contact.surfacesearch import SurfaceSearch

__all__ = ["CrawlPoints", "Regularised", "SlipMemory", "friction_normals", "resolution",
           "sliding_velocities", "slip_guard", "slip_velocities_at"]


class SlipMemory:
    """Newton's start with each slave node's slip velocity of the last step kept.

    GN22's start Δa = −a/β₁ keeps every velocity (``v₁ = v₀``), but a general pair
    measures the slip velocity against the master point under the node's projection
    *at the start of the step*, along the tangent there, and both move from step to
    step: the relative velocity, which carries the normal (penetration) rate, then
    shows a tangential part ``v_n Δθ`` (1e-7 m/s on the separately meshed Goda caisson
    during the impact, 1000 χ). A node that stuck (|v_T| ≤ χ) would start Newton far
    outside the stick band, where the law's tangent μλχ²/|v_T|³ is nil: Newton's first
    step reversed the slip of most sticking nodes (the guard landed them at zero) and
    the iteration took 7–9 iterations per step instead of 3–4. :meth:`predict` moves the
    slave node's tangential start so that its slip velocity, measured against this
    step's projection and tangent, is the one the last accepted step converged to
    (:meth:`converged`, :meth:`accept`): ``y_k += −t₀ (v_T(y) − v_T,last)/(β₁Δt)``.
    Only the start moves; the solution is the law's.

    Args:
        pair: The general pair.

    Attributes:
        slip: Per slave node, the slip velocity along the tangent at the end of the last
            accepted step (NaN: not in contact; None: no step yet); a checkpoint saves
            it (:meth:`saved`, :meth:`load`).
    """

    def __init__(self, pair: SurfaceSearch) -> None:
        self.pair = pair
        self.slip: np.ndarray | None = None
        self._pending: np.ndarray | None = None

    def along(self, v1: np.ndarray, facet: np.ndarray, N0: np.ndarray, t0: np.ndarray
              ) -> np.ndarray:
        """Per slave node, ``(v_k − v̄_m(ξ̄₀))·t₀`` at the velocities v1 (NaN: no facet)."""
        return slip_along(v1, facet, N0, t0, self.pair._node_pos, self.pair._pm)

    def predict(self, y: np.ndarray) -> int:
        """Move Newton's start y (in place) to the last step's slip velocities.

        Returns:
            The nodes moved (the same on every rank).
        """
        p = self.pair
        if self.slip is None or not p.spec.friction:
            return 0
        u0, _, v1 = p._state(y)
        facet, N0, t0 = p._frozen(u0)
        return int(shift_start(y, self.slip, self.along(v1, facet, N0, t0), t0, p._node_pos,
                               p.beta1 * p.step_dt()))

    def converged(self, y: np.ndarray) -> None:
        """Keep the converged step's slip velocities at the slave nodes in contact.

        They become :attr:`slip` when the step is accepted (:meth:`accept`); NaN where
        a node has no contact (λ_k = 0).
        """
        p = self.pair
        if not p.spec.friction:
            return
        u0, u1, v1 = p._state(y)
        along = self.along(v1, *p._frozen(u0))
        along[~(p._normal(u1)["lam"] > 0)] = np.nan
        self._pending = along

    def accept(self) -> None:
        """The step whose slip :meth:`converged` kept is accepted."""
        if self._pending is not None:
            self.slip, self._pending = self._pending, None

    def saved(self) -> list[float | None] | None:
        """:attr:`slip` for a checkpoint (JSON: None for NaN)."""
        if self.slip is None:
            return None
        return [float(x) if np.isfinite(x) else None for x in self.slip]

    def load(self, saved: list[float | None] | None) -> None:
        """Set :attr:`slip` from :meth:`saved` (a resumed run)."""
        self.slip = None if saved is None else np.array(
            [np.nan if x is None else x for x in saved], dtype=float)


@kernel
def slip_along(v1, facet, N0, t0, node_pos, pos_m):  # type: ignore[no-untyped-def]
    """:meth:`SlipMemory.along` (compiled): per slave node ``(v_k − Σ_b N̄₀_b v_b)·t₀``."""
    out = np.empty(len(facet))
    for j in range(len(facet)):
        f = facet[j]
        out[j] = np.nan if f < 0 else forcekernels.tangential_slip(v1, j, f, N0, t0,
                                                                     node_pos, pos_m)
    return out


@kernel
def shift_start(y, slip, along, t0, node_pos, dv):  # type: ignore[no-untyped-def]
    """:meth:`SlipMemory.predict`'s move of y (in place, compiled); the nodes moved.

    Where a node has a last slip and a slip now and its DOFs are unknowns:
    ``y_k −= t₀ (along − slip)/dv`` (``dv = β₁Δt``).
    """
    moved = 0
    for j in range(len(slip)):
        if (math.isfinite(slip[j]) and math.isfinite(along[j]) and node_pos[j, 0] >= 0
                and node_pos[j, 1] >= 0):
            shift = (along[j] - slip[j]) / dv
            y[node_pos[j, 0]] -= t0[j, 0] * shift
            y[node_pos[j, 1]] -= t0[j, 1] * shift
            moved += 1
    return moved


def friction_normals(lam: np.ndarray, facet: np.ndarray) -> tuple[np.ndarray, float]:
    """The slave nodes' normal forces for their friction, and their scale s.

    The friction acts at the nodes with λ_k > 0 and a start-of-step master point
    (:func:`~breakwater.contact.forcekernels.friction`). Where the contact ends within
    a slave facet (a slave hanging over the master's end, a rocking body lifting off)
    the quadratic N_k of its far node is negative where the facet presses: λ_k < 0,
    left out, and the friction of the sliding pair exceeded μN (μ × 1.025 over a
    block hanging off its base, 1.044 at worst, 4 % at a push; found by a user). There
    the forces λ_k are scaled by s = Σλ / Σ_carried λ, so that sliding carries μN
    (Σλ is the pair's normal resultant). Elsewhere s = 1 and λ is returned itself; the
    Jacobian takes s as a constant (:meth:`~breakwater.contact.general.SurfaceForces.matrix`).

    Args:
        lam: The slave nodes' normal forces λ_k = ∫ p N_k.
        facet: Their start-of-step master facets (−1: none).
    """
    s = carried_scale(lam, facet)
    return (lam, 1.0) if s == 1.0 else (lam * s, s)


def slip_velocities_at(node_pos: np.ndarray, pos_m: np.ndarray, facet: np.ndarray,
                       N0: np.ndarray, k: np.ndarray, rel: np.ndarray, n: int
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Velocities at the interface unknowns that give slave nodes ``k`` the slip ``rel``.

    The slip of node k is its velocity relative to its master point,
    ``v_k − Σ_b N̄₀_b v_b`` (facet f₀ = ``facet[k]``, shape values ``N0[k]``). Where the
    node's DOFs are free it is its own velocity: ``v_k = rel_k + Σ_b N̄₀_b v_b``. Where a
    component d is held (a slave node on a ``[fixed]`` face, position −1), its slip is
    the master's alone, ``Σ_b N̄₀_b v_b,d = −rel_k,d``: the master nodes of f₀ then move,
    the smallest such velocities (least squares over every held component at once),
    and the free slave nodes on the faces they share keep their slip. Without them the
    static state's friction along a held component (the master slipping under the
    node: the support's Poisson expansion) had no slip in the dynamics, and its reaction
    on the master vanished at t = 0 (issue 25).

    Args:
        node_pos: The slave nodes' interface positions ``(nodes, gdim)`` (−1: held).
        pos_m: The master facets' ``(M, nm, gdim)``.
        facet: The slave nodes' master facets f₀.
        N0: Their shape values there ``(nodes, nm)``.
        k: The nodes given a slip.
        rel: Their slip velocities ``(len(k), gdim)``.
        n: The number of interface unknowns.

    Returns:
        The interface positions set and their velocities (flat, positions ≥ 0, unique).
    """
    y = np.zeros(n + 1)  # a trailing 0: the held entries (position −1)
    set_ = np.zeros(n + 1, bool)
    held = node_pos[k] < 0
    if held.any():
        rows, comp = np.nonzero(held)
        cols = pos_m[facet[k[rows]], :, comp]  # (rows, nm): the master DOFs of each
        weights = N0[k[rows]]
        free = np.unique(cols[cols >= 0])
        if len(free):
            A = np.zeros((len(rows), len(free)))
            at = np.searchsorted(free, np.maximum(cols, 0))
            for b in range(cols.shape[1]):
                ok = cols[:, b] >= 0
                np.add.at(A, (np.flatnonzero(ok), at[ok, b]), weights[ok, b])
            y[free] = np.linalg.lstsq(A, -rel[rows, comp], rcond=None)[0]
            set_[free] = True
    master = np.einsum("kb,kbd->kd", N0[k], y[pos_m[facet[k]]])
    pos = node_pos[k]
    y[pos[~held]] = (rel + master)[~held]
    set_[pos[~held]] = True
    set_[-1] = False
    where = np.flatnonzero(set_)
    return where, y[where]


def sliding_velocities(node_pos: np.ndarray, pos_m: np.ndarray, facet: np.ndarray,
                       N0: np.ndarray, T0: np.ndarray, k: np.ndarray, d: np.ndarray,
                       speed: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Velocities at the interface unknowns that start slave nodes ``k`` sliding along d.

    Each node's slip is ``speed`` along the tangential part of d at its master point,
    ``Σ_α (d·T₀_α) T₀_α`` (its own tangent: the slip of a body sliding along d), set by
    :func:`slip_velocities_at`: the node's free components move; a held one (a slave
    node on a ``[fixed]`` face, e.g. a roller) takes no velocity, and its share of the
    slip, ``−(d·n) n`` along it where d has no component along it (a body can slide
    only along its free directions), goes to the master face's nodes. That share is nil
    where the master's normal is perpendicular to the held direction (a roller face
    perpendicular to the interface: the node's whole slip is along its free
    components); a fully held slave node (a fixed support, the slave of a sliding
    master) gives its whole slip to the master. A node where d is normal to the master
    is left at rest.

    Args:
        node_pos: The slave nodes' interface positions ``(nodes, gdim)`` (−1: held).
        pos_m: The master facets'.
        facet: The slave nodes' master facets f₀.
        N0: Their shape values there.
        T0: Their tangent bases ``(nodes, gdim − 1, gdim)`` (orthonormal).
        k: The nodes started (in contact).
        d: The unit sliding direction of the slave relative to the master.
        speed: The slip speed.
        n: The number of interface unknowns.

    Returns:
        The interface positions set and their velocities (flat).
    """
    T = T0[k]
    along = np.einsum("ka,kad->kd", np.einsum("kad,d->ka", T, d), T)
    size = np.linalg.norm(along, axis=1)
    keep = size > 1e-12
    return slip_velocities_at(node_pos, pos_m, facet, N0, k[keep],
                              speed * along[keep] / size[keep, None], n)


@kernel
def carried_scale(lam, facet):  # type: ignore[no-untyped-def]
    """:func:`friction_normals`' scale s, compiled: one pass at every evaluation.

    1 unless a node's normal force is negative or presses without a master point and
    the carried forces (λ_k > 0 with a master point) have a positive sum; then
    ``max(Σλ, 0) / Σ_carried λ``.
    """
    total, share, uncarried = 0.0, 0.0, False
    for j in range(len(lam)):
        total += lam[j]
        if lam[j] < 0.0 or (lam[j] > 0.0 and facet[j] < 0):
            uncarried = True
        elif lam[j] > 0.0:
            share += lam[j]
    if not uncarried or share <= 0.0:
        return 1.0
    return max(total, 0.0) / share


def resolution(pair: SurfaceSearch, y: np.ndarray) -> float:
    """The round-off of a general pair's f_c at the iterate y.

    A sticking slave node's friction −μλφ(v_T) has the tangent μλφ'(v_T), up to μλ/χ,
    and v_T is a difference of velocities of order |v| + Δt|a| + β₁Δt|Δa| computed to
    their round-off ε (the unit round-off) each: its force carries
    ``μλ_k φ'(v_T) ε Σ|v|``, 1e-6 N/m on the Goda caisson rocking on its corner
    (μλ/χ = 6.5e11 N s/m², |v| 1e-2 m/s) where the Newton tolerance is 7e-8.

    Returns:
        The root sum of squares over the slave nodes in contact (0 without friction:
        the normal part's round-off, ε_n w ε |x| per point, stays below the
        tolerances the Newton meets).
    """
    if not pair.spec.friction:
        return 0.0
    u0, u1, v1 = pair._state(y)
    p = pair._normal(u1)
    _, _, mu, chi = pair._law
    if not len(p["index"]):
        return 0.0
    facet, N0, t0 = pair._frozen(u0)
    lam, _ = friction_normals(p["lam"], facet)
    k, v_T, _, _ = forcekernels.friction(lam, facet, N0, t0, pair._node_pos, pair._pm,
                                         v1, mu, chi, np.full(len(facet), np.nan))
    _, v, a, _ = pair._start(y)
    dt = pair.step_dt()
    return float(forcekernels.friction_round_off(
        k, v_T, lam, facet, N0, pair._node_pos, pair._pm, v, a, y, dt,
        pair.beta1 * dt, mu, chi, float(np.finfo(float).eps)))


class CrawlPoints:
    """A general pair's slip guard, with the slaves' crawl points between iterates.

    Where the guard finds a slip crawling along the saturated law, the next iterate's
    friction force at the node is the law's tangent line at a crawl point
    (:func:`~breakwater.contact.guardkernels.slip_guard`,
    :func:`~breakwater.contact.forcekernels.friction`) until :meth:`drop`. A node whose
    slip reverses takes crawl points closer to Newton's proposal until then
    (:data:`~breakwater.contact.guardkernels.REGROW`).

    A 3-D pair's crawl points are tangent vectors (``components`` = 2, in the tangent
    basis of the node's start-of-step master point) and its guard
    :func:`~breakwater.contact.friction3d.slip_guard` (``kernel``: the same arguments).

    Args:
        nodes: The slave nodes.
        components: The slip's components (1 in 2-D, 2 in 3-D).
        kernel: The guard (:func:`~breakwater.contact.guardkernels.slip_guard`'s
            arguments).

    Attributes:
        none: No crawl point (NaN at every node): the law itself.
        at: The current iterate's crawl points (NaN: none at the node).
        any: Whether ``at`` holds one.
        version: Counts the changes of ``at`` (a cache's key).
    """

    def __init__(self, nodes: int, components: int = 1,
                 kernel: Callable[..., int] = guardkernels.slip_guard) -> None:
        self.none = np.full(nodes if components == 1 else (nodes, components), np.nan)
        self._kernel = kernel
        self.at, self._next = self.none.copy(), self.none.copy()
        self.any = False
        self.version = 0
        self._bounds = np.full(nodes, guardkernels.FREE, np.int8)

    def guard(self, step: np.ndarray, v1: np.ndarray, frozen: tuple[np.ndarray, ...],
              node_pos: np.ndarray, pos_m: np.ndarray, dv: float, chi: float,
              acts: np.ndarray) -> int:
        """The slip guard on Newton's step (in place); the crawl points of the next iterate.

        Args:
            step: Newton's step, cut in place.
            v1: The iterate's velocities at the interface unknowns (a trailing 0).
            frozen: The slave nodes' start-of-step master facet, N̄₀ and t₀ (T₀ in 3-D).
            node_pos: The slave nodes' interface positions.
            pos_m: The master facets'.
            dv: β₁Δt.
            chi: χ.
            acts: The nodes where the guard acts (:func:`~.coupling.guarded_nodes`).

        Returns:
            The nodes whose step changed.
        """
        facet, N0, t0 = frozen
        fixed = int(self._kernel(step, v1, facet, N0, t0, node_pos, pos_m, dv, chi, self.at,
                                 self._next, self._bounds, acts))
        self.at, self._next = self._next, self.at
        self.any = not np.isnan(self.at).all()
        self.version += 1
        return fixed

    def drop(self, allowed: bool = True) -> bool:
        """No crawl points from now on; new ones allowed at every node or at none.

        Returns:
            Whether there were any.
        """
        was = self.any
        if was:
            self.at.fill(np.nan)
            self.any = False
            self.version += 1
        self._bounds.fill(guardkernels.FREE if allowed else guardkernels.NONE)
        return was


def slip_guard(pair: Any, x: np.ndarray, step: np.ndarray,
               frozen_at: Callable[[np.ndarray], tuple[np.ndarray, ...]],
               bulk: coupling.BulkStiffness | None) -> int:
    """A general pair's slip guard on Newton's step at the iterate x (its ``precheck``).

    :meth:`CrawlPoints.guard` at the nodes where the law sets the slip
    (:func:`~.coupling.guarded_nodes`, from the nodes' friction normal forces at x).

    Args:
        pair: The pair (a 2-D or 3-D general pair's forces, with friction; its ``crawl``).
        x: The iterate (Δa at the interface unknowns).
        step: Newton's step, cut in place.
        frozen_at: The slave nodes' start-of-step master points at u₀.
        bulk: The bulk's stiffness on the unknowns (None: the guard acts everywhere).

    Returns:
        The nodes whose step changed.
    """
    u0, u1, v1 = pair._state(x)
    frozen = frozen_at(u0)
    _, _, mu, chi = pair._law
    dv = pair.beta1 * pair.step_dt()
    lam, _ = friction_normals(pair._normal(u1)["lam"], frozen[0])
    acts = coupling.guarded_nodes(lam, mu * dv / chi, bulk, pair._node_pos, frozen[2])
    return int(pair.crawl.guard(step, v1, frozen, pair._node_pos, pair._pm, dv, chi, acts))


class Regularised:
    """A general pair's ``regularise``: its friction law with χ stretched (a mixin).

    The interface Newton's continuation (:mod:`breakwater.stepping.continuation`)
    replaces ``law`` by the law of ``spec`` with χ times the stretch, and puts it back at
    1 (a static stage may have replaced both,
    :meth:`~breakwater.statics.pseudostep.PseudoStepper.friction`: the stretch applies
    to the stage's law).
    """

    law: forms.ContactLaw
    spec: SurfacePair
    _own_law: forms.ContactLaw | None = None  # the law while stretched

    def regularise(self, stretch: float) -> bool:
        """The friction's χ times ``stretch`` from now on (1: the law's own).

        Returns:
            Whether the pair has friction.
        """
        if self._own_law is not None:
            self.law, self._own_law = self._own_law, None
        if stretch != 1.0:
            self._own_law = self.law
            self.law = forms.ContactLaw.of(dataclasses.replace(
                self.spec, regularisation=self.spec.regularisation * stretch))
        return bool(self.spec.friction)
