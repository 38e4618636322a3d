"""A sea state and its waves, one by one: the Rayleigh heights of a storm at the site.

A storm is a stationary sea state of significant height H_1/3 and significant period
T_1/3 lasting N waves (:class:`SeaState`). :func:`wave_train` draws the individual wave
heights from the Rayleigh distribution (Longuet-Higgins 1952; Goda 2000, "Random Seas and
Design of Maritime Structures", §2.2), in the form of the design literature::

    P(H > x) = exp[−2 (x/H_1/3)²]                         (H_rms = H_1/3 / √2)

by inversion of a uniform draw u ∈ (0, 1] from ``numpy.random.default_rng(seed)``::

    H = H_1/3 √(−½ ln u)

so a seed gives the same storm on every machine and every MPI rank.

**Breaking at the site.** No wave higher than the breaker height H_b reaches the wall:
Goda's breaker index (:func:`breakwater.loads.wavepressure.breaking_height`, Goda 1970,
2000 §3.6, at the bottom slope 1/10 that :func:`~breakwater.loads.wavepressure.goda_pressure`
also uses) at the depth h_B = max(h, h_b) of the site, for the period T_1/3. A drawn
height above H_b is **capped at H_b** (not redrawn). The reason: a wave that would be
higher breaks seaward of the wall and arrives as a broken wave of height about H_b; it is
still one of the N waves of the storm (redrawing would make the storm's highest waves
*lower* than the Rayleigh draw and shift waves below H_b, the unconservative side for
sliding). Goda's (1975, 2000 §3.6) random-breaking model of the surf zone removes the
broken waves' energy gradually and gives heights at or below this cap, so the cap is a
conservative simplification of it, not a reproduction (the number of waves at H_b is
reported by :attr:`WaveHeights.broken`). Every capped height is accepted by
:func:`~breakwater.loads.wavepressure.goda_pressure`'s breaking check (same index, same
depth).

**Periods.** Every wave gets T_1/3. Goda (2000, §4.2.2) takes the period of the design
wave H_max as T_1/3; Shimosako & Takahashi's (1999) wave-by-wave sliding computation
assigns, as far as we can tell from the secondary sources available to us (Goda & Takagi
2000; Takahashi 2002, §4.5, "Design of vertical breakwaters", PARI reference document
34), the same significant period to every wave; we could not check the original here.
The waves follow one another: start_k = Σ_{j<k} T_j.

:func:`read_wave_table` reads a user's wave-by-wave table instead (rows ``H, T`` or
``H, T, start``), with :func:`breakwater.loads.tablefile.read_rows`.
"""

from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass

import numpy as np

from breakwater.loads.tablefile import read_rows
from breakwater.loads.wavepressure import BREAKER_SLOPE, breaking_height
from breakwater.storms.waves import Site, Wave, WaveTrain

__all__ = ["SeaState", "WaveHeights", "breaker_limit", "read_wave_table", "wave_heights",
           "wave_train"]


NUMBER = (int, float, np.integer, np.floating)
"""What a number of a sea state may be (NumPy's too: ``np.float32(14.0)`` was refused
as not "a number > 0")."""


@dataclass(frozen=True)
class SeaState:
    """A storm: a stationary sea state of N waves (give ``waves`` or ``duration``).

    Attributes:
        significant_height: H_1/3 (m), > 0.
        significant_period: T_1/3 (s), > 0.
        waves: N, the number of waves (>= 1); or None and ``duration`` given.
        duration: The storm's duration (s): N = floor(duration / T_1/3) (>= 1).
        seed: The seed of ``numpy.random.default_rng`` (an integer >= 0).

    Raises:
        ValueError: A field out of range, or both or neither of ``waves`` and
            ``duration`` (one line naming the field).

    """

    significant_height: float
    significant_period: float
    waves: int | None = None
    duration: float | None = None
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("significant_height", "significant_period"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, NUMBER) \
                    or not (value > 0 and math.isfinite(value)):
                raise ValueError(f"{name}: must be a number > 0 (got {value!r})")
        if (self.waves is None) == (self.duration is None):
            raise ValueError("waves, duration: give exactly one (the number of waves or "
                             "the storm's duration)")
        if self.waves is not None and (isinstance(self.waves, bool)
                                       or not isinstance(self.waves, int | np.integer)
                                       or self.waves < 1):
            raise ValueError(f"waves: must be an integer >= 1 (got {self.waves!r})")
        if self.duration is not None:
            d = self.duration
            if isinstance(d, bool) or not isinstance(d, NUMBER) \
                    or not (d > 0 and math.isfinite(d)):
                raise ValueError(f"duration: must be a number > 0 (got {d!r})")
            if d < self.significant_period * (1 - 1e-12):
                raise ValueError(f"duration: {d:g} s is shorter than one wave (T_1/3 = "
                                 f"{self.significant_period:g} s)")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int | np.integer) \
                or self.seed < 0:
            raise ValueError(f"seed: must be an integer >= 0 (got {self.seed!r})")
        # NumPy numbers stored as Python's, as the case file's reader stores them.
        for name, kind in (("significant_height", float), ("significant_period", float),
                           ("waves", int), ("duration", float), ("seed", int)):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, kind(getattr(self, name)))

    @property
    def count(self) -> int:
        """N, the number of waves."""
        if self.waves is not None:
            return int(self.waves)
        assert self.duration is not None
        return max(1, math.floor(self.duration / self.significant_period * (1 + 1e-12)))


@dataclass(frozen=True)
class WaveHeights:
    """The heights of a storm at the site.

    Attributes:
        heights: H_k (m), in the order of the waves, capped at ``limit``.
        limit: H_b, the breaker height at the site (m).
        broken: How many drawn heights exceeded H_b (and were capped).

    """

    heights: np.ndarray
    limit: float
    broken: int


def breaker_limit(period: float, site: Site) -> float:
    """H_b at the site for the period T: Goda's index at h_B = max(h, h_b), slope 1/10."""
    depth = site.depth if site.breaking_depth is None else max(site.depth,
                                                               site.breaking_depth)
    return breaking_height(period, depth, BREAKER_SLOPE, site.gravity)


def wave_heights(sea: SeaState, site: Site) -> WaveHeights:
    """The storm's individual heights: Rayleigh draws capped at H_b (module docstring)."""
    rng = np.random.default_rng(int(sea.seed))
    u = 1.0 - rng.random(sea.count)  # in (0, 1]: no log(0)
    drawn = sea.significant_height * np.sqrt(-0.5 * np.log(u))
    limit = breaker_limit(sea.significant_period, site)
    broken = int(np.count_nonzero(drawn > limit))
    return WaveHeights(heights=np.minimum(drawn, limit), limit=limit, broken=broken)


def wave_train(sea: SeaState, site: Site) -> WaveTrain:
    """The storm's waves one after the other, each of period T_1/3 (module docstring)."""
    heights = wave_heights(sea, site).heights
    T = sea.significant_period
    return WaveTrain(tuple(Wave(float(H), T, k * T) for k, H in enumerate(heights)))


def read_wave_table(path: pathlib.Path) -> WaveTrain:
    """A wave-by-wave table: rows ``H, T`` or ``H, T, start`` (m, s, s).

    Read as :func:`breakwater.loads.tablefile.read_table` reads a history (UTF-8/UTF-16,
    ``;``/tab/comma separators, decimal commas, one header row, ``#`` comments); units in
    the header convert the columns (``H (cm)``, ``T [ms]``: m, cm, mm, ft; s, ms, min,
    h; another unit is refused). Without a start column, each wave starts when the
    previous ends (start_k = Σ T of the previous); the column must be in every row or in none.

    Raises:
        OSError: The file cannot be read.
        ValueError: A bad row (the message names the file and the line): not two or
            three numbers, H or T <= 0, start < 0, a wave starting before the previous
            one ends, a start column in some rows only, or no row.

    """
    rows = read_rows(path, (2, 3), "two or three numbers H, T[, start]",
                     ("length", "time", "time"))
    if not rows:
        raise ValueError(f"{path.name}: no wave in the table (rows H, T[, start])")
    with_start = len(rows[0][1]) == 3
    waves: list[Wave] = []
    for number, row in rows:
        where = f"{path.name} line {number}"
        if (len(row) == 3) != with_start:
            raise ValueError(f"{where}: {len(row)} numbers, line {rows[0][0]} has "
                             f"{len(rows[0][1])}: give the start column in every row or "
                             "in none")
        H, T = row[0], row[1]
        if not H > 0:
            raise ValueError(f"{where}: wave height H = {H:g} m: must be > 0")
        if not T > 0:
            raise ValueError(f"{where}: wave period T = {T:g} s: must be > 0")
        start = row[2] if with_start else (waves[-1].end if waves else 0.0)
        if not start >= 0:
            raise ValueError(f"{where}: start = {start:g} s: must be >= 0")
        if waves and start < waves[-1].end * (1 - 1e-12):
            raise ValueError(f"{where}: the wave starts at {start:g} s, before the "
                             f"previous one ends ({waves[-1].end:g} s = its start + T)")
        waves.append(Wave(H, T, start))
    return WaveTrain(tuple(waves))
