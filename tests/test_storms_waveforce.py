"""One wave's load over time: the peaks are Goda's (Goda 1974, 2000) and Goda–Takahashi's
(Takahashi, Tanimoto & Shimosako 1994) resultants, the histories live on [0, τ₀)."""

from __future__ import annotations

import numpy as np
import pytest

from breakwater.loads.wavepressure import GodaRangeError, goda_pressure
from breakwater.storms.waveforce import ForceProfile, resultants, wave_load
from breakwater.storms.waves import Site, Wave

pytestmark = pytest.mark.serial  # arrays alone (no MPI): once is enough

PLAIN = Site(depth=20.0, toe_depth=14.5, berm_depth=11.0, crest_height=5.0, base_width=25.0)
# d/h = 0.4 and B_M ≈ 0.12 L: Takahashi's α_I at its largest, α_I = H/d = 1.25 > α₂ = 0.31
BERM = Site(depth=20.0, toe_depth=12.0, berm_depth=8.0, crest_height=4.0, base_width=20.0,
            berm_width=15.0)


def _goda(wave: Wave, site: Site, impulsive: bool):
    return goda_pressure(wave.height, wave.period, site.depth, site.toe_depth,
                         site.berm_depth, site.crest_height, impulsive=impulsive,
                         berm_width=site.berm_width if impulsive else None)


@pytest.mark.parametrize(("site", "impulsive"), [(PLAIN, False), (BERM, True)])
def test_peak_is_goda(site, impulsive):
    """P(τ₀/2) is Goda's (Goda–Takahashi's) P and M_P, to round-off; nothing exceeds it."""
    wave = Wave(10.0, 10.0, start=30.0)
    load = wave_load(wave, site)
    r = resultants(load, site)
    g = _goda(wave, site, impulsive)
    if impulsive:
        assert g.alpha_impulsive > 3 * g.alpha2  # the impulsive part is present
        assert load.p1.impulsive > 0
    assert r.force(0.5 * load.duration) == pytest.approx(g.force, rel=1e-12)
    assert r.moment(0.5 * load.duration) == pytest.approx(g.moment, rel=1e-12)
    τ = np.linspace(-1.0, load.duration + 1.0, 20001)
    assert max(r.force(t) for t in τ) <= g.force * (1 + 1e-12)
    # the uplift has no α₂ nor α_I: Goda's p_u, U = ½ p_u B, M_U = ⅔ U B about the heel
    assert r.uplift(0.5 * load.duration) == pytest.approx(g.uplift_force(site.base_width))
    assert r.uplift_moment(0.5 * load.duration) == pytest.approx(
        g.uplift_moment(site.base_width))
    assert dict(load.front)[0.0] == 1.0  # the shape is normalised at the SWL


def test_durations_and_support():
    wave = Wave(10.0, 10.0)
    profile = ForceProfile(duration_fraction=0.4, impulse_fraction=0.2)
    load = wave_load(wave, BERM, profile)
    τ0, τ1 = 4.0, 0.8
    assert load.duration == pytest.approx(τ0)
    for history in (load.p1, load.uplift):
        for τ in (-1e-9, -1.0, τ0, τ0 + 1e-9, 7.0):
            assert history(τ) == 0.0
        assert history(1e-6) > 0.0 and history(τ0 * (1 - 1e-9)) > 0.0
    # the triangle: base τ₁ centred on τ₀/2, outside it only the sine hump
    for τ in (0.5 * τ0 - 0.51 * τ1, 0.5 * τ0 + 0.51 * τ1):
        assert load.p1(τ) == pytest.approx(load.p1.standing * np.sin(np.pi * τ / τ0))
    assert load.p1(0.5 * τ0 + 0.25 * τ1) == pytest.approx(
        load.p1.standing * np.sin(np.pi * (0.5 + 0.25 * τ1 / τ0)) + 0.5 * load.p1.impulsive)
    assert load.p1.breakpoints == pytest.approx((0.0, 1.6, 2.0, 2.4, 4.0))
    assert wave_load(wave, BERM).duration == pytest.approx(5.0)  # default k₀ = ½


def test_refused():
    with pytest.raises(GodaRangeError, match=r"^wave_height"):
        wave_load(Wave(40.0, 10.0), PLAIN)  # above the breaker limit
    with pytest.raises(ValueError, match=r"^duration_fraction"):
        ForceProfile(duration_fraction=0.0)
