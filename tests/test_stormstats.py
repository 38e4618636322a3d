"""A study over storm seeds as a Monte Carlo (breakwater.studies.stormstats).

The statistics of the finished cases' ``storm.total_sliding`` (sweep.csv) against the
formulas computed here (numpy's mean, sample standard deviation and percentiles; the
fraction above each limit; the CLT's half-width 1.96 s/√n), the failed cases left out.
"""

from __future__ import annotations

import json
import math
import pathlib

import numpy as np
import pytest

from breakwater.common.errors import CaseError
from breakwater.studies.stormstats import COLUMN, monte_carlo
from breakwater.studies.studyfile import load_study

pytestmark = pytest.mark.serial  # files only: once is enough


def test_monte_carlo_of_a_storm_study(tmp_path: pathlib.Path) -> None:
    study_file = tmp_path / "storms.toml"
    study_file.write_text('base = "goda"\n[grid]\n"loads.storm.storm.sea.seed" = [0, 1, 2, 3, 4]\n'
                          "[figures]\nlimits = [0.1, 0.3]\n")
    study = load_study(study_file)
    totals = [0.0, 0.05, 0.2, 0.4, 9.9]
    header = ["loads.storm.storm.sea.seed", "status", COLUMN]
    rows = [{"loads.storm.storm.sea.seed": str(i), "status": "finished", COLUMN: repr(s)}
            for i, s in enumerate(totals)]
    rows[4]["status"] = "failed"  # its total is not a storm's: left out
    out = monte_carlo(tmp_path, study, header, rows)
    assert out is not None
    done = np.array(totals[:4])
    assert out["storms"] == 4 and out["seed_key"] == "loads.storm.storm.sea.seed"
    # the storm left out is said (it may be the one that slid most: 9.9 m here)
    assert out["planned"] == 5 and out["left_out"] == {"failed": 1}
    assert out["mean"] == pytest.approx(done.mean(), rel=1e-15)
    assert out["std"] == pytest.approx(done.std(ddof=1), rel=1e-15)
    assert out["percentiles"]["50"] == pytest.approx(np.percentile(done, 50), rel=1e-15)
    assert out["exceedance"] == {"0.1": 0.5, "0.3": 0.25}
    assert out["half_width_95"] == pytest.approx(1.959964 * done.std(ddof=1) / 2, rel=1e-6)
    assert json.loads((tmp_path / "monte_carlo.json").read_text())["storms"] == 4
    assert (tmp_path / "figures" / "monte_carlo.png").stat().st_size > 0
    assert math.isfinite(out["storms_needed_10pct_95"])
    # No storm column: not a storm study.
    assert monte_carlo(tmp_path, study, ["status"], [{"status": "finished"}]) is None


def test_monte_carlo_needs_the_seed_alone(tmp_path: pathlib.Path) -> None:
    # Storms of two frictions pooled as one sample, or deterministic storms (no seed
    # varied) counted as draws: no statistics, the reason said (a user's study printed
    # an expected sliding over friction 0.3 and 0.5, and "4 storms" of 2 wave files).
    mixed = tmp_path / "mixed.toml"
    mixed.write_text('base = "goda"\n[grid]\n"loads.storm.storm.sea.seed" = [0, 1]\n'
                     '"contact.interface.friction" = [0.3, 0.5]\n')
    header = ["loads.storm.storm.sea.seed", "contact.interface.friction", "status", COLUMN]
    rows = [{"loads.storm.storm.sea.seed": str(i % 2), "contact.interface.friction": f,
             "status": "finished", COLUMN: "0.001"} for i, f in enumerate(["0.3", "0.5"] * 2)]
    out = monte_carlo(tmp_path, load_study(mixed), header, rows)
    assert out == {"skipped": "the study varies contact.interface.friction besides the "
                   "seed (one design per study: its storms' seeds alone)"}
    fixed = tmp_path / "fixed.toml"
    fixed.write_text('base = "goda"\n[grid]\n"time.dt" = [1e-4, 2e-4]\n')
    out = monte_carlo(tmp_path, load_study(fixed), ["time.dt", "status", COLUMN], rows)
    assert out == {"skipped": "the study varies no storm seed"}
    assert not (tmp_path / "monte_carlo.json").exists()


def test_a_seed_counts_once(tmp_path: pathlib.Path) -> None:
    # Seeds 0, 1, 1 (three draws of a choice of three seeds may repeat one): storm 1
    # twice is one storm, not two draws. Its statistics would weigh it double (mean
    # (0 + 2 + 2)/3 = 1.33 against 1.0 of the two storms) and narrow the half-width by
    # sqrt(3/2): none are given, the reason said.
    study_file = tmp_path / "storms.toml"
    study_file.write_text('base = "goda"\n[samples]\ncount = 3\n'
                          '"loads.storm.storm.sea.seed" = {choice = [0, 1, 2]}\n')
    key = "loads.storm.storm.sea.seed"
    rows = [{key: str(seed), "status": "finished", COLUMN: repr(total)}
            for seed, total in ((0, 0.0), (1, 0.002), (1, 0.002))]
    out = monte_carlo(tmp_path, load_study(study_file), [key, "status", COLUMN], rows)
    assert out == {"skipped": "seed 1 repeats: the same storm would count as several "
                   "(give each seed once)"}
    assert not (tmp_path / "monte_carlo.json").exists()


def test_limits_are_checked(tmp_path: pathlib.Path) -> None:
    study_file = tmp_path / "bad.toml"
    study_file.write_text('base = "goda"\n[grid]\n"time.dt" = [1e-4]\n'
                          "[figures]\nlimits = [0.1, -1]\n")
    with pytest.raises(CaseError, match=r"figures\.limits"):
        load_study(study_file)
