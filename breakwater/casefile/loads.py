"""The ``[loads.<name>]`` tables of a case: what a load is, in TOML, and its model loads.

A load is a **time function** (a dimensionless factor, or the impulse-normalised
pulse) times a **spatial traction field** on a facet group (:mod:`breakwater.loads.fields`):

- time functions (``time_function``): ``"pulse"`` (an impact of given ``impulse`` or
  from a ``[pendulum]``: the default when one of them is given), ``"constant"`` (the
  default otherwise; from ``start`` on), ``"ramp"`` (zero until ``start``, linear to 1
  over ``rise``, then held) and ``"table"`` (``[loads.<name>.table]``: a CSV ``file``
  of t, value rows or inline ``points``, interpolated linearly; a run outlasting the
  table is an error unless ``hold_last = true``);
- magnitudes (exactly one, except for pulses which take ``impulse``/``pendulum``):
  ``force`` (N of the real structure, divided by ``out_of_plane_length``, spread
  uniformly over the group along ``direction``), ``traction`` (Pa along
  ``direction``), ``pressure`` (Pa normal to the surface, positive pushing into the
  body), ``[profile]`` (a pressure p(s) given by points along an axis) or ``[goda]``
  (Goda's design wave pressure on the front face and, with ``uplift_group``, the
  triangular uplift under the base; :mod:`breakwater.loads.wavepressure`);
- a storm (``[storm]``, :mod:`breakwater.casefile.stormcase`): waves one after the other,
  each its Goda front pressure (the shape changing from wave to wave) and uplift with
  its own force-time history; it is its own time function (no ``time_function``).

These tables are read without the solver stack; on a mesh,
:func:`~breakwater.casefile.meshloads.surface_loads` turns a load into the model's
:class:`~breakwater.model.model.SurfaceLoad` (two for a Goda load with uplift) and
:func:`~breakwater.casefile.meshloads.load_summary` describes it for the run's summary.
"""

from __future__ import annotations

import math
import pathlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

from breakwater.casefile.stormcase import StormCase, check_site
from breakwater.config.fields import InvalidField, positive, setting
from breakwater.config.typecheck import check_fields
from breakwater.loads.fields import PressureProfile
from breakwater.loads.signals import (
    STANDARD_GRAVITY,
    Constant,
    Pulse,
    PulseShape,
    Ramp,
    Table,
    impact_velocity,
    pendulum_impulse,
)
from breakwater.loads.tablefile import read_table
from breakwater.loads.wavepressure import GodaPressure, GodaRangeError, goda_pressure

__all__ = ["RESOLVED_STEPS", "GodaCase", "LoadCase", "PendulumCase", "ProfileCase", "TableCase"]

TimeFunction = Literal["pulse", "constant", "ramp", "table"]
MAGNITUDES = ("force", "traction", "pressure", "profile", "goda", "storm")

RESOLVED_STEPS = 10
"""A pulse shorter than this many nominal steps is warned about as under-resolved
(:func:`~breakwater.casefile.loadchecks.pulse_warning`); one not longer than a step is
refused (:meth:`LoadCase.check_time`)."""


@dataclass(frozen=True)
class PendulumCase:
    """``[loads.<name>.pendulum]``: the impulse of a pendulum, I = M ω (1 + e₀) (eq. 29)."""

    mass: float = setting(unit="kg", doc="pendulum mass M")
    cord_length: float = setting(unit="m", doc="cord length l₀")
    release_distance: float = setting(unit="m", doc="release distance s₀ from the struck face")
    restitution: float = setting(doc="coefficient of restitution e₀, in [0, 1]")
    gravity: float = setting(STANDARD_GRAVITY, unit="m/s²", doc="g in ω = s₀ sqrt(g/l₀)")

    def __post_init__(self) -> None:
        check_fields(self)
        for name in ("mass", "cord_length", "release_distance", "gravity"):
            positive(getattr(self, name), name)
        if not 0.0 <= self.restitution <= 1.0:
            raise InvalidField("restitution", f"must be in [0, 1] (got {self.restitution:g})")
        if not math.isfinite(self.impulse):  # e.g. a cord of 1e-320 m: ω overflows
            raise InvalidField("", f"the impulse M ω (1 + e₀) overflows (ω = s₀ sqrt(g/l₀) "
                               f"= {self.velocity:g} m/s)")

    @property
    def velocity(self) -> float:
        """Impact velocity ω (m/s)."""
        return impact_velocity(self.cord_length, self.release_distance, self.gravity)

    @property
    def impulse(self) -> float:
        """Impulse I (N s)."""
        return pendulum_impulse(self.mass, self.cord_length, self.release_distance,
                                self.restitution, self.gravity)


@dataclass(frozen=True)
class TableCase:
    """``[loads.<name>.table]``: a tabulated history of the load factor."""

    file: str | None = setting(None, doc="CSV file of t, value rows (s, -), relative to "
                               "the case file: a first row without numbers (a header), "
                               "# comments and blank rows are skipped; separators , ; tab "
                               "or blanks, decimal commas with ; or tab, UTF-8 (with or "
                               "without BOM) or UTF-16; a time unit in the header (t [ms]) "
                               "converts the times (see breakwater.loads.tablefile.read_table)")
    points: tuple[tuple[float, ...], ...] | None = setting(None, doc="inline [t, value] "
                                                           "pairs (instead of file)")
    hold_last: bool = setting(False, doc="hold the last value after the table ends (else "
                              "a run outlasting the table is an error)")

    def __post_init__(self) -> None:
        check_fields(self)
        if (self.file is None) == (self.points is None):
            raise InvalidField("file", "give either file or points (exactly one)")
        if self.file is not None:
            try:
                times, values = read_table(pathlib.Path(self.file))
            except (OSError, ValueError) as e:
                raise InvalidField("file", str(e)) from None
            where = "file"
        else:
            assert self.points is not None
            if any(len(p) != 2 for p in self.points):
                raise InvalidField("points", "expected [t, value] pairs")
            times = tuple(p[0] for p in self.points)
            values = tuple(p[1] for p in self.points)
            where = "points"
        try:
            table = Table(times, values, self.hold_last)
        except ValueError as e:
            raise InvalidField(where, str(e)) from None
        object.__setattr__(self, "_table", table)

    def history(self, start: float = 0.0) -> Table:
        """The table as a time function, its time 0 at ``start``."""
        table: Table = self.__dict__["_table"]
        return Table(table.times, table.values, self.hold_last, start)


@dataclass(frozen=True)
class ProfileCase:
    """``[loads.<name>.profile]``: a pressure p(s) (Pa, positive into the body) along an axis."""

    points: tuple[tuple[float, ...], ...] = setting(unit="m, Pa", doc="[s, p] pairs, s "
                                                    "increasing; linear between them, 0 "
                                                    "outside")
    axis: tuple[float, ...] = setting((0.0, 1.0), doc="direction along which s is measured "
                                      "(default: the elevation y)")
    origin: tuple[float, ...] = setting((0.0, 0.0), unit="m", doc="the point where s = 0 "
                                        "(with a 3D axis, default [0, 0, 0])")

    def __post_init__(self) -> None:
        check_fields(self)
        if len(self.axis) not in (2, 3) or not any(self.axis):
            raise InvalidField("axis", f"must be a non-zero 2- or 3-vector (got "
                               f"{list(self.axis)})")
        if len(self.axis) == 3 and self.origin == (0.0, 0.0):  # the default, or [0, 0]
            object.__setattr__(self, "origin", (0.0, 0.0, 0.0))  # (was refused: "got [0, 0]")
        if len(self.origin) != len(self.axis):
            raise InvalidField("origin", f"must have {len(self.axis)} coordinates, as axis "
                               f"(got {list(self.origin)})")
        if any(len(p) != 2 for p in self.points):
            raise InvalidField("points", "expected [s, p] pairs")
        try:
            self.field()
        except ValueError as e:
            raise InvalidField("points", str(e)) from None

    def field(self) -> PressureProfile:
        """The model's pressure profile."""
        return PressureProfile(tuple((p[0], p[1]) if len(p) == 2 else (math.nan, math.nan)
                                     for p in self.points), self.axis, self.origin)


@dataclass(frozen=True)
class GodaCase:
    """``[loads.<name>.goda]``: Goda's design wave pressure (:mod:`breakwater.loads.wavepressure`).

    The front pressure acts on the load's group (the seaward face, vertical, its
    elevation the mesh's y); with ``uplift_group`` the triangular uplift acts on the
    base of the same body, p_u at its edge nearest the loaded face, 0 at the heel. In
    3D both are the same across the face's and the base's width (along z).
    """

    wave_height: float = setting(unit="m", doc="design (highest) wave height H_max")
    period: float = setting(unit="s", doc="wave period (L from the linear dispersion "
                            "relation at the depth h)")
    depth: float = setting(unit="m", doc="water depth h in front of the breakwater")
    toe_depth: float = setting(unit="m", doc="h': depth of the base of the upright section "
                               "below the still water level")
    berm_depth: float = setting(unit="m", doc="d: depth above the armour of the "
                                "foundation (the berm), <= h'")
    crest_height: float = setting(unit="m", doc="h_c: crest elevation above the still "
                                  "water level")
    still_water_level: float = setting(unit="m", doc="y coordinate of the still water "
                                       "level in the mesh")
    angle: float = setting(0.0, unit="°", doc="β: wave incidence from the normal to the "
                           "breakwater")
    breaking_depth: float | None = setting(None, unit="m", doc="h_b: depth at 5 H_1/3 "
                                           "seaward (default: h)")
    factors: tuple[float, ...] = setting((1.0, 1.0, 1.0), doc="λ₁, λ₂, λ₃ (1: plain "
                                         "upright section)")
    density: float = setting(1025.0, unit="kg/m³", doc="water density ρ")
    gravity: float = setting(9.81, unit="m/s²", doc="g")
    uplift_group: str | None = setting(None, doc="facet group of the base under the "
                                       "uplift (an interface: its side on the loaded body)")
    impulsive: bool = setting(False, doc="the extended formula: α* = max(α₂, α_I) in p₁, "
                              "with Takahashi et al.'s (1994) impulsive coefficient α_I "
                              "(needs berm_width)")
    berm_width: float | None = setting(None, unit="m", doc="B_M: width of the berm in "
                                       "front of the upright section (impulsive only)")

    def __post_init__(self) -> None:
        check_fields(self)
        check_site(self.factors, self.impulsive, self.berm_width)
        try:
            self.pressure()  # the formula's own range checks
        except GodaRangeError as e:
            raise InvalidField(e.key, e.problem) from None

    def pressure(self) -> GodaPressure:
        """The pressures (Pa) of the design wave."""
        λ1, λ2, λ3 = self.factors
        return goda_pressure(self.wave_height, self.period, self.depth, self.toe_depth,
                             self.berm_depth, self.crest_height, self.angle,
                             self.breaking_depth, (λ1, λ2, λ3), self.density, self.gravity,
                             self.impulsive, self.berm_width)

    def front(self) -> PressureProfile:
        """The front pressure profile along y (origin at the still water level)."""
        return PressureProfile(self.pressure().front_points(), (0.0, 1.0),
                               (0.0, self.still_water_level))


@dataclass(frozen=True)
class LoadCase:
    """``[loads.<name>]``: a time function times a traction field on a facet group.

    Pulses (the default with ``impulse`` or ``[pendulum]``): the traction is
    ``I / (out_of_plane_length · patch length) · shape(t)`` along ``direction``, with
    ∫ shape dt = 1. Other time functions multiply exactly one magnitude: ``force``,
    ``traction``, ``pressure``, ``[profile]`` or ``[goda]`` (see
    :mod:`breakwater.casefile.loads`).
    """

    name: str = setting(key=True, doc="name of the load")
    group: str = setting(doc="facet (1D) physical group loaded")
    groups: tuple[str, ...] = setting((), doc="further facet groups loaded alike (e.g. the "
                                      "parts of a split face); a force is spread over all")
    enabled: bool = setting(True, doc="false: the load is not applied (e.g. a load of the "
                            "case this one extends)")
    body: str | None = setting(None, doc="the body loaded, when the group is an interface "
                               "between two bodies")
    time_function: TimeFunction | None = setting(None, doc='"pulse" (default with impulse '  # noqa: RUF009 (a field() with docs)
                                                 'or pendulum), "constant" (default '
                                                 'otherwise), "ramp" or "table"')
    direction: tuple[float, ...] = setting((1.0, 0.0), doc="direction of the traction "
                                           "(normalised): pulse, force, traction")
    impulse: float | None = setting(None, unit="N s", doc="pulse: impulse I of the real (3D) "
                                    "structure; divided by out_of_plane_length")
    pendulum: PendulumCase | None = setting(None, doc="pulse: the impulse from a pendulum "  # noqa: RUF009 (a field() with docs)
                                            "(eq. 29)")
    force: float | None = setting(None, unit="N", doc="resultant of the real structure "
                                  "(divided by out_of_plane_length), spread uniformly over "
                                  "the group along direction")
    traction: float | None = setting(None, unit="Pa", doc="traction along direction")
    pressure: float | None = setting(None, unit="Pa", doc="pressure normal to the surface, "
                                     "positive pushing into the body")
    profile: ProfileCase | None = setting(None, doc="pressure varying along the surface")  # noqa: RUF009 (a field() with docs)
    goda: GodaCase | None = setting(None, doc="Goda's design wave pressure")  # noqa: RUF009 (a field() with docs)
    storm: StormCase | None = setting(None, doc="a storm, wave by wave (its own time "  # noqa: RUF009 (a field() with docs)
                                      "function)")
    shape: PulseShape = setting("triangular", doc="pulse: force-time shape")  # noqa: RUF009 (a field() with docs)
    duration: float = setting(2e-3, unit="s", doc="pulse: duration")
    start: float = setting(0.0, unit="s", doc="time the load starts (a table: its t = 0)")
    peak: float = setting(0.5, doc="triangular pulse: time of the peak as a fraction of "
                          "the duration, in [0, 1]")
    rise: float | None = setting(None, unit="s", doc="ramp: rise time from 0 to full load")
    table: TableCase | None = setting(None, doc="table: the tabulated factor")  # noqa: RUF009 (a field() with docs)

    def __post_init__(self) -> None:
        check_fields(self)
        listed = (self.group, *self.groups)
        twice = next((g for k, g in enumerate(listed) if g in listed[:k]), None)
        if twice is not None:  # its facets were loaded twice: Goda's force 1.9x, no word
            raise InvalidField("groups", f"'{twice}' is listed twice in group and groups: "
                               "its facets would be loaded twice")
        if len(self.direction) not in (2, 3) or not any(self.direction):
            raise InvalidField("direction", f"must be a non-zero 2- or 3-vector (got "
                               f"{list(self.direction)})")
        norm = math.hypot(*self.direction)
        object.__setattr__(self, "direction", tuple(c / norm for c in self.direction))
        impulsive = self.impulse is not None or self.pendulum is not None
        given = [k for k in MAGNITUDES if getattr(self, k) is not None]
        kind: str = self.time_function or ("pulse" if impulsive else "constant")
        if self.storm is not None:
            if self.time_function is not None:
                raise InvalidField("time_function", "a [storm] gives each wave's force-time "
                                   "history: remove time_function")
            if len(given) != 1 or impulsive:
                other = next((k for k in given if k != "storm"), "impulse")
                raise InvalidField(other, "a [storm] is the load's only magnitude")
            if self.start != 0.0:
                raise InvalidField("start", "a storm starts at t = 0 (its waves give their "
                                   "own start times)")
            kind = "storm"
        elif kind == "pulse":
            if given:
                raise InvalidField(given[0], "a pulse is given by its impulse (or "
                                   "[pendulum]), not a force or pressure")
            if (self.impulse is None) == (self.pendulum is None):
                raise InvalidField("impulse", "give either impulse or a [pendulum] table "
                                   "(exactly one)")
            if self.impulse is not None:
                positive(self.impulse, "impulse")
        else:
            if impulsive:
                raise InvalidField("time_function", f'"{kind}" multiplies a force or '
                                   f'pressure: an impulse (impulse or [pendulum]) needs '
                                   f'"pulse"')
            if len(given) != 1:
                raise InvalidField(given[1] if given else "force",
                                   f"give exactly one of {', '.join(MAGNITUDES)} (got "
                                   f"{', '.join(given) or 'none'})")
        positive(self.duration, "duration")
        positive(self.start, "start", strict=False)
        if not 0.0 <= self.peak <= 1.0:
            raise InvalidField("peak", f"must be in [0, 1] (got {self.peak:g})")
        if kind == "ramp":
            if self.rise is None:
                raise InvalidField("rise", 'missing: a "ramp" needs its rise time (s)')
            positive(self.rise, "rise")
        elif self.rise is not None:
            raise InvalidField("rise", f'only a "ramp" has a rise time (time_function is '
                               f'"{kind}")')
        if kind == "table" and self.table is None:
            raise InvalidField("table", 'missing: time_function = "table" needs a '
                               '[table] (file or points)')
        if kind != "table" and self.table is not None:
            raise InvalidField("table", f'a [table] needs time_function = "table" (got '
                               f'"{kind}")')
        object.__setattr__(self, "_kind", kind)

    @property
    def kind(self) -> str:
        """The time function: ``time_function`` or its default."""
        return str(self.__dict__["_kind"])

    @property
    def magnitude(self) -> str:
        """``"impulse"`` for pulses, else the magnitude given (``force``, ...)."""
        if self.kind == "pulse":
            return "impulse"
        return next(k for k in MAGNITUDES if getattr(self, k) is not None)

    @property
    def total_impulse(self) -> float:
        """The impulse I of the real structure (N s); pulses only."""
        if self.pendulum is not None:
            return self.pendulum.impulse
        if self.impulse is None:
            raise ValueError(f"load '{self.name}' is not a pulse")
        return self.impulse

    def pulse(self, out_of_plane_length: float, patch_length: float) -> Pulse:
        """The traction amplitude (Pa) of a pulse on a patch of the given length (m)."""
        per_area = self.total_impulse / (out_of_plane_length * patch_length)
        return Pulse(per_area, self.duration, self.shape, self.start, self.peak)

    def time_factor(self) -> Callable[[float], float]:
        """The dimensionless time function of a non-pulse load."""
        if self.kind == "constant":
            return Constant(1.0, self.start)
        if self.kind == "ramp":
            assert self.rise is not None
            return Ramp(1.0, self.start, self.rise)
        if self.kind == "table":
            assert self.table is not None
            return self.table.history(self.start)
        raise ValueError(f"load '{self.name}' is a pulse")

    def check_duration(self, end_time: float) -> None:
        """Raise :class:`InvalidField` if a table ends before ``end_time`` (s)."""
        if self.kind == "table" and self.table is not None and not self.table.hold_last:
            end = self.table.history(self.start).end
            if end < end_time:
                raise InvalidField(f"loads.{self.name}.table",
                                   f"the table ends at t = {end:g} s, before time.end_time "
                                   f"= {end_time:g} s (extend it or set hold_last = true)")

    def check_time(self, end_time: float, dt: float) -> None:
        """Refuse a load that never acts before ``end_time``, or a pulse no step can sample.

        Raises:
            InvalidField: A table that ends too early (:meth:`check_duration`); a load
                that starts at or after the end time (a table: whose first point is
                there: before it, its first value would act from t = 0); a pulse not
                longer than the time step (sampled at the step ends, it applies nothing,
                or a multiple of its impulse).

        """
        self.check_duration(end_time)
        if not self.enabled:
            return
        where = f"loads.{self.name}"
        if self.storm is not None:
            train = self.storm.waves_train
            if end_time < train.duration * (1 - 1e-12):
                raise InvalidField("time.end_time", f"{end_time:g} s ends the run before "
                                   f"the storm of loads.{self.name} ({len(train)} waves, to "
                                   f"t = {train.duration:g} s): set time.end_time >= "
                                   f"{train.duration:g}")
        elif self.kind == "table":
            assert self.table is not None
            first = self.table.history(self.start).times[0] + self.start
            if first >= end_time:
                raise InvalidField(f"{where}.table", f"the table's first point is at t = "
                                   f"{first:g} s, at or after time.end_time = {end_time:g} "
                                   "s: only its first value would act, held from t = 0")
        elif self.start >= end_time:
            raise InvalidField(f"{where}.start", f"the load starts at t = {self.start:g} s, "
                               f"at or after time.end_time = {end_time:g} s: it never acts "
                               "(set enabled = false to keep it off)")
        if self.kind == "pulse" and not self.duration > dt:
            raise InvalidField(f"{where}.duration", f"the pulse lasts {self.duration:g} s, "
                               f"not more than time.dt = {dt:g} s: sampled at the step ends "
                               "it applies nothing or a multiple of its impulse (set "
                               f"time.dt <= {self.duration / RESOLVED_STEPS:.3g} s)")
