"""The Monte Carlo of a study over storms: the expected sliding distance from FE runs.

A study whose cases run a storm (``[loads.<name>.storm]``) records each case's total
sliding in ``sweep.csv`` (the headline column ``storm.total_sliding``,
:func:`breakwater.studies.sweep.headline`). Varying the storm's seed
(``"loads.<name>.storm.sea.seed" = [0, 1, ..., N-1]`` in ``[grid]``) makes the study a
Monte Carlo over storms, the finite-element counterpart of
:func:`breakwater.storms.montecarlo.expected_sliding`: :func:`monte_carlo` gives the same
statistics (:class:`~breakwater.storms.montecarlo.MonteCarlo`: mean, standard deviation,
percentiles, the probability of exceeding each tolerable sliding of ``[figures] limits``,
the 95 % half-width of the mean and the storms needed for ±10 %) over the finished
cases, and writes ``monte_carlo.json``, ``monte_carlo.csv`` and
``figures/monte_carlo.png``. The cases left out (failed, interrupted, not run) are
counted there (``planned``, ``left_out``) and in the study's line: a storm that failed
may be one that slid most, and the statistics without it are low.
"""

from __future__ import annotations

import math
import pathlib
from typing import Any

import numpy as np

from breakwater.common import files
from breakwater.storms.montecarlo import MonteCarlo, plot, write_csv
from breakwater.studies.studyfile import Study

__all__ = ["COLUMN", "monte_carlo"]

COLUMN = "storm.total_sliding"
"""The headline column of a case's total sliding over its storm (m)."""


def _seed_key(study: Study) -> str | None:
    """The varied key of the storms' seed, if the study varies one."""
    return next((k for k in study.varied if k.endswith(".sea.seed")), None)


def monte_carlo(folder: pathlib.Path, study: Study, header: list[str],
                rows: list[dict[str, str]]) -> dict[str, Any] | None:
    """The statistics of the finished cases' total sliding; None if no case has a storm.

    Args:
        folder: The study's output folder (the files are written there).
        study: The study.
        header: ``sweep.csv``'s columns.
        rows: Its rows.

    Returns:
        The ``monte_carlo.json`` content; ``{"skipped": reason}`` where the seed is not
        the study's only varied key (nothing written); None (no storm column, or no
        finished case).
    """
    if COLUMN not in header:
        return None
    key = _seed_key(study)
    others = [k for k in study.varied if k != key]
    if key is None or others:
        # Statistics of storms drawn with different seeds of one design: without a
        # varied seed the storms are not random draws, and pooled over another varied
        # key they mixed designs (friction 0.3 and 0.5 as one sample; found by a user).
        return {"skipped": "the study varies no storm seed" if key is None else
                f"the study varies {', '.join(others)} besides the seed (one design per "
                "study: its storms' seeds alone)"}
    done = [r for r in rows if r.get("status") == "finished" and r.get(COLUMN)]
    if not done:
        return None
    # The storms left out (failed, interrupted, not run): the statistics are of the
    # finished ones only, and a storm that failed may be one that slid most.
    left_out: dict[str, int] = {}
    kept = {id(r) for r in done}
    for r in rows:
        if id(r) not in kept:
            status = r.get("status") or "pending"
            left_out[status] = left_out.get(status, 0) + 1
    seeds = tuple(int(float(r[key])) if key and r.get(key) else i
                  for i, r in enumerate(done))
    repeated = sorted({x for x in seeds if seeds.count(x) > 1})
    if repeated:
        # One storm counted as several draws (a seed twice in [grid], or {choice} of
        # seeds): its weight doubled and the half-width too narrow by sqrt(n/unique).
        return {"skipped": f"seed{'s' * (len(repeated) > 1)} "
                f"{', '.join(map(str, repeated))} repeat{'s' * (len(repeated) == 1)}: "
                "the same storm would count as several (give each seed once)"}
    totals = np.array([float(r[COLUMN]) for r in done])
    limits = tuple(float(x) for x in study.figures.get("limits", ()))
    result = MonteCarlo(seeds, totals, limits)
    p = result.percentiles
    out: dict[str, Any] = {
        "storms": len(totals), "planned": len(rows), "left_out": left_out,
        "seed_key": key, "mean": result.mean, "std": result.std,
        "percentiles": {f"{k:g}": v for k, v in p.items()},
        "exceedance": {f"{k:g}": v for k, v in result.exceedance.items()},
        "half_width_95": result.half_width() if len(totals) > 1 else math.nan,
        "storms_needed_10pct_95": result.storms_needed() if result.mean > 0 else None,
        "files": ["monte_carlo.csv", "figures/monte_carlo.png"]}
    write_csv(result, folder / "monte_carlo.csv")
    (folder / "figures").mkdir(exist_ok=True)
    plot(result, folder / "figures" / "monte_carlo.png",
         title=f"{study.name}: total sliding per storm (finite elements)")
    files.atomic_write_json(folder / "monte_carlo.json", out)
    return out
