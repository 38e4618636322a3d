"""Study files: a base case and the case keys to vary, read into a list of points.

A study file (TOML) names a base case and how to vary it::

    name = "bolts"                  # default: the file name
    base = "goda"                   # a case file (relative to this file) or a built-in
    [set]                           # every case: key = value, dotted case keys
    "time.end_time" = 0.15
    [grid]                          # the product of the lists (first key slowest)
    "contact.interface.friction" = [0.5, 0.65, 0.8]
    [zip]                           # lists of one length: the i-th values go together
    "loads.impact.duration" = [1e-3, 2e-3]
    "loads.impact.peak" = [0.5, 0.3]
    [samples]                       # random points, reproducible from the seed
    count = 8
    seed = 1
    "bodies.mound.density" = {uniform = [1600, 2000]}
    "bodies.mound.shear_modulus" = {log_uniform = [4e5, 3e6]}
    [[derived]]                     # one key implies another, by a table
    from = "mesh.goda.bolt_height"
    key = "loads.impact.pendulum.cord_length"
    table = [[0.034, 3.527], [0.101, 3.46], [0.168, 3.393]]
    interpolate = false             # true: linear between the table's (numeric) rows
    [figures]                       # optional, see breakwater.studies.plots
    x = ["bodies.mound.shear_modulus"]
    reference = {time_of_max_ux = 0.032}
    limits = [0.1, 0.3]             # a storm study: tolerable slidings (m) for the
                                    # Monte Carlo (breakwater.studies.stormstats)

Keys are any case key in the ``--set key=value`` dotted syntax; every case is read by
:func:`breakwater.casefile.case.load_case` with the study's values as overrides, so it is
validated exactly as a case file with ``--set`` (a table merges into the case's, or is a
new entry of a named collection: ``"fixed.rear" = {components = [0]}``). The points
are the product of the ``[grid]`` lists, the ``[zip]`` rows and the ``[samples]`` rows
(any of them may be absent, not all); samples draw each key in file order, point after point, from
``numpy.random.default_rng(seed)`` (``uniform``: in [a, b); ``log_uniform``: its
logarithm uniform; ``choice``: one of a list, with replacement; a ``count`` above the
distinct points the choices can draw, every key a choice, is refused). Derived keys are
set after the varied ones (a table lookup matches a number to 1e-9 relative).

File paths in a study (``base``, and the values of case keys that name files:
``mesh.source``, ``loads.<name>.table.file``) are relative to the study file, as in a
case file; ``--set`` values on the command line are relative to the working directory.

A study has at most ``max_points`` points (:data:`MAX_POINTS`; ``sweep --max-points N``
raises it), counted before any is drawn: every point's case is read before the study
starts (tens of milliseconds each) and each runs a case.

Every problem is a one-line :class:`~breakwater.common.errors.CaseError` naming the file;
:func:`check_points` reads every point's case before anything runs and names each bad
point with its error.
"""

from __future__ import annotations

import bisect
import itertools
import math
import pathlib
import re
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

from breakwater.common.errors import CaseError
from breakwater.common.files import name_problem, path_problem
from breakwater.config.fields import printable, suggest
from breakwater.config.overrides import OVERRIDE, Override, file_argument, override_list
from breakwater.config.tomlfiles import OUT_OF_RANGE, out_of_range, toml_literal

if TYPE_CHECKING:
    from breakwater.casefile.case import Case

__all__ = ["Derived", "Point", "Study", "check_points", "load_study", "toml_literal"]

TOP_KEYS = ("name", "description", "base", "set", "grid", "zip", "samples", "derived",
            "figures")
DERIVED_KEYS = ("from", "key", "table", "interpolate")
FIGURE_KEYS = ("x", "y", "reference", "reference_label", "limits")
DISTRIBUTIONS = ("uniform", "log_uniform", "choice")
MAX_POINTS = 1000
"""Default limit on the points of a study (``sweep --max-points``)."""
SHOWN_ERRORS = 5
"""The distinct errors of bad points a study's refusal shows (then their count)."""
RESERVED = ("output.directory", "name")
"""Case keys a study may not set: the sweep names each case's folder."""


@dataclass(frozen=True)
class Derived:
    """A key set from another by a table: ``key = table(source)``."""

    source: str
    key: str
    table: tuple[tuple[Any, Any], ...]
    interpolate: bool = False

    @staticmethod
    def same(a: Any, x: Any) -> bool:
        """Whether the table's ``a`` is the source value ``x`` (numbers to 1e-9)."""
        return bool(a == x or (_number(a) and _number(x) and math.isclose(a, x, rel_tol=1e-9)))

    def value(self, x: Any) -> Any:
        """The derived value for ``x``; CaseError when the table does not give one."""
        for a, b in self.table:
            if self.same(a, x):
                return b
        if self.interpolate and _number(x):
            xs = [a for a, _ in self.table]
            if xs[0] <= x <= xs[-1]:
                j = bisect.bisect_right(xs, x)
                (x0, y0), (x1, y1) = self.table[j - 1], self.table[j]
                return y0 + (y1 - y0) * (x - x0) / (x1 - x0)
        rows = ", ".join(toml_literal(a) for a, _ in self.table)
        how = "outside the table" if self.interpolate else "not in the table"
        raise CaseError(f"derived {self.key}: {self.source} = {toml_literal(x)} is {how} "
                        f"({rows})")


@dataclass(frozen=True)
class Point:
    """One case of a study: its number and the values it sets (varied, then derived)."""

    index: int
    values: dict[str, Any]

    @property
    def folder(self) -> str:
        """``case-0007`` and a readable suffix of the values (last key parts)."""
        parts = []
        for key, value in self.values.items():
            text = f"{value:.4g}" if _number(value) and not isinstance(value, bool) \
                else str(value)
            parts.append(f"{key.rsplit('.', 1)[-1]}={text}")
        suffix = re.sub(r"[^A-Za-z0-9_.=+-]+", "_", "_".join(parts))[:80]
        return f"case-{self.index:04d}" + (f"_{suffix}" if suffix else "")

    def overrides(self) -> list[str]:
        """The values as ``key=value`` overrides."""
        return [f"{k}={toml_literal(v)}" for k, v in self.values.items()]

    def label(self) -> str:
        """``case-0007 (key=value, ...)`` for messages."""
        values = ", ".join(f"{k}={toml_literal(v)}" for k, v in self.values.items())
        return f"case-{self.index:04d} ({values})"


@dataclass(frozen=True)
class Study:
    """A study read from its file (see the module docstring)."""

    path: pathlib.Path
    name: str
    description: str
    base: str
    fixed: dict[str, Any]
    varied: tuple[str, ...]
    derived: tuple[Derived, ...]
    points: tuple[Point, ...]
    figures: dict[str, Any] = field(default_factory=dict)

    @property
    def keys(self) -> tuple[str, ...]:
        """The keys the points set: the varied keys, then the derived ones."""
        return self.varied + tuple(d.key for d in self.derived)


def _number(x: Any) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool)


def _flatten(table: Mapping[str, Any], prefix: str = "",
             leaf: Any = None) -> dict[str, Any]:
    """Nested tables as dotted keys (``leaf(value)`` True stops at a table)."""
    out: dict[str, Any] = {}
    for k, v in table.items():
        key = f"{prefix}{k}"
        if isinstance(v, Mapping) and not (leaf and leaf(v)):
            out.update(_flatten(v, key + ".", leaf))
        else:
            out[key] = v
    return out


class _Reader:
    """Reads one study file; every error names it."""

    def __init__(self, path: pathlib.Path) -> None:
        self.path = path

    def error(self, where: str, problem: str) -> CaseError:
        return CaseError(printable(f"{self.path.name}: {where}: {problem}" if where
                                   else f"{self.path.name}: {problem}"))

    def unknown(self, table: Mapping[str, Any], known: Sequence[str], where: str) -> None:
        for key in table:
            if key not in known:
                raise self.error(f"{where}{key}", f"unknown key{suggest(key, known)}")

    def values(self, table: Any, name: str) -> dict[str, list[Any]]:
        if not isinstance(table, Mapping):
            raise self.error(name, "expected a table of key = [values]")
        out = _flatten(table)
        for key, values in out.items():
            if not isinstance(values, list) or not values:
                raise self.error(f"{name}.{key}", "expected a non-empty list of values")
        return out

    def sample_count(self, table: Any) -> int:
        """``samples.count``, checked."""
        if not isinstance(table, Mapping):
            raise self.error("samples", "expected a table")
        count = table.get("count")
        if not isinstance(count, int) or isinstance(count, bool) or count < 1:
            raise self.error("samples.count", f"expected an integer >= 1 (got {count!r})")
        return count

    def samples(self, table: Any) -> list[dict[str, Any]]:
        import numpy as np

        count = self.sample_count(table)
        table = dict(table)
        del table["count"]
        seed = table.pop("seed", 0)
        if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
            raise self.error("samples.seed", f"expected an integer >= 0 (got {seed!r})")
        specs = _flatten(table, leaf=lambda v: not any(isinstance(x, Mapping)
                                                       for x in v.values()))
        if not specs:
            raise self.error("samples", "no key to sample")
        checked: dict[str, tuple[str, Any]] = {}
        for key, spec in specs.items():
            where = f"samples.{key}"
            if not isinstance(spec, Mapping) or len(spec) != 1:
                raise self.error(where, "expected one of {uniform = [a, b]}, "
                                 "{log_uniform = [a, b]}, {choice = [values]}")
            kind, args = next(iter(spec.items()))
            if kind not in DISTRIBUTIONS:
                raise self.error(f"{where}.{kind}", f"unknown distribution"
                                 f"{suggest(kind, DISTRIBUTIONS)}")
            if kind == "choice":
                if not isinstance(args, list) or not args:
                    raise self.error(where, "choice: expected a non-empty list")
            elif not (isinstance(args, list) and len(args) == 2 and all(map(_number, args))
                      and args[0] < args[1] and (kind == "uniform" or args[0] > 0)
                      and math.isfinite(args[1] - args[0])):  # numpy's uniform needs it
                raise self.error(where, f"{kind}: expected finite [a, b] with a < b"
                                 + (" and a > 0" if kind == "log_uniform" else ""))
            checked[key] = (kind, args)
        self.enough_points(checked, count)
        rng = np.random.default_rng(seed)
        rows = []
        for _ in range(count):
            row: dict[str, Any] = {}
            for key, (kind, args) in checked.items():
                if kind == "uniform":
                    row[key] = float(rng.uniform(args[0], args[1]))
                elif kind == "log_uniform":
                    row[key] = float(math.exp(rng.uniform(math.log(args[0]),
                                                          math.log(args[1]))))
                else:
                    row[key] = args[int(rng.integers(len(args)))]
            rows.append(row)
        return rows

    def enough_points(self, checked: Mapping[str, tuple[str, Any]], count: int) -> None:
        """Refuse more samples than the distinct points the choices can draw.

        When every key is a ``choice``, a ``count`` above the product of their distinct
        values makes identical cases, certainly (the grid refuses a value given twice).
        Fewer may still draw a point twice: sampling with replacement, by chance.
        """
        if any(kind != "choice" for kind, _ in checked.values()):
            return  # a uniform draw: distinct points
        distinct = math.prod(len({toml_literal(v) for v in args})
                             for _, args in checked.values())
        if count > distinct:
            where = f"samples.{next(iter(checked))}" if len(checked) == 1 else "samples"
            points = f"{distinct} distinct point{'s' * (distinct > 1)}"
            raise self.error(where, f"count = {count} draws of {points}: identical cases "
                             f"(count at most {distinct}, or each value once in [grid])")

    def derived(self, items: Any) -> tuple[Derived, ...]:
        if not isinstance(items, list) or not all(isinstance(d, Mapping) for d in items):
            raise self.error("derived", "expected [[derived]] tables")
        out = []
        for j, d in enumerate(items):
            where = f"derived[{j}]"
            self.unknown(d, DERIVED_KEYS, f"{where}.")
            for key in ("from", "key", "table"):
                if key not in d:
                    raise self.error(f"{where}.{key}", "missing")
            if not isinstance(d["from"], str) or not isinstance(d["key"], str):
                raise self.error(where, "from and key must be case keys (strings)")
            table = d["table"]
            if not (isinstance(table, list) and table and all(
                    isinstance(r, list) and len(r) == 2 for r in table)):
                raise self.error(f"{where}.table", "expected a list of [from, value] pairs")
            interpolate = d.get("interpolate", False)
            if not isinstance(interpolate, bool):
                raise self.error(f"{where}.interpolate", "expected true or false")
            rows = tuple((r[0], r[1]) for r in table)
            if interpolate:
                xs = [a for a, _ in rows]
                # Finite steps too: (x - x0) / (x1 - x0) of an infinite step is 0.
                if not all(_number(a) and _number(b) for a, b in rows) or \
                        not all(x1 > x0 and math.isfinite(x1 - x0) and math.isfinite(y1 - y0)
                                for (x0, y0), (x1, y1) in itertools.pairwise(rows)) or \
                        not all(map(math.isfinite, (*xs, *(b for _, b in rows)))):
                    raise self.error(f"{where}.table", "interpolate: expected finite numbers, "
                                     "the first column increasing")
            # A value given twice: value() took its first row, silently (a row copied and
            # its first column not edited).
            for k, (a, _) in enumerate(rows):
                if any(Derived.same(a, b) for b, _ in rows[:k]):
                    raise self.error(f"{where}.table", f"{d['from']} = {toml_literal(a)} is "
                                     "given twice in the first column (each value once)")
            out.append(Derived(d["from"], d["key"], rows, interpolate))
        return tuple(out)

    def figures(self, table: Any) -> dict[str, Any]:
        if not isinstance(table, Mapping):
            raise self.error("figures", "expected a table")
        self.unknown(table, FIGURE_KEYS, "figures.")
        out = dict(table)
        for key in ("x", "y"):
            if key in out and not (isinstance(out[key], list)
                                   and all(isinstance(c, str) for c in out[key])):
                raise self.error(f"figures.{key}", "expected a list of column names")
        limits = out.get("limits", [])
        if not (isinstance(limits, list) and all(_number(v) and float(v) > 0 for v in limits)):
            raise self.error("figures.limits", "expected a list of tolerable slidings (m), "
                             "each > 0")
        ref = out.get("reference", {})
        if not isinstance(ref, Mapping):
            raise self.error("figures.reference", "expected a table of column = value")
        for column, value in ref.items():
            marks = value if isinstance(value, Mapping) else {"": value}
            if not all(_number(v) for v in marks.values()):
                raise self.error(f"figures.reference.{column}", "expected a number or a "
                                 "table of label = number")
        return out


def load_study(path: str | pathlib.Path, overrides: Sequence[str] | None = (),
               max_points: int = MAX_POINTS) -> Study:
    """Read a study file into its points (the cases are not read: :func:`check_points`).

    Args:
        path: The study file.
        overrides: ``key=value`` case overrides added to ``[set]`` (``--set``), a list
            or a tuple of strings (None: none); a key the study varies may not be given.
        max_points: Refuse a study of more points (counted before any is drawn).

    Raises:
        CaseError: One line naming the file and the problem.

    """
    file_argument(path, "a study file")
    overrides = override_list(overrides, "load_study('study.toml', ['time.end_time=0.05'])")
    path = pathlib.Path(path)
    if not path.is_file():
        raise CaseError(f"{path}: study file not found")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise CaseError(f"{path.name}: invalid TOML ({e})") from None
    except ValueError as e:  # tomllib's int() of an integer of more than 4300 digits
        raise CaseError(f"{path.name}: invalid TOML ({str(e).split(':')[0]})") from None
    r = _Reader(path)
    key = out_of_range(data)
    if key is not None:
        raise r.error(key, OUT_OF_RANGE)
    r.unknown(data, TOP_KEYS, "")
    for key in ("name", "description", "base"):
        if key in data and not isinstance(data[key], str):
            raise r.error(key, "expected a string")
    name = data.get("name", path.stem)
    problem = name_problem(name)
    if problem is not None:  # the name is the default folder results/<name>
        raise r.error("name", problem)
    if "base" not in data:
        raise r.error("base", 'missing (a case file, or a built-in case such as "goda")')
    base = data["base"]
    problem = path_problem(base)
    if problem is not None:  # a NUL byte or a name too long: ValueError, OSError
        raise r.error("base", problem)
    candidate = path.parent / base
    if candidate.is_file():
        base = str(candidate.resolve())
    elif pathlib.Path(base).suffix or "/" in base:
        raise r.error("base", f"case file not found: {candidate}")
    if not isinstance(data.get("set", {}), Mapping):
        raise r.error("set", "expected a table of key = value")
    # As given: a table is merged into the case's, or is a new entry of a named
    # collection ("fixed.rear" = {components = [0]}), which its dotted keys could not make.
    fixed = dict(data.get("set", {}))
    for spec in overrides:
        key, sep, text = spec.partition("=")
        if not sep:
            raise CaseError(f"{OVERRIDE} {spec}: expected key=value")
        fixed[key.strip()] = _Literal(text.strip())
    fixed_keys = _flatten(fixed)
    grid = r.values(data.get("grid", {}), "grid")
    for key, listed in grid.items():  # two identical cases (a storm counted twice)
        texts = [toml_literal(v) for v in listed]
        twice = next((t for j, t in enumerate(texts) if t in texts[:j]), None)
        if twice is not None:
            raise r.error(f"grid.{key}", f"{twice} is given twice (each value once)")
    zipped = r.values(data.get("zip", {}), "zip")
    lengths = {len(v) for v in zipped.values()}
    if len(lengths) > 1:
        raise r.error("zip", f"the lists have different lengths ({sorted(lengths)})")
    n_points = math.prod(len(v) for v in grid.values()) * (lengths.pop() if lengths else 1)
    if "samples" in data:
        n_points *= r.sample_count(data["samples"])
    if n_points > max_points:
        raise r.error("", f"{n_points:.4g} points, above the limit of {max_points} (every "
                      "point's case is read before the study starts, and each runs; "
                      "sweep --max-points N raises the limit)")
    samples = r.samples(data["samples"]) if "samples" in data else []
    derived = r.derived(data.get("derived", []))
    varied = [*grid, *zipped, *(samples[0] if samples else {})]
    if not varied:
        raise r.error("", "empty study: nothing to vary (give [grid], [zip] or [samples])")
    given = {k for k, v in fixed.items() if isinstance(v, _Literal)}  # by --set
    seen: dict[str, str] = {}
    for key in [*varied, *(d.key for d in derived)]:
        if key in given:  # a --set value was named as the study file's
            raise CaseError(printable(f"{OVERRIDE} {key}: the study varies it (a key is "
                                      "varied, derived or set only once)"))
        if key in seen or key in fixed_keys:
            raise r.error(key, "set twice (a key is varied, derived or set only once)")
        seen[key] = key
        if key in RESERVED:
            raise r.error(key, "is set by the sweep (one folder per case)")
    for key in fixed_keys:
        if key in RESERVED:
            if key in given:
                raise CaseError(printable(f"{OVERRIDE} {key}: is set by the sweep (one "
                                          "folder per case; sweep --out DIR: the study's)"))
            raise r.error(f"set.{key}", "is set by the sweep (one folder per case)")
    for d in derived:
        if d.source not in varied:
            raise r.error(f"derived {d.key}", f"from: '{d.source}' is not a varied key"
                          f"{suggest(d.source, varied)}")
    zip_rows = [dict(zip(zipped, row, strict=True)) for row in zip(*zipped.values(),
                                                                  strict=True)]
    axes: list[list[dict[str, Any]]] = [[{k: v} for v in values] for k, values in grid.items()]
    if zip_rows:
        axes.append(zip_rows)
    if samples:
        axes.append(samples)
    points = []
    for index, combo in enumerate(itertools.product(*axes)):
        values: dict[str, Any] = {}
        for part in combo:
            values.update(part)
        points.append(Point(index, values))  # derived values: check_points
    figures = r.figures(data.get("figures", {}))
    return Study(path, name, data.get("description", ""), base,
                 {k: v for k, v in fixed.items()}, tuple(varied), derived, tuple(points),
                 figures)


class _Literal(str):
    """A ``--set`` value kept as its TOML text."""


def _fixed_overrides(study: Study) -> list[str]:
    """The ``[set]`` values, labelled with the study file, and ``--set``'s."""
    return [Override(f"{k}={v}") if isinstance(v, _Literal)
            else Override(f"{k}={toml_literal(v)}", study.path.name)
            for k, v in study.fixed.items()]


def with_derived(study: Study, point: Point) -> Point:
    """The point with its derived values (CaseError when a table gives none)."""
    values = dict(point.values)
    for d in study.derived:
        values[d.key] = d.value(values[d.source])
    return Point(point.index, values)


def _relative_to_study(study: Study, values: Mapping[str, Any]) -> dict[str, Any]:
    """The values, file paths (``mesh.source``, a table's ``file``) resolved.

    Against the study file's folder; ``--set`` values (kept as text) are left to the
    working directory.
    """
    from breakwater.casefile.case import is_file_value

    folder = study.path.parent

    def relative(key: str, value: Any) -> Any:
        if isinstance(value, Mapping):  # a table: its keys' paths
            return {k: relative(f"{key}.{k}", v) for k, v in value.items()}
        if not isinstance(value, _Literal) and is_file_value(key, value) \
                and path_problem(value) is None:  # else the case's error names the path
            return str((folder / value).resolve())  # (tomlfiles.resolved)
        return value

    return {k: relative(k, v) for k, v in values.items()}


def case_of(study: Study, point: Point, folder: pathlib.Path) -> Case:
    """The case of a point (its derived values included), output in ``folder``."""
    from breakwater.casefile.case import load_case

    fixed = replace(study, fixed=_relative_to_study(study, study.fixed))
    values = Point(point.index, _relative_to_study(study, point.values))
    # The study's values named as its file's, --set's as --set's (the messages).
    overrides = [*_fixed_overrides(fixed),
                 *(Override(o, study.path.name) for o in values.overrides()),
                 Override(f"output.directory={toml_literal(str(folder))}", study.path.name)]
    return load_case(study.base, overrides)


def check_points(study: Study, out: pathlib.Path) -> tuple[list[Point], list[Case]]:
    """Every point's case, read and validated before anything runs.

    Returns:
        The points with their derived values, and their cases (output in
        ``out/<point folder>``).

    Raises:
        CaseError: One line: each bad point with its error (points with the same
            error, e.g. of a ``[set]`` value, are named together).

    """
    points, cases = [], []
    bad: dict[str, list[str]] = {}
    for p in study.points:
        try:
            q = with_derived(study, p)
            cases.append(case_of(study, q, out / q.folder))
            points.append(q)
        except CaseError as e:
            bad.setdefault(_strip(e, study.path.name), []).append(p.label())
    if len(bad) == 1 and len(next(iter(bad.values()))) == len(study.points) \
            and next(iter(bad)).startswith(OVERRIDE):  # a --set value: every case
        raise CaseError(printable(f"{next(iter(bad))} (every case of {study.path.name})"))
    if bad:
        n = sum(map(len, bad.values()))
        parts = [f"{labels[0] if len(labels) == 1 else _names(labels)}: {message}"
                 for message, labels in bad.items()]
        if len(parts) > SHOWN_ERRORS:  # a line of every sampled point's error: 30 kB
            rest = sum(len(labels) for labels in list(bad.values())[SHOWN_ERRORS:])
            parts = [*parts[:SHOWN_ERRORS], f"and {rest} more point{'s' * (rest > 1)} "
                     "with other errors"]
        raise CaseError(printable(f"{study.path.name}: {n} of {len(study.points)} points "
                                  f"make an invalid case: " + "; ".join(parts)))
    _check_figure_columns(study, cases)
    return points, cases


def _check_figure_columns(study: Study, cases: Sequence[Case]) -> None:
    """Refuse a ``[figures]`` column that ``sweep.csv`` will not have (CaseError).

    The columns: the study's keys, ``wall_time`` and the headline columns its cases
    can give (:func:`breakwater.studies.columns.headline_columns`).
    """
    from breakwater.studies.columns import headline_columns

    known: dict[str, None] = dict.fromkeys([*study.keys, "wall_time"])
    for case in cases:
        known.update(dict.fromkeys(headline_columns(case.resolved())))
    spec = study.figures
    named = [*((f"figures.{axis}", c) for axis in ("x", "y") for c in spec.get(axis, ())),
             *((f"figures.reference.{c}", c) for c in spec.get("reference", {}))]
    for where, column in named:
        if column not in known:
            raise _Reader(study.path).error(
                where, f"'{column}' is not a column of the study's sweep.csv"
                f"{suggest(column, list(known))}")


def _names(labels: Sequence[str]) -> str:
    """``case-0001, case-0004 (2 points)`` from point labels."""
    return f"{', '.join(x.split(' ', 1)[0] for x in labels)} ({len(labels)} points)"


def _strip(error: CaseError, label: str) -> str:
    """The error of a point's case, without the study's label (``--set``'s kept)."""
    text = " ".join(str(error).split())
    return text.removeprefix(f"{label}: ").removeprefix(f"{label} ")
