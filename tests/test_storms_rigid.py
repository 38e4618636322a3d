"""The rigid-block sliding model against closed forms (Coulomb friction, Newton's law).

A block of mass m on a floor with friction μ under a normal force N (here N = W' = M g −
ρ g B h', the weight in still water) pushed by F(t): it starts when F > μN and
m ẍ = F − μN while it slides, until ẋ = 0 (Shimosako & Takahashi 1999's model).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
from numpy.polynomial import Polynomial as Poly

from breakwater.storms.rigid import (
    ADDED_MASS_COEFFICIENT,
    Caisson,
    slide,
    slide_motion,
    storm_sliding,
)
from breakwater.storms.seastate import SeaState, wave_train
from breakwater.storms.waveforce import PulseHistory, wave_load
from breakwater.storms.waves import Site, Wave, WaveLoad, WaveTrain

pytestmark = pytest.mark.serial  # arrays alone (no MPI): once is enough

UNIT = ((-1.0, 1.0), (0.0, 1.0))  # front shape with ∫ s dz = 1 m: P = p₁


@dataclass(frozen=True)
class Rect:
    """F for 0 <= τ < duration."""

    value: float
    duration: float

    def __call__(self, τ: float) -> float:
        return self.value if 0.0 <= τ < self.duration else 0.0

    @property
    def breakpoints(self) -> tuple[float, ...]:
        return (0.0, self.duration)

    @property
    def peak(self) -> float:
        return self.value


def _load(p1, duration: float, uplift=None) -> WaveLoad:
    return WaveLoad(Wave(1.0, 10.0), UNIT, p1, uplift or Rect(0.0, duration), duration)


def _block(mass=1000.0, μ=0.6, toe_depth=0.0, added_mass=False) -> Caisson:
    return Caisson(mass=mass, base_width=1.0, toe_depth=toe_depth, friction=μ,
                   added_mass=added_mass, density=1000.0, gravity=9.81)


@pytest.mark.parametrize("added_mass", [False, True])
def test_rectangular_pulse(added_mass):
    """d = ½ a τ² + (aτ)²/(2 μ g'), a = (F₀ − μN)/m', g' = N/m' (m' = M + M_a).

    Derivation: under F₀ the block accelerates at a from rest for τ (d₁ = ½aτ², v = aτ),
    then decelerates at μN/m' = μg' to rest: d₂ = v²/(2μg'). Tolerance 1e-6 (the
    quadrature is exact for the constant force: round-off).
    """
    c = _block(toe_depth=0.5, added_mass=added_mass)
    N, m = c.submerged_weight, c.moving_mass
    F0, τ = 2.0 * 0.6 * N, 0.3
    a = (F0 - 0.6 * N) / m
    g_ = N / m
    expected = 0.5 * a * τ**2 + (a * τ) ** 2 / (2.0 * 0.6 * g_)
    motion = slide_motion(_load(Rect(F0, τ), τ), c)
    assert motion.distance == pytest.approx(expected, rel=1e-6)
    assert motion.start == 0.0
    assert motion.stop == pytest.approx(τ + a * τ / (0.6 * g_), rel=1e-9)
    assert (m > c.mass) == added_mass


def test_no_sliding_at_or_below_friction():
    c = _block()
    N = c.submerged_weight
    for F0 in (0.5 * 0.6 * N, 0.6 * N):
        assert slide(_load(Rect(F0, 0.3), 0.3), c) == 0.0
    # a load without peak attributes takes the full path, with the same answer
    assert slide(_load(lambda τ: 0.6 * N if 0 <= τ < 0.3 else 0.0, 0.3), c) == 0.0
    # uplift lowers the friction: μ(N − U) < F₀ < μN slides
    uplift = Rect(2.0 * 0.2 * N, 0.3)  # U = ½ p_u B = 0.2 N
    assert slide(_load(Rect(0.9 * 0.6 * N, 0.3), 0.3, uplift), c) > 0.0


def test_triangular_pulse():
    """A symmetric triangle of peak F₀ and base τ against the piecewise-polynomial solution.

    F = 2F₀ t/τ on [0, τ/2], 2F₀ (1 − t/τ) on [τ/2, τ], 0 after; sliding starts at
    t_s = μN τ/(2F₀), m v̇ = F − μN; v and x are polynomials on each piece (integrated
    exactly with numpy's Polynomial), the stop is the root of v. Tolerance 1e-9.
    """
    c = _block()
    N, m, μ = c.submerged_weight, c.mass, 0.6
    F0, τ = 3.0 * μ * N, 0.4
    t = Poly([0.0, 1.0])
    pieces = [(2 * F0 / τ * t - μ * N, 0.5 * τ), (2 * F0 * (1 - t / τ) - μ * N, τ),
              (0.0 * t - μ * N, math.inf)]
    ts = μ * N * τ / (2 * F0)
    v0, x0, lo = 0.0, 0.0, ts
    for force, hi in pieces:
        acc = force / m
        v = acc.integ(lbnd=lo) + v0
        x = v.integ(lbnd=lo) + x0
        roots = [r.real for r in v.roots() if abs(r.imag) < 1e-12 and lo < r.real <= hi]
        if roots:
            expected = x(min(roots))
            stop = min(roots)
            break
        v0, x0, lo = v(hi), x(hi), hi
    motion = slide_motion(_load(PulseHistory(0.0, F0, τ, τ), τ), c)
    assert motion.start == pytest.approx(ts, rel=1e-12)
    assert motion.stop == pytest.approx(stop, rel=1e-9)
    assert motion.distance == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("base", [0.4, 0.002])
def test_history_without_breakpoints(base):
    """A history with no ``breakpoints`` (e.g. tabulated) is integrated adaptively.

    A triangle of base ``base`` off the panel grid (centre 0.2031 s) on a hump at half the
    friction: with 0.002 s it crosses μN only between the 9 samples of a panel (the
    golden-section search must find it). Against the same history with its breakpoints
    (exact quadrature) to 1e-9 (the adaptive tolerance is 1e-12 of the terms).
    """
    c = _block()
    N = c.submerged_weight

    @dataclass(frozen=True)
    class Bumped:
        def __call__(self, τ: float) -> float:
            if not 0.0 <= τ < 0.4:
                return 0.0
            return 0.3 * N + 0.42 * N * max(0.0, 1.0 - abs(τ - 0.2031) / (0.5 * base))

    class WithBreaks(Bumped):
        breakpoints = (0.0, 0.2031 - 0.5 * base, 0.2031, 0.2031 + 0.5 * base, 0.4)

    exact = slide_motion(_load(WithBreaks(), 0.4, Rect(0.0, 0.4)), c)
    generic = slide_motion(_load(Bumped(), 0.4, lambda τ: 0.0), c)
    assert exact.distance > 0.0
    assert generic.distance == pytest.approx(exact.distance, rel=1e-9)
    assert generic.start == pytest.approx(exact.start, rel=1e-12)


def test_added_mass_coefficient():
    """Westergaard's two-face added mass 28 ζ(3)/π³ ρh'² = 1.0855 ρh'² (rigid module)."""
    ζ3 = sum(1.0 / n**3 for n in range(1, 200_000))
    assert 28.0 * ζ3 / math.pi**3 == pytest.approx(ADDED_MASS_COEFFICIENT, abs=5e-5)
    c = _block(mass=5000.0, toe_depth=2.0, added_mass=True)
    assert c.moving_mass == pytest.approx(5000.0 + 1.0855 * 1000.0 * 4.0)


def test_caisson_refused():
    with pytest.raises(ValueError, match=r"^friction"):
        _block(μ=0.0)
    c = _block()
    lift = 2.0 * c.submerged_weight  # U = ½ p_u B = W'
    for uplift in (Rect(lift, 0.3), lambda τ: lift if 0 <= τ < 0.3 else 0.0):
        with pytest.raises(ValueError, match=r"^the uplift U = .* lifts off"):
            slide(_load(Rect(0.9 * c.submerged_weight, 0.3), 0.3, uplift), c)
    with pytest.raises(ValueError, match=r"^mass: .* floats"):
        Caisson(mass=1000.0, base_width=1.0, toe_depth=2.0, friction=0.6, density=1000.0)


def test_storm_sliding_is_the_sum_of_the_waves():
    site = Site(depth=20.0, toe_depth=14.5, berm_depth=11.0, crest_height=5.0,
                base_width=20.0)
    c = Caisson(mass=2100.0 * 20.0 * 19.5, base_width=20.0, toe_depth=14.5, friction=0.6)
    train = wave_train(SeaState(8.0, 14.0, waves=1000, seed=0), site)
    cumulative = storm_sliding(train, site, c)
    each = [slide(wave_load(w, site), c) for w in train.waves]
    assert cumulative[-1] > 0.0 and np.all(np.diff(cumulative) >= 0.0)
    assert cumulative == pytest.approx(np.cumsum(each), rel=1e-12)
    with pytest.raises(ValueError, match=r"^base_width"):
        storm_sliding(train, site, Caisson(mass=2100.0 * 21.0 * 19.5, base_width=21.0,
                                           toe_depth=14.5, friction=0.6))


def test_sliding_into_the_next_wave_is_refused():
    """μ = 0.1: a 12 m wave sets the caisson sliding for 16 s, past the next wave (12 s)."""
    site = Site(depth=20.0, toe_depth=14.5, berm_depth=11.0, crest_height=5.0,
                base_width=20.0)
    c = Caisson(mass=2100.0 * 20.0 * 19.5, base_width=20.0, toe_depth=14.5, friction=0.1)
    first = Wave(12.0, 12.0)
    assert slide_motion(wave_load(first, site), c).stop > 12.0
    with pytest.raises(ValueError, match=r"^wave 1 \(H = 12 m\): the caisson still slides"):
        storm_sliding(WaveTrain((first, Wave(5.0, 12.0, 12.0))), site, c)


def test_weight_given():
    """W' given (an FE model's static normal force) replaces M g − ρ g B h'; the same
    closed form of the rectangular pulse follows with N = W'."""
    c = _block(toe_depth=0.5, added_mass=False)
    given = Caisson(c.mass, c.base_width, c.toe_depth, c.friction, added_mass=False,
                    weight=0.5 * c.submerged_weight)
    N, m = given.submerged_weight, given.moving_mass
    assert N == 0.5 * c.submerged_weight and m == c.mass
    F0, τ = 2.0 * 0.6 * N, 0.3
    a = (F0 - 0.6 * N) / m
    expected = 0.5 * a * τ**2 + (a * τ) ** 2 / (2.0 * 0.6 * N / m)
    assert slide(_load(Rect(F0, τ), τ), given) == pytest.approx(expected, rel=1e-6)
    with pytest.raises(ValueError, match="weight: W' must be > 0"):
        Caisson(c.mass, c.base_width, c.toe_depth, c.friction, weight=0.0)
