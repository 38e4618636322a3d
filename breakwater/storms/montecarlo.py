"""The expected sliding distance of a caisson over storms: Monte Carlo of the rigid model.

Shimosako & Takahashi's (1999) performance-based design judges a caisson by its expected
sliding distance over storms (or a lifetime of storms; Goda & Takagi 2000). Each storm is
a :class:`~breakwater.storms.seastate.SeaState` with its own seed (0..N−1, or given): its
waves are drawn (:func:`~breakwater.storms.seastate.wave_train`) and the caisson slides
wave by wave (:func:`~breakwater.storms.rigid.storm_sliding`). Over the storms' total
slidings S_i (i = 1..n) :func:`expected_sliding` gives::

    mean  S̄ = (1/n) Σ S_i            std  s = √[Σ (S_i − S̄)² / (n − 1)]
    percentiles 5, 50, 95 (numpy's linear interpolation between order statistics)
    P(S > limit) = #{S_i > limit} / n   for each tolerable sliding (e.g. 0.1 m, Goda &
                                        Takagi 2000; 0.3 m, Shimosako & Takahashi 1999)

and :meth:`MonteCarlo.storms_needed` the number of storms for the mean to be within a
relative error ε at a confidence c, by the central limit theorem (a normal S̄, the sample
s standing for σ), and :meth:`MonteCarlo.half_width` the half-width of the mean's
confidence interval from the storms run::

    n = ⌈(z s / (ε S̄))²⌉,   S̄ ± z s/√n,   z = Φ⁻¹((1 + c)/2)  (two-sided; 1.96 at 95 %)

:func:`write_csv` writes the storms' totals, :func:`plot` their histogram with the mean
and the limits (matplotlib, Agg, as :mod:`breakwater.studies.plots`).
"""

from __future__ import annotations

import math
import pathlib
import statistics
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from breakwater.common.files import atomic_write_text, temporary_path
from breakwater.common.plotstyle import default_style
from breakwater.storms.rigid import Caisson, storm_sliding
from breakwater.storms.seastate import SeaState, wave_train
from breakwater.storms.waveforce import ForceProfile
from breakwater.storms.waves import Site

__all__ = ["MonteCarlo", "expected_sliding", "plot", "write_csv"]

PERCENTILES = (5.0, 50.0, 95.0)


@dataclass(frozen=True)
class MonteCarlo:
    """The storms' total slidings and their statistics (module docstring).

    Attributes:
        seeds: The storms' seeds.
        totals: The total sliding of each storm (m).
        limits: The tolerable slidings (m) of :attr:`exceedance`.

    """

    seeds: tuple[int, ...]
    totals: np.ndarray
    limits: tuple[float, ...]

    @property
    def mean(self) -> float:
        """S̄, the expected sliding per storm (m)."""
        return float(np.mean(self.totals))

    @property
    def std(self) -> float:
        """s, the sample standard deviation (n − 1; 0 for one storm) (m)."""
        return float(np.std(self.totals, ddof=1)) if len(self.totals) > 1 else 0.0

    @property
    def percentiles(self) -> dict[float, float]:
        """The 5th, 50th and 95th percentiles (m)."""
        values = np.percentile(self.totals, PERCENTILES)
        return {p: float(v) for p, v in zip(PERCENTILES, values, strict=True)}

    @property
    def exceedance(self) -> dict[float, float]:
        """P(S > limit) for each limit: the fraction of storms sliding more."""
        return {lim: float(np.mean(self.totals > lim)) for lim in self.limits}

    def half_width(self, confidence: float = 0.95) -> float:
        """The half-width z s/√n of the mean's confidence interval (CLT, two-sided) (m)."""
        if not 0 < confidence < 1:
            raise ValueError(f"confidence: must be in (0, 1) (got {confidence!r})")
        z = statistics.NormalDist().inv_cdf(0.5 * (1.0 + confidence))
        return z * self.std / math.sqrt(len(self.totals))

    def storms_needed(self, relative_error: float = 0.1, confidence: float = 0.95) -> int:
        """The storms n for the mean within ``relative_error`` at ``confidence``.

        By the CLT, two-sided (module docstring). Returns 1 when every storm slides the
        same (s = 0, e.g. no sliding at all).
        """
        if not relative_error > 0:
            raise ValueError(f"relative_error: must be > 0 (got {relative_error!r})")
        if not 0 < confidence < 1:
            raise ValueError(f"confidence: must be in (0, 1) (got {confidence!r})")
        if self.std == 0.0:
            return 1
        z = statistics.NormalDist().inv_cdf(0.5 * (1.0 + confidence))
        return math.ceil((z * self.std / (relative_error * self.mean)) ** 2)


def expected_sliding(sea: SeaState, site: Site, caisson: Caisson,
                     storms: int | Sequence[int] = 100,
                     limits: Sequence[float] | float = (0.1, 0.3),
                     profile: ForceProfile | None = None) -> MonteCarlo:
    """The total sliding over storms of the sea state (seeds 0..storms−1, or given).

    Args:
        sea: The sea state (its ``seed`` is replaced by each storm's).
        site: The site.
        caisson: The caisson (base width and toe depth as the site's).
        storms: The number of storms (seeds 0..n−1) or the seeds (integers, each once).
        limits: Tolerable slidings (m) for the exceedance probabilities (or one).
        profile: The force-time profile (default
            :class:`~breakwater.storms.waveforce.ForceProfile`).

    Raises:
        ValueError: ``storms`` neither a count nor a list of distinct integer seeds
            (a string, a float seed, a seed given twice), or a bad limit (one line).
    """
    seeds = _seeds(storms)
    if _real(limits):  # one limit
        limits = (float(limits),)  # type: ignore[arg-type]
    if isinstance(limits, str | bytes) or not isinstance(limits, Iterable):
        raise ValueError(f"limits: expected a list of slidings (m), got {limits!r}")
    for lim in limits:
        if not (_real(lim) and lim >= 0 and math.isfinite(lim)):
            raise ValueError(f"limits: must be >= 0 (got {lim!r})")
    totals = np.array([storm_sliding(wave_train(replace(sea, seed=s), site), site, caisson,
                                     profile)[-1] for s in seeds])
    return MonteCarlo(seeds=seeds, totals=totals, limits=tuple(float(x) for x in limits))


def _integer(x: Any) -> bool:
    return isinstance(x, int | np.integer) and not isinstance(x, bool | np.bool_)


def _real(x: Any) -> bool:
    return isinstance(x, int | float | np.integer | np.floating) \
        and not isinstance(x, bool | np.bool_)


def _seeds(storms: Any) -> tuple[int, ...]:
    """The storms' seeds: ``range(storms)`` of a count, or the seeds given, each once.

    A string was read as seeds character by character (``storms="100"``: seeds 1, 0, 0,
    the storm of seed 0 counted twice), a seed given twice counted one storm twice in
    the statistics, a float seed was truncated (1.7: seed 1) and a NumPy count failed
    with ``TypeError: 'numpy.int64' object is not iterable``.
    """
    if _integer(storms):
        if storms < 1:
            raise ValueError(f"storms: must be >= 1 (got {storms})")
        return tuple(range(int(storms)))
    if isinstance(storms, str | bytes) or not isinstance(storms, Iterable):
        raise ValueError("storms: expected the number of storms or a list of seeds "
                         f"(integers >= 0), got {type(storms).__name__} {storms!r}")
    given = list(storms)
    if not given:
        raise ValueError("storms: no seed given")
    wrong = next((s for s in given if not (_integer(s) and s >= 0)), None)
    if wrong is not None:
        raise ValueError(f"storms: a seed must be an integer >= 0 (got {wrong!r})")
    seeds = tuple(int(s) for s in given)
    twice = next((s for k, s in enumerate(seeds) if s in seeds[:k]), None)
    if twice is not None:
        raise ValueError(f"storms: seed {twice} is given twice (a seed is one storm: "
                         "twice, it would be counted twice in the statistics)")
    return seeds


def write_csv(result: MonteCarlo, path: str | pathlib.Path) -> pathlib.Path:
    """``seed,total_sliding_m`` per storm (atomic write)."""
    lines = ["seed,total_sliding_m"]
    lines += [f"{s},{x:.9g}" for s, x in zip(result.seeds, result.totals, strict=True)]
    return atomic_write_text(path, "\n".join(lines) + "\n")


@default_style
def plot(result: MonteCarlo, path: str | pathlib.Path, title: str = "") -> pathlib.Path:
    """The histogram of the storms' total sliding, with the mean and the limits (PNG)."""
    from matplotlib.figure import Figure

    path = pathlib.Path(path)
    fig = Figure(figsize=(6.0, 4.0), layout="constrained")
    ax = fig.add_subplot()
    ax.hist(result.totals, bins=max(10, min(50, len(result.totals) // 5)), color="0.7",
            edgecolor="0.3", lw=0.5)
    ax.axvline(result.mean, color="C0", lw=1.2, label=f"mean {result.mean:.3g} m")
    for k, lim in enumerate(result.limits):
        ax.axvline(lim, color="C3", lw=0.9, ls=("--", ":", "-.")[k % 3],
                   label=f"limit {lim:g} m: P(S > limit) = {result.exceedance[lim]:.3g}")
    ax.set_xlabel("total sliding per storm S (m)")
    ax.set_ylabel("storms")
    ax.grid(True, lw=0.3)
    ax.legend(fontsize=7)
    ax.set_title(title or f"{len(result.totals)} storms", fontsize=10)
    tmp = temporary_path(path)
    fig.savefig(tmp, dpi=80)
    tmp.replace(path)
    return path
