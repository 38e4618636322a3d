"""The storm's waves: Rayleigh heights, the breaking cap, the wave-by-wave table.

References: the Rayleigh distribution of individual wave heights in the form
P(H > x) = exp[−2 (x/H_1/3)²] (Longuet-Higgins 1952; Goda 2000, §2.2); the mean of its
highest third and the expected largest of N heights are computed here in closed form /
by quadrature of the exact distribution.
"""

from __future__ import annotations

import math
import pathlib

import numpy as np
import pytest

from breakwater.loads.wavepressure import breaking_height
from breakwater.storms.seastate import (
    SeaState,
    breaker_limit,
    read_wave_table,
    wave_heights,
    wave_train,
)
from breakwater.storms.waves import Site

pytestmark = pytest.mark.serial  # arrays and files alone (no MPI): once is enough

DEEP = Site(depth=100.0, toe_depth=80.0, berm_depth=70.0, crest_height=5.0, base_width=20.0)


def _h13_exact(hs: float) -> float:
    """Mean of the highest third of the Rayleigh law P(H > x) = exp(−2 (x/Hs)²).

    With H_rms = Hs/√2 and a = H_rms √(ln 3) (P(H > a) = 1/3):
    ∫_a^∞ x f(x) dx = (a/3 + H_rms (√π/2) erfc(√ln 3)), divided by 1/3.
    """
    hrms = hs / math.sqrt(2.0)
    a = hrms * math.sqrt(math.log(3.0))
    return a + 3.0 * hrms * 0.5 * math.sqrt(math.pi) * math.erfc(math.sqrt(math.log(3.0)))


def _hmax_exact(hs: float, n: int) -> float:
    """E[max of n heights] = ∫_0^∞ [1 − F(x)^n] dx (quadrature, 2e5 intervals to 6 Hs)."""
    x = np.linspace(0.0, 6.0 * hs, 200_001)
    f = 1.0 - (1.0 - np.exp(-2.0 * (x / hs) ** 2)) ** n
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(x)))


def test_reproducible():
    sea = SeaState(3.0, 9.0, waves=200, seed=7)
    a, b = wave_train(sea, DEEP), wave_train(sea, DEEP)
    assert a == b
    other = wave_train(SeaState(3.0, 9.0, waves=200, seed=8), DEEP)
    assert [w.height for w in a.waves] != [w.height for w in other.waves]


def test_waves_follow_one_another_with_the_significant_period():
    train = wave_train(SeaState(2.0, 8.0, duration=8.0 * 50 + 3.0, seed=1), DEEP)
    assert len(train) == 50
    for k, w in enumerate(train.waves):
        assert w.period == 8.0
        assert w.start == pytest.approx(8.0 * k, rel=1e-15, abs=0)


def test_rayleigh_statistics():
    """H_1/3 of the sample and H_max against the exact law, over 200 storms of 1000 waves.

    Tolerance: 4 standard errors of the mean over the storms (s/√200, from the sample),
    a failure rate of 6e-5 if the draws are right; the estimators' own biases (order
    statistics of 1000 draws) are below 1e-3 Hs, well inside it.
    """
    hs, n, storms = 2.0, 1000, 200
    h13, hmax = [], []
    for seed in range(storms):
        heights = np.sort(wave_heights(SeaState(hs, 10.0, waves=n, seed=seed), DEEP).heights)
        h13.append(heights[-(n // 3):].mean())
        hmax.append(heights[-1])
    for sample, exact in ((h13, _h13_exact(hs)), (hmax, _hmax_exact(hs, n))):
        mean, se = np.mean(sample), np.std(sample, ddof=1) / math.sqrt(storms)
        assert abs(mean - exact) < 4.0 * se, (mean, exact, se)
    # Goda 2000 (§2.2): H_1/3 = 4.004 √m0 = 1.416 H_rms, H_rms = 2√2 √m0 = Hs/√2 here
    assert _h13_exact(hs) == pytest.approx(1.416 / math.sqrt(2.0) * hs, rel=4e-4)  # 1.416: 4 digits


def test_breaking_caps_the_heights():
    shallow = Site(depth=5.0, toe_depth=4.0, berm_depth=3.0, crest_height=2.0, base_width=10.0)
    sea = SeaState(5.0, 10.0, waves=500, seed=3)
    limit = breaker_limit(10.0, shallow)
    assert limit == pytest.approx(breaking_height(10.0, 5.0))
    capped, free = wave_heights(sea, shallow), wave_heights(sea, DEEP)
    assert capped.broken > 10 and capped.limit == limit
    assert np.all(capped.heights <= limit)
    assert np.count_nonzero(capped.heights == limit) == capped.broken
    below = free.heights <= limit  # the same draws: unchanged below the cap
    assert np.array_equal(capped.heights[below], free.heights[below])
    # h_b deeper than h: the limit at h_B = max(h, h_b)
    site = Site(depth=5.0, toe_depth=4.0, berm_depth=3.0, crest_height=2.0,
                base_width=10.0, breaking_depth=7.0)
    assert breaker_limit(10.0, site) == pytest.approx(breaking_height(10.0, 7.0))


@pytest.mark.parametrize(("kwargs", "key"), [
    (dict(significant_height=0.0, significant_period=8.0, waves=10), "significant_height"),
    (dict(significant_height=2.0, significant_period=-1.0, waves=10), "significant_period"),
    (dict(significant_height=2.0, significant_period=8.0), "waves, duration"),
    (dict(significant_height=2.0, significant_period=8.0, waves=10, duration=80.0),
     "waves, duration"),
    (dict(significant_height=2.0, significant_period=8.0, waves=0), "waves"),
    (dict(significant_height=2.0, significant_period=8.0, waves=2.5), "waves"),
    (dict(significant_height=2.0, significant_period=8.0, duration=4.0), "duration"),
    (dict(significant_height=2.0, significant_period=8.0, waves=5, seed=-1), "seed"),
])
def test_sea_state_refused(kwargs, key):
    with pytest.raises(ValueError, match=f"^{key}:"):
        SeaState(**kwargs)


def test_read_wave_table(tmp_path):
    path = tmp_path / "waves.csv"
    path.write_text("H (m);T (s)\n1,5;8\n# a comment\n2,25;9,5\n", encoding="utf-8")
    train = read_wave_table(path)
    assert [(w.height, w.period, w.start) for w in train.waves] == [
        (1.5, 8.0, 0.0), (2.25, 9.5, 8.0)]
    path.write_text("1.5, 8, 0\n2, 9, 10\n", encoding="utf-8")
    assert [w.start for w in read_wave_table(path).waves] == [0.0, 10.0]


@pytest.mark.parametrize(("text", "match"), [
    ("H,T\n1.5,8\n2,x\n", r"waves.csv line 3: expected two or three numbers .*'x' is not"),
    ("1.5,8\n2,9,1,4\n", r"waves.csv line 2: expected two or three numbers .*4 cells"),
    ("1.5,8\n-2,9\n", r"waves.csv line 2: wave height H = -2 m"),
    ("1.5,0\n", r"waves.csv line 1: wave period T = 0 s"),
    ("1.5,8,0\n2,9\n", r"waves.csv line 2: 2 numbers, line 1 has 3"),
    ("1.5,8,0\n2,9,5\n", r"waves.csv line 2: the wave starts at 5 s, before the previous"),
    ("H,T\n", r"waves.csv: no wave"),
    # A decimal comma in a blank-separated row: H = 2.5, T = 8 was read H = 2, T = 5,
    # start = 8 (and the next rows alike: a storm of other waves, silently).
    ("H T\n2,5 8\n3,5 20\n", r"waves.csv line 2: cells apart by commas and by blanks"),
    ("H [m];T [days]\n2;8\n", r"waves.csv line 1: column 2 \('T \[days\]'\) is a time in"),
])
def test_read_wave_table_refuses_bad_rows(tmp_path, text, match):
    path = tmp_path / "waves.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ValueError, match=match):
        read_wave_table(path)


def test_read_wave_table_units_in_the_header(tmp_path):
    # A laboratory's waves in cm and ms: read as m and s (they were read as m and s as
    # written: waves 100 times too high, 1000 times too long).
    path = tmp_path / "waves.csv"
    path.write_text("H (cm);T (ms);start (ms)\n15;1400;0\n18,5;1500;1400\n",
                    encoding="utf-8")
    waves = read_wave_table(path).waves
    assert [(w.height, w.period, w.start) for w in waves] == [
        pytest.approx((0.15, 1.4, 0.0), rel=1e-15), pytest.approx((0.185, 1.5, 1.4), rel=1e-15)]
    path.write_text("H [ft]\tT [s]\n2\t8\n", encoding="utf-8")
    assert read_wave_table(path).waves[0].height == pytest.approx(2 * 0.3048, rel=1e-15)


def test_capped_waves_are_counted_for_the_warning(tmp_path) -> None:
    # A sea state far above breaking at the site (H_1/3 = 5 m in 0.32 m of water): every
    # wave is capped at H_b, which the run now says (nothing did); one far below: none.
    from breakwater.casefile.case import load_case

    example = pathlib.Path(__file__).parents[1] / "examples" / "goda_storm.toml"
    text = example.read_text(encoding="utf-8")
    listed = next(line for line in text.splitlines() if line.startswith("waves = [["))
    for height, capped in ((5.0, 5), (0.01, 0)):
        case_file = tmp_path / f"sea{height}.toml"
        case_file.write_text(text.replace(listed, f"sea = {{ significant_height = {height}, "
                                                 "period = 1.4, waves = 5, seed = 1 }"),
                             encoding="utf-8")
        storm = next(ld for ld in load_case(case_file).loads if ld.name == "wave").storm
        count, waves, limit = storm.capped(0.205)
        assert (count, waves) == (capped, 5)
        assert limit == pytest.approx(0.2947, rel=1e-3)  # Goda's H_b here (the run's)
