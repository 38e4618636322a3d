"""Spatial traction fields of the surface loads: UFL expressions of x and the normal.

A surface load is ``amplitude(t) × field`` (:class:`breakwater.model.model.SurfaceLoad`):
the field is the traction (Pa) per unit amplitude, a fixed UFL expression of the
position ``x`` and of the outward unit normal ``n`` of the loaded body, so that the
fast solver assembles each load once at unit amplitude. A constant traction is the
load's ``direction`` vector itself; the fields here (frozen dataclasses;
``traction(x, n)`` gives the UFL vector) are

- :class:`Pressure`: a uniform pressure p normal to the surface, **positive pushing
  into the body** (traction −p n);
- :class:`PressureProfile`: a pressure p(s) varying along the surface, linear between
  given points (s, p), zero outside them, with s = (x − origin)·axis the coordinate
  along a unit axis (e.g. the elevation y for ``axis = (0, 1)``).

A field may also change at given times (:class:`StagedField`, "a field that can change
at given times"): its traction is a UFL expression of parameters held in one
``fem.Constant`` that the model sets at the start of each stage, so that its compiled
forms stay and only the assembled vectors are redone then
(:meth:`breakwater.model.residual.ModelForms.set_time`). :class:`StagedProfile` is a
pressure profile whose points change from stage to stage (a storm's front pressure,
wave by wave: :mod:`breakwater.storms`).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:  # ufl when a field is assembled: a case file is read without it
    import ufl

__all__ = ["Pressure", "PressureProfile", "StagedField", "StagedProfile", "TractionField"]


class TractionField(Protocol):
    """A traction field per unit amplitude."""

    def traction(self, x: ufl.core.expr.Expr, n: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
        """The traction (Pa) at position ``x`` where the outward normal is ``n``."""


@dataclass(frozen=True)
class Pressure:
    """A uniform pressure (Pa) normal to the surface, positive into the body."""

    value: float = 1.0

    def traction(self, x: ufl.core.expr.Expr, n: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
        """−p n."""
        return -self.value * n


def _along(x: ufl.core.expr.Expr, origin: tuple[float, ...], axis: tuple[float, ...]
           ) -> ufl.core.expr.Expr:
    """The coordinate s = (x − origin)·axis along a profile, as a UFL expression.

    The axis's components are the first coordinates': a 2D axis in 3D measures s in the
    x-y plane (the elevation y of (0, 1) in both).
    """
    import ufl

    xs = ufl.as_vector([x[i] for i in range(len(axis))])
    return ufl.dot(xs - ufl.as_vector(origin), ufl.as_vector(axis))


@dataclass(frozen=True)
class PressureProfile:
    """A pressure p(s) (Pa, positive into the body), linear between points, 0 outside.

    Attributes:
        points: (s, p) pairs with increasing s (m, Pa); at least two.
        axis: Direction along which s is measured (normalised here).
        origin: The point where s = 0 (m).

    """

    points: tuple[tuple[float, float], ...]
    axis: tuple[float, ...] = (0.0, 1.0)
    origin: tuple[float, ...] = (0.0, 0.0)

    def __post_init__(self) -> None:
        if len(self.points) < 2 or any(len(p) != 2 for p in self.points):
            raise ValueError("a pressure profile needs at least two (s, p) points")
        s = [p[0] for p in self.points]
        for k in range(1, len(s)):
            if not s[k] > s[k - 1]:
                raise ValueError(f"profile coordinates must increase (point {k}: "
                                 f"s = {s[k]:g} after s = {s[k - 1]:g})")
        norm = math.hypot(*self.axis)
        if not norm > 0 or len(self.axis) != len(self.origin):
            raise ValueError("the profile axis must be a non-zero vector of the dimension "
                             "of the origin")
        object.__setattr__(self, "axis", tuple(c / norm for c in self.axis))

    def coordinate(self, x: np.ndarray) -> np.ndarray:
        """The coordinate s of points ``x`` (rows; numpy)."""
        x = np.asarray(x, dtype=float)[..., :len(self.axis)]
        return (x - np.asarray(self.origin)) @ np.asarray(self.axis)

    def pressure(self, s: np.ndarray | float) -> np.ndarray:
        """p(s) (numpy): linear between the points, 0 outside them."""
        s_k = [p[0] for p in self.points]
        p_k = [p[1] for p in self.points]
        s = np.asarray(s, dtype=float)
        inside = (s >= s_k[0]) & (s <= s_k[-1])
        return np.where(inside, np.interp(s, s_k, p_k), 0.0)

    def ufl_pressure(self, x: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
        """p(s(x)) as a UFL expression (a sum of one linear piece per interval)."""
        import ufl

        s = _along(x, self.origin, self.axis)
        p: ufl.core.expr.Expr = ufl.as_ufl(0.0)
        pts = self.points
        for k in range(len(pts) - 1):
            (s0, p0), (s1, p1) = pts[k], pts[k + 1]
            upper = ufl.le(s, s1) if k == len(pts) - 2 else ufl.lt(s, s1)
            piece = p0 + (p1 - p0) / (s1 - s0) * (s - s0)
            p = p + ufl.conditional(ufl.And(ufl.ge(s, s0), upper), piece, 0.0)
        return p

    def traction(self, x: ufl.core.expr.Expr, n: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
        """−p(s) n."""
        return -self.ufl_pressure(x) * n


@runtime_checkable
class StagedField(Protocol):
    """A traction field per unit amplitude that changes at given times.

    Stage k holds for ``times[k] <= t < times[k + 1]`` (stage 0 also before
    ``times[0]``); its parameters (``size`` numbers) are the values of one
    ``fem.Constant`` of shape ``(size,)`` that :meth:`traction_with` reads.
    """

    @property
    def size(self) -> int:
        """The number of parameters."""

    def stage(self, t: float) -> int:
        """The stage holding time ``t``."""

    def parameters(self, stage: int) -> tuple[float, ...]:
        """The parameters of a stage (``size`` numbers)."""

    def traction_with(self, x: ufl.core.expr.Expr, n: ufl.core.expr.Expr,
                      c: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
        """The traction at ``x`` (outward normal ``n``) for the parameters ``c``."""


@dataclass(frozen=True)
class StagedProfile:
    """A pressure profile (:class:`PressureProfile`) whose points change at given times.

    Every stage has the same number K of points (a profile with fewer is refined at
    the midpoints of its longest intervals: the same function); the parameters are
    the K coordinates then the K pressures.

    Attributes:
        stages: Each stage's (s, p) points, increasing s (m, Pa).
        times: When each stage begins (s), increasing; stage 0 also before.
        axis: Direction along which s is measured (normalised here).
        origin: The point where s = 0 (m).

    """

    stages: tuple[tuple[tuple[float, float], ...], ...]
    times: tuple[float, ...]
    axis: tuple[float, ...] = (0.0, 1.0)
    origin: tuple[float, ...] = (0.0, 0.0)

    def __post_init__(self) -> None:
        if not self.stages or len(self.stages) != len(self.times):
            raise ValueError("a staged profile needs one start time per stage (at least one)")
        if any(not t1 > t0 for t0, t1 in zip(self.times, self.times[1:], strict=False)):
            raise ValueError("the stages' start times must increase")
        profiles = [PressureProfile(tuple(points), self.axis, self.origin)
                    for points in self.stages]  # each stage's own checks
        k = max(len(p.points) for p in profiles)
        object.__setattr__(self, "stages", tuple(_refine(p.points, k) for p in profiles))
        object.__setattr__(self, "axis", profiles[0].axis)

    @property
    def size(self) -> int:
        """2K: the K coordinates, then the K pressures."""
        return 2 * len(self.stages[0])

    def stage(self, t: float) -> int:
        """The last stage begun at ``t`` (0 before the first)."""
        # (bisect on the tuple: NumPy's searchsorted took 30 µs converting a storm's
        # thousand stage times to an array at every step.)
        return max(0, bisect.bisect_right(self.times, t) - 1)

    def profile(self, stage: int) -> PressureProfile:
        """A stage's pressure profile."""
        return PressureProfile(self.stages[stage], self.axis, self.origin)

    def parameters(self, stage: int) -> tuple[float, ...]:
        """The coordinates, then the pressures, of a stage's points."""
        points = self.stages[stage]
        return tuple(p[0] for p in points) + tuple(p[1] for p in points)

    def traction_with(self, x: ufl.core.expr.Expr, n: ufl.core.expr.Expr,
                      c: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
        """−p(s) n, the points read from ``c`` (as :meth:`PressureProfile.ufl_pressure`)."""
        import ufl

        k = len(self.stages[0])
        s = _along(x, self.origin, self.axis)
        p: ufl.core.expr.Expr = ufl.as_ufl(0.0)
        for j in range(k - 1):
            s0, s1, p0, p1 = c[j], c[j + 1], c[k + j], c[k + j + 1]
            upper = ufl.le(s, s1) if j == k - 2 else ufl.lt(s, s1)
            piece = p0 + (p1 - p0) / (s1 - s0) * (s - s0)
            p = p + ufl.conditional(ufl.And(ufl.ge(s, s0), upper), piece, 0.0)
        return -p * n


def _refine(points: tuple[tuple[float, float], ...], k: int) -> tuple[tuple[float, float], ...]:
    """The same piecewise-linear profile on ``k`` points: the longest intervals halved."""
    out = [(float(s), float(p)) for s, p in points]
    while len(out) < k:
        j = max(range(len(out) - 1), key=lambda i: out[i + 1][0] - out[i][0])
        (s0, p0), (s1, p1) = out[j], out[j + 1]
        out.insert(j + 1, (0.5 * (s0 + s1), 0.5 * (p0 + p1)))
    return tuple(out)
