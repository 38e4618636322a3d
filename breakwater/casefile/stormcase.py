"""``[loads.<name>.storm]``: a storm, wave by wave, on the caisson (issue 24).

The site takes the key names of ``[loads.<name>.goda]`` but ``wave_height`` and
``period`` (the base width B is the extent of ``uplift_group``); the waves are given
by exactly one of

- ``[loads.<name>.storm.sea]``: a sea state (significant height, period, a count of
  waves or a duration, a seed): Rayleigh-distributed heights
  (:func:`breakwater.storms.seastate.wave_train`);
- ``waves = "table.csv"``: a table of waves (:func:`breakwater.storms.seastate.read_wave_table`);
- ``waves = [[H, T], ...]``: inline, one after the other from t = 0.

Every wave is checked against Goda's ranges here (a wave above the breaking limit is
refused, named by its number, height and period). Each wave's load (front shape,
p₁(τ), p_u(τ)) is :func:`breakwater.storms.waveforce.wave_load`'s; the model's loads
are :mod:`breakwater.storms.stormload`'s (the front shape changes at each wave's start).
Reading a case needs no solver stack.
"""

from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass
from typing import TYPE_CHECKING

from breakwater.config.fields import InvalidField, positive, setting
from breakwater.config.typecheck import check_fields
from breakwater.loads.wavepressure import GodaPressure, GodaRangeError, goda_pressure
from breakwater.storms.waves import Site, Wave, WaveTrain

if TYPE_CHECKING:
    from breakwater.storms.seastate import SeaState
    from breakwater.storms.waves import WaveLoad

__all__ = ["MAX_WAVES", "SeaCase", "StormCase", "check_site"]

MAX_WAVES = 1_000_000
"""The most waves a sea state may draw (a prototype storm is a few thousand)."""


def check_site(factors: tuple[float, ...], impulsive: bool, berm_width: float | None
               ) -> None:
    """The checks of Goda's site keys shared by ``[goda]`` and ``[storm]``.

    Raises:
        InvalidField: Not three factors; ``berm_width`` missing with ``impulsive``, given
            without it, or not > 0.
    """
    if len(factors) != 3:
        raise InvalidField("factors", f"expected 3 values (got {len(factors)})")
    if impulsive and berm_width is None:
        raise InvalidField("berm_width", "missing: impulsive = true needs the berm width B_M")
    if not impulsive and berm_width is not None:
        raise InvalidField("berm_width", "is used only with impulsive = true")
    if berm_width is not None and not berm_width > 0:
        raise InvalidField("berm_width", f"must be > 0 (got {berm_width:g})")


@dataclass(frozen=True)
class SeaCase:
    """``[loads.<name>.storm.sea]``: a sea state, the waves' heights Rayleigh-distributed.

    Its waves (:func:`breakwater.storms.seastate.wave_train`): N heights drawn from the
    Rayleigh distribution of H_1/3 with the seed, capped at the breaking limit, each of
    period T_1/3, one after the other from t = 0.
    """

    significant_height: float = setting(unit="m", doc="H_1/3, the significant wave height")
    period: float = setting(unit="s", doc="the waves' period (T_1/3)")
    waves: int | None = setting(None, doc="number of waves (or duration)")
    duration: float | None = setting(None, unit="s", doc="the storm's duration (or waves)")
    seed: int = setting(0, doc="seed of the random heights (the same seed, the same storm)")

    def __post_init__(self) -> None:
        check_fields(self)
        positive(self.significant_height, "significant_height")
        positive(self.period, "period")
        if (self.waves is None) == (self.duration is None):
            raise InvalidField("waves", "give either waves (a count) or duration (exactly one)")
        if self.waves is not None and not self.waves >= 1:
            raise InvalidField("waves", f"must be >= 1 (got {self.waves})")
        if self.duration is not None:
            positive(self.duration, "duration")
        # Drawn before time.end_time is checked: 1e7 waves took 3 minutes and 1.9 GB to
        # be refused, 1e9 a traceback (found by a user).
        count = self.waves if self.waves is not None else (self.duration or 0) / self.period
        if count > MAX_WAVES:
            raise InvalidField("waves" if self.waves is not None else "duration",
                               f"{count:.3g} waves: at most {MAX_WAVES:.0e} in one storm "
                               "(a wave takes about 250 time steps)")

    def state(self) -> SeaState:
        """The sea state these settings describe (its waves drawn with the seed)."""
        from breakwater.storms.seastate import SeaState

        return SeaState(significant_height=self.significant_height,
                        significant_period=self.period, waves=self.waves,
                        duration=self.duration, seed=self.seed)


@dataclass(frozen=True)
class StormCase:
    """``[loads.<name>.storm]``: a storm on the caisson, wave by wave (module docstring).

    The front pressure acts on the load's group (the seaward face, vertical, its
    elevation the mesh's y); the uplift on ``uplift_group`` (the base: p_u at its edge
    nearest the loaded face, 0 at the heel).
    """

    depth: float = setting(unit="m", doc="water depth h in front of the breakwater")
    toe_depth: float = setting(unit="m", doc="h': depth of the base of the upright section "
                               "below the still water level")
    berm_depth: float = setting(unit="m", doc="d: depth above the armour of the "
                                "foundation (the berm), <= h'")
    crest_height: float = setting(unit="m", doc="h_c: crest elevation above the still "
                                  "water level")
    still_water_level: float = setting(unit="m", doc="y coordinate of the still water "
                                       "level in the mesh")
    uplift_group: str = setting(doc="facet group of the caisson's base: the uplift acts on "
                                "it, its extent gives the base width B, and the contact "
                                "pair on it gives the per-wave sliding (waves.csv)")
    angle: float = setting(0.0, unit="°", doc="β: wave incidence from the normal to the "
                           "breakwater")
    breaking_depth: float | None = setting(None, unit="m", doc="h_b: depth at 5 H_1/3 "
                                           "seaward (default: h)")
    factors: tuple[float, ...] = setting((1.0, 1.0, 1.0), doc="λ₁, λ₂, λ₃ (1: plain "
                                         "upright section)")
    density: float = setting(1025.0, unit="kg/m³", doc="water density ρ")
    gravity: float = setting(9.81, unit="m/s²", doc="g")
    impulsive: bool = setting(False, doc="Takahashi et al.'s (1994) impulsive coefficient "
                              "α_I in p₁ (needs berm_width)")
    berm_width: float | None = setting(None, unit="m", doc="B_M: width of the berm in "
                                       "front of the upright section (impulsive only)")
    sea: SeaCase | None = setting(None, doc="the waves from a sea state (or waves)")  # noqa: RUF009 (a field() with docs)
    waves: str | tuple[tuple[float, ...], ...] | None = setting(
        None, unit="m, s", doc='the waves: a CSV file of H, T rows ("table.csv", relative '
        "to the case file; breakwater.storms.seastate.read_wave_table) or inline [[H, T], "
        "...] (one after the other from t = 0); or [sea]")

    def __post_init__(self) -> None:
        check_fields(self)
        check_site(self.factors, self.impulsive, self.berm_width)
        if (self.sea is None) == (self.waves is None):
            raise InvalidField("waves", "give either waves (a file or [[H, T], ...]) or a "
                               "[sea] table (exactly one)")
        train = self.train(math.nan)  # B enters the uplift's force only, not the checks
        object.__setattr__(self, "_train", train)
        where = "sea" if self.sea is not None else "waves"
        for k, w in enumerate(train.waves):
            try:
                self._pressure(w)
            except GodaRangeError as e:
                raise InvalidField(where, f"wave {k + 1} (H = {w.height:g} m, T = "
                                   f"{w.period:g} s, at t = {w.start:g} s): {e.key}: "
                                   f"{e.problem}") from None

    def _pressure(self, w: Wave) -> GodaPressure:
        λ1, λ2, λ3 = self.factors
        return goda_pressure(w.height, w.period, self.depth, self.toe_depth, self.berm_depth,
                             self.crest_height, self.angle, self.breaking_depth,
                             (λ1, λ2, λ3), self.density, self.gravity, self.impulsive,
                             self.berm_width)

    def site(self, base_width: float) -> Site:
        """Goda's geometry of the site, with the caisson's base width B (m)."""
        λ1, λ2, λ3 = self.factors
        return Site(self.depth, self.toe_depth, self.berm_depth, self.crest_height,
                    base_width, self.angle, self.breaking_depth, (λ1, λ2, λ3), self.density,
                    self.gravity, self.berm_width if self.impulsive else None)

    @property
    def waves_train(self) -> WaveTrain:
        """The storm's waves (read with the case: they do not depend on B)."""
        train: WaveTrain = self.__dict__["_train"]
        return train

    def train(self, base_width: float) -> WaveTrain:
        """The storm's waves (a sea state's drawn with its seed), made anew."""
        if self.sea is not None:
            from breakwater.storms.seastate import wave_train

            try:
                return wave_train(self.sea.state(), self.site(base_width))
            except ValueError as e:
                raise InvalidField("sea", str(e)) from None
        if isinstance(self.waves, str):
            from breakwater.storms.seastate import read_wave_table

            try:
                return read_wave_table(pathlib.Path(self.waves))
            except (OSError, ValueError) as e:
                raise InvalidField("waves", str(e)) from None
        assert self.waves is not None
        if not self.waves or any(len(w) != 2 for w in self.waves):
            raise InvalidField("waves", "expected [H, T] pairs (at least one)")
        waves, start = [], 0.0
        for k, (h, t) in enumerate(self.waves):
            try:
                waves.append(Wave(h, t, start))
            except ValueError as e:
                raise InvalidField("waves", f"wave {k + 1}: {e}") from None
            start += t
        return WaveTrain(tuple(waves))

    def capped(self, base_width: float) -> tuple[int, int, float] | None:
        """A sea state's waves capped at the breaking height: (capped, waves, H_b) (m).

        None for a storm of given waves. The same draws as :meth:`train` (the seed).
        """
        if self.sea is None:
            return None
        from breakwater.storms.seastate import wave_heights

        drawn = wave_heights(self.sea.state(), self.site(base_width))
        return drawn.broken, len(drawn.heights), float(drawn.limit)

    def wave_loads(self, base_width: float) -> tuple[WaveLoad, ...]:
        """Each wave's load (:func:`breakwater.storms.waveforce.wave_load`) at B (m)."""
        from breakwater.storms.waveforce import wave_load

        site = self.site(base_width)
        return tuple(wave_load(w, site) for w in self.waves_train.waves)
