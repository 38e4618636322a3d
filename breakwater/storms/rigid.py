"""The rigid-block sliding model of a caisson (Shimosako & Takahashi 1994, 1999).

The caisson is a rigid block on its mound, held by Coulomb friction μ. While it slides
landward (Shimosako & Takahashi 1999; Takahashi 2002, "Design of vertical breakwaters",
§4.5; Goda & Takagi 2000)::

    (M + M_a) ẍ = P(t) − μ (W' − U(t))

with M the caisson's mass per metre, W' = M g − ρ g B h' its weight in still water
(buoyancy of a rectangular section of width B submerged to the toe depth h'), P(t) the
horizontal wave force and U(t) the uplift (:mod:`breakwater.storms.waveforce`), and
M_a the added mass of the water on the caisson's faces::

    M_a = 1.0855 ρ h'²

the value the sources above use as we know it from the literature restating them (we
could not read the originals here), and which we verified to be Westergaard's added mass
of a rigid wall of draft h' accelerated in still water, on its two faces: one face carries
Σ_n 2ρh'²/λ_n³ = 14 ζ(3)/π³ ρh'² = 0.5427 ρh'² (λ_n = (2n − 1)π/2), two faces
28 ζ(3)/π³ = 1.0855 (tests/test_storms_rigid.py checks the number). The finite-element
model has no water: ``Caisson(added_mass=False)`` drops M_a for the FE-vs-rigid comparison.

From rest the block stays while P <= μ (W' − U) (static friction at the same μ); it
starts when the net force R = P − μ(W' − U) becomes positive and stops when its velocity
returns to 0. Only landward sliding is modelled, as the sources do: a seaward net force
(the wave trough, here not in the load) never moves the block. Each wave is computed
from rest: the block must stop before the next wave begins (checked, else refused).

**Integration.** R(t) is piecewise smooth: a history's ``breakpoints`` attribute (if
any: :class:`~breakwater.storms.waveforce.PulseHistory` has one) lists where it is not,
and the time axis is cut there and into panels of at most duration/64. On each panel,
v and x are integrated by 8-point Gauss–Legendre quadrature (exact for polynomials of
degree 15; a sine over 1/64 of its half period to round-off; for a history without
``breakpoints`` adaptively: each panel halved at least twice, then until the halves
agree with the whole to 1e-12 of the integrand's terms, which resolves a kink inside a
panel at the cost of more evaluations)::

    v(t) = v(a) + (1/m') ∫_a^t R ds
    x(b) = x(a) + v(a)(b − a) + (1/m') ∫_a^b (b − s) R(s) ds

The start (R = 0) and the stop (v = 0) are found by bisection to round-off (events, not
a fixed step) between samples of R or v at 9 points per panel; where no sample crosses
but the samples' second differences allow a hidden excursion across 0 between them
(a smooth f exceeds its samples by at most h²/8 max|f''| ≈ |Δ²f|/8; we search when
within |Δ²f|), the panel's extremum is located by golden-section search first. After
the load ends R = −μW' and the stop is closed-form: x += v² m'/(2μW').
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from breakwater.config.typecheck import check_fields
from breakwater.storms.waveforce import ForceProfile, wave_load
from breakwater.storms.waves import Site, WaveLoad, WaveTrain

__all__ = ["ADDED_MASS_COEFFICIENT", "Caisson", "Slide", "slide", "slide_motion",
           "storm_sliding"]

ADDED_MASS_COEFFICIENT = 1.0855
"""M_a / (ρ h'²): Westergaard's added mass of a wall's two faces (module docstring)."""

_PANELS = 64
_SAMPLES = 8
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(8)


@dataclass(frozen=True)
class Caisson:
    """A caisson per metre of breakwater, for the rigid-block model.

    Attributes:
        mass: M, the caisson's mass per metre in air, fill included (kg/m).
        base_width: B (m).
        toe_depth: h', the depth of its base below the still water level (m): buoyancy
            ρ g B h' and the added mass.
        friction: μ between the caisson and the mound.
        added_mass: Include M_a = 1.0855 ρ h'² (False: the FE model's dry block).
        density: Water density ρ (kg/m³).
        gravity: g (m/s²).
        weight: W' given (N/m), e.g. a finite-element model's static normal force on
            the mound (its weight less the buoyancy loads it applies); None:
            M g − ρ g B h'.

    Raises:
        ValueError: A field out of range, or W' <= 0 (the caisson floats), naming it.

    """

    mass: float
    base_width: float
    toe_depth: float
    friction: float
    added_mass: bool = True
    density: float = 1025.0
    gravity: float = 9.81
    weight: float | None = None

    def __post_init__(self) -> None:
        check_fields(self, ValueError)  # added_mass="no" was true, mass="1" a TypeError
        for name in ("mass", "base_width", "friction", "density", "gravity"):
            value = getattr(self, name)
            if not (value > 0 and math.isfinite(value)):
                raise ValueError(f"{name}: must be > 0 (got {value!r})")
        if not (self.toe_depth >= 0 and math.isfinite(self.toe_depth)):
            raise ValueError(f"toe_depth: must be >= 0 (got {self.toe_depth!r})")
        if self.weight is not None and not (self.weight > 0 and math.isfinite(self.weight)):
            raise ValueError(f"weight: W' must be > 0 (got {self.weight!r})")
        if not self.submerged_weight > 0:
            raise ValueError(f"mass: M g = {self.mass * self.gravity:.4g} N/m does not "
                             f"exceed the buoyancy ρ g B h' = {self.buoyancy:.4g} N/m: the "
                             "caisson floats")

    @property
    def buoyancy(self) -> float:
        """ρ g B h' (N/m)."""
        return self.density * self.gravity * self.base_width * self.toe_depth

    @property
    def submerged_weight(self) -> float:
        """W' = M g − ρ g B h' (N/m), or ``weight`` when given."""
        if self.weight is not None:
            return self.weight
        return self.mass * self.gravity - self.buoyancy

    @property
    def moving_mass(self) -> float:
        """The moving mass m' = M + M_a (kg/m), M_a = 1.0855 ρ h'² when ``added_mass``."""
        extra = ADDED_MASS_COEFFICIENT * self.density * self.toe_depth**2
        return self.mass + (extra if self.added_mass else 0.0)


@dataclass(frozen=True)
class Slide:
    """One wave's sliding.

    Attributes:
        distance: The landward sliding (m), >= 0.
        start: When sliding began (s since the wave's force began; None: no sliding).
        stop: When it stopped (s; None: no sliding).

    """

    distance: float
    start: float | None = None
    stop: float | None = None


def _gauss(f: Callable[[float], float], a: float, b: float) -> float:
    """∫_a^b f by 8-point Gauss–Legendre."""
    half, mid = 0.5 * (b - a), 0.5 * (a + b)
    return half * sum(w * f(mid + half * x) for x, w in zip(_NODES, _WEIGHTS, strict=True))


def _adaptive(f: Callable[[float], float], a: float, b: float, whole: float, tol: float,
              depth: int = 0) -> float:
    """∫_a^b f, halving until the halves agree with the whole within ``tol`` (kinks)."""
    m = 0.5 * (a + b)
    left, right = _gauss(f, a, m), _gauss(f, m, b)
    if depth >= 30 or not a < m < b or (depth >= 2 and abs(left + right - whole) <= tol):
        return left + right  # depth >= 2: two halvings before a chance agreement counts
    return (_adaptive(f, a, m, left, tol, depth + 1)  # the same tol: round-off is
            + _adaptive(f, m, b, right, tol, depth + 1))  # absolute, not halved


def _integrator(smooth: bool
                ) -> Callable[[Callable[[float], float], float, float, float], float]:
    """Gauss–Legendre on a smooth panel, else adaptive (a history without breakpoints).

    The adaptive tolerance is 1e-12 (b − a) (max|f| at the nodes + ``level``), ``level``
    the size of the terms of the integrand (μW' for R = P − μ(W' − U)): relative to the integrand's
    scale, not to the integral, which may be 0, nor to R alone, whose round-off is that
    of its terms (just after sliding starts R ≈ 0).
    """
    if smooth:
        return lambda f, a, b, level: _gauss(f, a, b)

    def integral(f: Callable[[float], float], a: float, b: float, level: float) -> float:
        half, mid = 0.5 * (b - a), 0.5 * (a + b)
        values = [f(mid + half * x) for x in _NODES]
        whole = half * sum(w * v for w, v in zip(_WEIGHTS, values, strict=True))
        scale = abs(b - a) * (max(abs(v) for v in values) + level)
        return _adaptive(f, a, b, whole, 1e-12 * scale)

    return integral


def _bisect(f: Callable[[float], float], lo: float, hi: float) -> float:
    """The t in (lo, hi] where f turns positive (f(lo) <= 0 < f(hi)), to round-off."""
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if not lo < mid < hi:
            break
        if f(mid) > 0.0:
            hi = mid
        else:
            lo = mid
    return hi


def _first_positive(f: Callable[[float], float], a: float, b: float) -> float | None:
    """The first t in [a, b] where f > 0 (module docstring), or None."""
    ts = np.linspace(a, b, _SAMPLES + 1)
    fs = [f(float(t)) for t in ts]
    for i, value in enumerate(fs):
        if value > 0.0:
            return float(ts[0]) if i == 0 else _bisect(f, float(ts[i - 1]), float(ts[i]))
    d2 = max(abs(fs[i - 1] - 2.0 * fs[i] + fs[i + 1]) for i in range(1, _SAMPLES))
    k = int(np.argmax(fs))
    if fs[k] + d2 <= 0.0:
        return None
    lo, hi = float(ts[max(k - 1, 0)]), float(ts[min(k + 1, _SAMPLES)])
    left = lo
    g = (math.sqrt(5.0) - 1.0) / 2.0  # golden-section search for the maximum
    c, d = hi - g * (hi - lo), lo + g * (hi - lo)
    fc, fd = f(c), f(d)
    for _ in range(80):
        if max(fc, fd) > 0.0 or hi - lo <= 1e-15 * max(abs(hi), 1.0):
            break
        if fc > fd:
            hi, d, fd = d, c, fc
            c = hi - g * (hi - lo)
            fc = f(c)
        else:
            lo, c, fc = c, d, fd
            d = lo + g * (hi - lo)
            fd = f(d)
    top = c if fc > fd else d
    return _bisect(f, left, top) if max(fc, fd) > 0.0 else None


def _sliding(R: Callable[[float], float], integral: Callable[..., float], v0: float,
             a: float, b: float, m: float, level: float) -> tuple[float | None, float, float]:
    """Slide from a (velocity v0) to b or to the stop: (the stop or None, Δx, v at the end).

    ``level``: μW', the size of the terms of R (the adaptive integral's tolerance).
    """
    t_stop = _first_positive(lambda t: -(v0 + integral(R, a, t, level) / m), a, b)
    end = b if t_stop is None else t_stop
    dx = v0 * (end - a) + integral(lambda s: (end - s) * R(s), a, end, level * (end - a)) / m
    v = 0.0 if t_stop is not None else v0 + integral(R, a, b, level) / m
    return t_stop, dx, v


def _panels(load: WaveLoad) -> list[float]:
    """The panel ends over [0, duration]: the histories' breakpoints, refined."""
    T = load.duration
    cuts = {0.0, T}
    for history in (load.p1, load.uplift):
        cuts.update(t for t in getattr(history, "breakpoints", ()) if 0.0 < t < T)
    ends = sorted(cuts)
    out = [0.0]
    for a, b in itertools.pairwise(ends):
        n = max(1, math.ceil((b - a) / T * _PANELS))
        out.extend(a + (b - a) * k / n for k in range(1, n + 1))
    return out


def slide_motion(load: WaveLoad, caisson: Caisson) -> Slide:
    """One wave's sliding from rest, with its start and stop (module docstring).

    Raises:
        ValueError: The uplift reaches the submerged weight (the caisson lifts off:
            outside the sliding model).

    """
    wave_force = sum(0.5 * (s0 + s1) * (z1 - z0)
                     for (z0, s0), (z1, s1) in zip(load.front, load.front[1:], strict=False))
    μ, W, B, m = (caisson.friction, caisson.submerged_weight, caisson.base_width,
                  caisson.moving_mass)

    def R(τ: float) -> float:
        U = 0.5 * B * load.uplift(τ)
        if U >= W:  # a history without a peak: checked where it is evaluated
            raise ValueError(f"the uplift U = {U:.4g} N/m at τ = {τ:.4g} s reaches the "
                             f"submerged weight W' = {W:.4g} N/m: the caisson lifts off "
                             "(outside the sliding model)")
        return wave_force * load.p1(τ) - μ * (W - U)

    peaks = [getattr(h, "peak", None) for h in (load.p1, load.uplift)]
    if peaks[1] is not None and 0.5 * B * peaks[1] >= W:
        raise ValueError(f"the uplift U = {0.5 * B * peaks[1]:.4g} N/m reaches the "
                         f"submerged weight W' = {W:.4g} N/m: the caisson lifts off "
                         "(outside the sliding model)")
    if peaks[0] is not None and peaks[1] is not None \
            and wave_force * peaks[0] + μ * 0.5 * B * peaks[1] <= μ * W:
        return Slide(0.0)  # R <= 0 throughout: no sliding (the common case, fast)
    ends = _panels(load)
    smooth = all(hasattr(h, "breakpoints") for h in (load.p1, load.uplift))
    integral = _integrator(smooth)
    v = x = 0.0
    start: float | None = None
    stop: float | None = None
    sliding = False
    for a, b in itertools.pairwise(ends):
        while a < b:
            if not sliding:
                t = _first_positive(R, a, b)
                if t is None:
                    break
                sliding, a = True, t
                start = t if start is None else start
                continue
            t_stop, dx, v = _sliding(R, integral, v, a, b, m, μ * W)
            x += dx
            sliding = t_stop is None
            if t_stop is not None:
                stop = a = t_stop
            else:
                a = b
    if sliding:  # still moving when the load ends: R = −μW' from then on
        deceleration = μ * W / m
        x += v * v / (2.0 * deceleration)
        stop = load.duration + v / deceleration
    if start is None:
        return Slide(0.0)
    return Slide(float(max(x, 0.0)), float(start), None if stop is None else float(stop))


def slide(load: WaveLoad, caisson: Caisson) -> float:
    """The landward sliding (m) of the caisson under one wave, from rest."""
    return slide_motion(load, caisson).distance


def storm_sliding(train: WaveTrain, site: Site, caisson: Caisson,
                  profile: ForceProfile | None = None) -> np.ndarray:
    """The cumulative sliding (m) after each wave of a storm, each wave from rest.

    Args:
        train: The storm's waves.
        site: The site (Goda's geometry); its ``base_width`` and ``toe_depth`` must be
            the caisson's.
        caisson: The caisson.
        profile: The force-time profile's durations (default
            :class:`~breakwater.storms.waveforce.ForceProfile`).

    Returns:
        The sliding after waves 1..N (m), non-decreasing.

    Raises:
        ValueError: The site and the caisson disagree, or a wave's sliding does not stop
            before the next wave begins (the from-rest assumption fails).

    """
    for name in ("base_width", "toe_depth"):
        if not math.isclose(getattr(site, name), getattr(caisson, name), rel_tol=1e-12):
            raise ValueError(f"{name}: the site has {getattr(site, name):g} m, the "
                             f"caisson {getattr(caisson, name):g} m")
    out = np.empty(len(train))
    total = 0.0
    for k, wave in enumerate(train.waves):
        load = wave_load(wave, site, profile)
        motion = slide_motion(load, caisson)
        if motion.stop is not None and k + 1 < len(train) \
                and wave.start + motion.stop > train.waves[k + 1].start:
            raise ValueError(f"wave {k + 1} (H = {wave.height:.3g} m): the caisson still "
                             f"slides when wave {k + 2} begins; the wave-by-wave "
                             "(from rest) model does not hold")
        total += motion.distance
        out[k] = total
    return out
