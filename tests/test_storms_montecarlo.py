"""The Monte Carlo of the expected sliding: statistics, reproducibility, outputs."""

from __future__ import annotations

import math
import pathlib
import subprocess
import sys

import numpy as np
import pytest

from breakwater.storms.montecarlo import MonteCarlo, expected_sliding, plot, write_csv
from breakwater.storms.rigid import Caisson
from breakwater.storms.seastate import SeaState
from breakwater.storms.waves import Site

pytestmark = pytest.mark.serial  # arrays alone (no MPI): once is enough


def _case(width: float) -> tuple[Site, Caisson]:
    site = Site(depth=20.0, toe_depth=14.5, berm_depth=11.0, crest_height=5.0,
                base_width=width)
    return site, Caisson(mass=2100.0 * width * 19.5, base_width=width, toe_depth=14.5,
                         friction=0.6)


def test_far_below_sliding_is_zero():
    """H_1/3 = 2 m on the 30 m caisson (safety factor 1.24 at H_max = 14.4 m): the largest
    of 200 waves (about 4–5 m) is far below sliding, every storm gives 0."""
    site, caisson = _case(30.0)
    result = expected_sliding(SeaState(2.0, 10.0, waves=200), site, caisson, storms=5)
    assert result.mean == 0.0 and result.std == 0.0
    assert result.percentiles == {5.0: 0.0, 50.0: 0.0, 95.0: 0.0}
    assert result.exceedance == {0.1: 0.0, 0.3: 0.0}
    assert result.storms_needed() == 1


def test_statistics_ordered_and_reproducible(tmp_path):
    site, caisson = _case(20.0)
    sea = SeaState(8.0, 14.0, waves=200)
    a = expected_sliding(sea, site, caisson, storms=(3, 5, 7, 11, 13, 17), limits=(0.1,))
    b = expected_sliding(sea, site, caisson, storms=(3, 5, 7, 11, 13, 17), limits=(0.1,))
    assert np.array_equal(a.totals, b.totals) and a.seeds == (3, 5, 7, 11, 13, 17)
    assert a.mean > 0.0
    p = a.percentiles
    assert min(a.totals) <= p[5.0] <= p[50.0] <= p[95.0] <= max(a.totals)
    assert a.exceedance[0.1] == np.mean(a.totals > 0.1)
    z = 1.959963984540054  # Φ⁻¹(0.975)
    assert a.storms_needed(0.1, 0.95) == math.ceil((z * a.std / (0.1 * a.mean)) ** 2)
    assert a.half_width(0.95) == pytest.approx(z * a.std / math.sqrt(6))
    csv = write_csv(a, tmp_path / "mc.csv")
    rows = csv.read_text().splitlines()
    assert rows[0] == "seed,total_sliding_m" and len(rows) == 7
    assert float(rows[1].split(",")[1]) == pytest.approx(a.totals[0], rel=1e-8)
    png = plot(a, tmp_path / "mc.png")
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_refused():
    site, caisson = _case(30.0)
    sea = SeaState(2.0, 10.0, waves=10)
    with pytest.raises(ValueError, match=r"^storms"):
        expected_sliding(sea, site, caisson, storms=0)
    with pytest.raises(ValueError, match=r"^limits"):
        expected_sliding(sea, site, caisson, storms=1, limits=(-0.1,))
    with pytest.raises(ValueError, match=r"^confidence"):
        MonteCarlo((0,), np.zeros(1), ()).storms_needed(confidence=1.0)


def test_storms_neither_a_count_nor_seeds_are_refused():
    """``storms="100"`` ran the seeds 1, 0, 0 (a string read character by character), the
    storm of seed 0 counted twice in the mean, percentiles and P(S > limit), as did
    ``storms=[0, 0]``; ``storms=[1.7, 2.2]`` ran seeds 1 and 2. Now one line each; a
    NumPy count and a single limit are taken (``np.int64(3)``: ``TypeError: 'numpy.int64'
    object is not iterable``; ``limits=0.2``: ``'float' object is not iterable``)."""
    site, caisson = _case(30.0)
    sea = SeaState(2.0, 10.0, waves=10)
    for storms, message in (
            ("100", r"^storms: expected the number of storms or a list of seeds \(integers "
                    r">= 0\), got str '100'$"),
            ([0, 0], r"^storms: seed 0 is given twice \(a seed is one storm"),
            ([1.7, 2.2], r"^storms: a seed must be an integer >= 0 \(got 1\.7\)$"),
            (3.0, r"^storms: expected the number of storms .*got float 3\.0$"),
            (True, r"^storms: expected the number of storms .*got bool True$")):
        with pytest.raises(ValueError, match=message):
            expected_sliding(sea, site, caisson, storms=storms)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"^limits: must be >= 0 \(got '0\.1'\)$"):
        expected_sliding(sea, site, caisson, storms=1, limits=["0.1"])  # type: ignore[list-item]
    result = expected_sliding(sea, site, caisson, storms=np.int64(2), limits=0.2)
    assert result.seeds == (0, 1) and result.limits == (0.2,)
    # The sea state takes NumPy numbers and stores them as Python's (np.float32(14.0)
    # was refused as not "a number > 0").
    numpy_sea = SeaState(np.float64(2.0), np.float32(10.0), waves=np.int64(10),
                         seed=np.int64(3))
    assert numpy_sea == SeaState(2.0, 10.0, waves=10, seed=3)
    assert type(numpy_sea.significant_period) is float and type(numpy_sea.seed) is int


def test_storm_rigid_example_refuses_a_bad_argument(tmp_path):
    """``examples/storm_rigid.py abc`` (or ``0``) failed with a traceback (int()'s, or
    expected_sliding's ValueError); now one line naming the argument, exit status 2,
    before any storm is run."""
    script = pathlib.Path(__file__).parents[1] / "examples" / "storm_rigid.py"
    (tmp_path / "afile").touch()
    usage = " (usage: python examples/storm_rigid.py [STORMS] [OUTDIR])\n"
    for args, message in ((["abc"], "STORMS: expected a whole number >= 1, got 'abc'"),
                          (["0"], "STORMS: expected a whole number >= 1, got '0'"),
                          (["-3"], "STORMS: expected a whole number >= 1, got '-3'"),
                          (["2", "out", "x"], "expected at most 2 arguments, got 3"),
                          (["2", "afile/sub"], "OUTDIR: cannot make 'afile/sub' (Not a "
                                               "directory)")):
        done = subprocess.run([sys.executable, str(script), *args], cwd=tmp_path,
                              capture_output=True, text=True, timeout=120, check=False)
        assert (done.returncode, done.stdout, done.stderr) == \
            (2, "", f"storm_rigid.py: {message}{usage}"), args
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]  # nothing made
