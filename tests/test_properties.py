"""Property-based tests of the load-time layer: generated inputs never end in a traceback.

Generated case files (mutations of the built-in Goda case and of the tests' two-block
case: values of every TOML type, unknown keys, missing keys, broken TOML text),
``--set`` overrides, load tables (CSV text) and study files are read as the program
reads them
(:func:`~breakwater.casefile.case.load_case`, ``show-case``,
:func:`~breakwater.studies.studyfile.load_study` and
:func:`~breakwater.studies.studyfile.check_points`). The outcome must be a valid object or one
:class:`~breakwater.common.errors.CaseError` of one line naming the file; never another
exception, never a hang, never a multi-line message. A case that loads must round-trip
(``show-case`` prints a file that loads back to the same case); a table that loads holds
the rows that were written, as finite, increasing numbers.

Reproducible: every test is derandomised (hypothesis draws the same examples on every
run, on every machine and on every MPI rank) and keeps no example database. Every
minimal failing example found so far is kept as a file in ``tests/bad_cases`` (``x*``,
``z*``; an override's in ``tests/bad_cases/run``) or ``tests/bad_studies`` (``y*``,
``q*``). Every class of input is generated: NUL bytes and over-long names in paths,
files that are not UTF-8, names with line breaks, spreadsheet tables, huge sizes. Each
example runs under a wall-clock alarm (:func:`time_limit`) besides hypothesis'
deadline, so that a hang fails instead of stalling the suite.

Pure Python: no mesh is built and nothing runs (the two-block case names a ``.msh``
file of which the case layer reads only the ``$PhysicalNames`` header). Serial only:
nothing on these paths depends on the rank (no collective; the one rank-dependent line,
an input error printed by rank 0 alone, runs on 2 ranks in ``tests/test_bad_runs.py``'s
refused runs, through the same :func:`breakwater.cli.main`).
"""

from __future__ import annotations

import contextlib
import copy
import datetime
import io
import itertools
import math
import os
import pathlib
import re
import signal
import string
import tempfile
import tomllib
from collections.abc import Iterator
from typing import Any

import pytest
import tomli_w
from blocks import two_block_case
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st
from mpi4py import MPI

from breakwater import cli
from breakwater.casefile.case import BUILTIN_CASES, Case, load_case
from breakwater.common.errors import CaseError
from breakwater.config.fields import schema_keys
from breakwater.config.tomlfiles import display
from breakwater.studies.studyfile import check_points, load_study, toml_literal

pytestmark = pytest.mark.serial  # pure Python, no rank-dependent path (module doc)

EXAMPLES = int(os.environ.get("BREAKWATER_PROPERTY_EXAMPLES", "120"))
"""Examples per test (the file runs in about 20 s of CPU serially). To explore, set
``BREAKWATER_PROPERTY_EXAMPLES`` (e.g. 3000) and ``BREAKWATER_PROPERTY_RANDOM=1``
(new random examples on every run instead of the fixed ones)."""
PROFILE = settings(max_examples=EXAMPLES, database=None,
                   derandomize=not os.environ.get("BREAKWATER_PROPERTY_RANDOM"),
                   deadline=5000,  # ms: an example takes 10-50 ms of CPU; a loaded machine, 10x+
                   suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much,
                                          HealthCheck.data_too_large])
LIMIT = 30.0
"""Seconds after which an example counts as a hang (the alarm of :func:`time_limit`)."""


class Hang(Exception):
    """An example ran past :data:`LIMIT`."""


@contextlib.contextmanager
def time_limit(seconds: float = LIMIT) -> Iterator[None]:
    """Raise :class:`Hang` in the block after ``seconds`` of wall time (SIGALRM)."""
    def alarm(signum: int, frame: Any) -> None:
        raise Hang(f"still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


# --- the folder of the examples -----------------------------------------------------

# The two-block case's mesh: only its $PhysicalNames header is read when a case is
# loaded (breakwater.common.gmshtools), so this header stands for the mesh of
# blocks.two_rectangles (stacked, equal widths) without building one.
MSH_HEADER = """$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
11
0 13 "a_corner"
1 3 "interface"
1 4 "a_top"
1 5 "a_left"
1 6 "a_right"
1 7 "b_bottom"
1 8 "b_left"
1 9 "b_right"
2 1 "a"
2 2 "b"
1 10 "b_top_free"
$EndPhysicalNames
"""

TWO_BLOCK_TAIL = """
[loads.push]
group = "a_left"
time_function = "table"
pressure = 1e5
[loads.push.table]
points = [[0.0, 0.0], [1e-3, 1.0]]
hold_last = true
[output.probes.corner]
body = "a"
group = "a_corner"
[output.pair_probes.slip]
pair = "interface"
point = [0.0, 1.0]
"""


@pytest.fixture(scope="module")
def here() -> Iterator[pathlib.Path]:
    """A folder of this process (each MPI rank its own) holding the mesh header."""
    with tempfile.TemporaryDirectory(prefix="props") as folder:
        path = pathlib.Path(folder)
        (path / "blocks.msh").write_text(MSH_HEADER)
        (path / "other.toml").write_text(two_block_text())  # extends = "other.toml"
        yield path


def two_block_text() -> str:
    """The two-block case (mesh ``blocks.msh`` beside the case file), loads and probes."""
    return two_block_case("blocks.msh", tail=TWO_BLOCK_TAIL)


GODA_TEXT = (BUILTIN_CASES / "goda.toml").read_text(encoding="utf-8")
GODA_RESOLVED = load_case().resolved()


# --- what every outcome must be ------------------------------------------------------

def one_line(message: str) -> bool:
    """True for a message of one line (no character that starts another line)."""
    return message.splitlines() == [message] and message.isprintable()


def outcome(path: pathlib.Path) -> Case | CaseError:
    """``load_case(path)``: the case, or its CaseError checked for one line naming the file."""
    try:
        with time_limit():
            return load_case(path)
    except CaseError as e:
        message = str(e)
        assert one_line(message), repr(message)
        assert path.name in message.split(": ", 1)[0], message  # the file is named first
        return e


def show_case(path: pathlib.Path) -> tuple[int, str, str]:
    """``breakwater show-case path``: exit status, stdout, stderr."""
    out, err = io.StringIO(), io.StringIO()
    with time_limit(), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = cli.main(["show-case", str(path)])
    return status, out.getvalue(), err.getvalue()


def check_case_file(path: pathlib.Path, note: bool = True) -> Case | CaseError:
    """The outcome of a case file, through ``load_case`` and through ``show-case``.

    A case that loads must round-trip: ``show-case`` prints its resolved TOML, which
    loads back to the same case.
    """
    result = outcome(path)
    if note:  # hypothesis' statistics (--hypothesis-show-statistics)
        event("loaded" if isinstance(result, Case) else "refused")
    status, out, err = show_case(path)
    printing = MPI.COMM_WORLD.rank == 0
    if isinstance(result, CaseError):
        assert status == 2 and out == "", (status, out)
        if printing:
            assert err == f"breakwater: error: {' '.join(str(result).split())}\n", err
        return result
    assert status == 0 and err == "", (status, err)
    assert result.name.splitlines() == [result.name], repr(result.name)  # z2
    gx, gy = result.gravity  # the weights and energies of the run are finite (z7, z8)
    assert math.isfinite(gx * gx + gy * gy), result.gravity
    assert all(math.isfinite(b.density * max(abs(gx), abs(gy))) for b in result.bodies)
    for load in result.loads:  # what a pulse derives from the case is finite too
        if load.kind == "pulse":
            assert math.isfinite(load.total_impulse / result.out_of_plane_length), load
    data = result.resolved()
    text = out if printing else tomli_w.dumps(data)
    assert tomllib.loads(text) == data
    again = path.with_name(f"{path.stem}.resolved.toml")
    again.write_text(text, encoding="utf-8")
    back = outcome(again)
    assert isinstance(back, Case), back
    assert back.resolved() == data
    assert back == result or back.name == result.name  # equal but for the file's stem
    return result


# --- generated TOML values -------------------------------------------------------------

NAMES = ("goda", "caisson", "mound", "interface", "impact", "base", "a", "b", "a_left",
         "a_corner", "b_bottom", "pulse", "constant", "ramp", "table", "triangular",
         "half-sine", "block", "metre", "fast", "reference", "segments", "nodes", "small",
         "blocks.msh", "missing.csv", "other.toml", "case.toml", "")
"""Strings the case layer knows (names of groups, bodies, choices), so that mutated
cases often still load."""

floats = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 5e-324, 1e-300, 1e-12, 1e-4, 0.5, 1.0, 2.0, 1e6, 1e12,
                     1e300, 1.7976931348623157e308, -1.0, -1e300]),
    st.floats(1e-6, 1e4),  # near the case's own values: many mutated cases load
)
integers = st.one_of(st.integers(-3, 60), st.integers(-2**70, 2**70),
                     st.sampled_from([2**63 - 1, -2**63, 2**63, 10**400, -10**400]))
PATHS = ("a\x00b", "x" * 300, "x/" * 2100, "wave\u2028case", "a\x85b", "nul.csv\x00")
"""Strings no path or name can hold: a NUL byte, a name over 255 bytes, a path over
4095 bytes, line breaks (z4-z6, q2, q3; z2, q1)."""
texts = st.one_of(st.sampled_from(NAMES), st.text(max_size=12),
                  st.text(string.printable, max_size=12), st.sampled_from(PATHS))
dates = st.one_of(st.dates(), st.datetimes(), st.times())
scalars = st.one_of(floats, integers, st.booleans(), texts, dates)


values = st.recursive(
    scalars,
    lambda inner: st.one_of(st.lists(inner, max_size=4),
                            st.dictionaries(st.one_of(st.sampled_from(NAMES[:12]),
                                                      st.text(max_size=8)),
                                            inner, max_size=3)),
    max_leaves=8)
"""Every kind of TOML value: numbers of every size, strings, dates, arrays, tables."""


# --- mutations of a case's data ----------------------------------------------------------

def paths_of(data: Any, prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    """Every key path of nested tables (tables and leaves)."""
    out = []
    if isinstance(data, dict):
        for k, v in data.items():
            out.append((*prefix, k))
            out += paths_of(v, (*prefix, k))
    return out


def schema_paths(data: dict[str, Any]) -> list[tuple[str, ...]]:
    """The schema's keys, ``<name>`` replaced by an entry of the data (or a new one)."""
    out = []
    for key in schema_keys(Case):
        parts = key.split(".")
        if "<name>" not in parts:
            out.append(tuple(parts))
            continue
        i = parts.index("<name>")
        table = data
        for p in parts[:i]:
            table = table.get(p, {}) if isinstance(table, dict) else {}
        names = list(table) if isinstance(table, dict) else []
        for name in [*names[:1], "extra"]:
            full = [*parts[:i], name, *parts[i + 1:]]
            if "<name>" not in full:
                out.append(tuple(full))
    return out


def set_path(data: dict[str, Any], path: tuple[str, ...], value: Any) -> None:
    node = data
    for p in path[:-1]:
        if not isinstance(node.get(p), dict):
            node[p] = {}
        node = node[p]
    node[path[-1]] = value


def delete_path(data: dict[str, Any], path: tuple[str, ...]) -> None:
    node: Any = data
    for p in path[:-1]:
        node = node.get(p) if isinstance(node, dict) else None
    if isinstance(node, dict):
        node.pop(path[-1], None)


def mutations(data: dict[str, Any]) -> st.SearchStrategy[list[tuple[str, Any, Any]]]:
    """Lists of edits of ``data``: set a key (known or not) to a value, delete a key."""
    known = sorted(set(paths_of(data)) | set(schema_paths(data)) | {("extends",)})
    tables = [()] + [p for p in paths_of(data) if isinstance(_get(data, p), dict)]
    numeric = [p for p in paths_of(data) if _numbers(_get(data, p))]
    kinds = {
        "scale": st.tuples(st.just("scale"), st.sampled_from(numeric), factors),
        "set": st.tuples(st.just("set"), st.sampled_from(known), values),
        "delete": st.tuples(st.just("delete"), st.sampled_from(known), st.none()),
        "unknown": st.tuples(st.just("unknown"), st.sampled_from(tables),
                             st.tuples(st.text(min_size=1, max_size=10), values)),
    }
    # Scaled numbers half of the time: an edited case that loads is tested further.
    edit = st.sampled_from(["scale", "scale", "scale", "set", "delete", "unknown"]
                           ).flatmap(kinds.__getitem__)
    return st.lists(edit, min_size=1, max_size=3)


factors = st.one_of(st.sampled_from([0.0, -1.0, 0.5, 2.0, 10.0, 1e-300, 1e300]),
                    st.floats(0.1, 10.0))
"""Factors of a number of the case: the value keeps its type, the case often loads."""


def _numbers(value: Any) -> bool:
    """A number or an array of numbers (not booleans)."""
    if isinstance(value, list):
        return bool(value) and all(map(_numbers, value))
    return isinstance(value, int | float) and not isinstance(value, bool)


def _scale(value: Any, factor: float) -> Any:
    if isinstance(value, list):
        return [_scale(v, factor) for v in value]
    scaled = value * factor
    return int(scaled) if isinstance(value, int) and math.isfinite(scaled) else scaled


def _get(data: Any, path: tuple[str, ...]) -> Any:
    for p in path:
        data = data[p]
    return data


def _get_or_none(data: Any, path: tuple[str, ...]) -> Any:
    for p in path:
        if not isinstance(data, dict) or p not in data:
            return None
        data = data[p]
    return data


def mutate(data: dict[str, Any], edits: list[tuple[str, Any, Any]]) -> dict[str, Any]:
    data = copy.deepcopy(data)
    for kind, path, arg in edits:
        if kind == "scale":
            if _numbers(_get_or_none(data, path)):
                set_path(data, path, _scale(_get(data, path), arg))
        elif kind == "set":
            set_path(data, path, arg)
        elif kind == "delete":
            delete_path(data, path)
        else:
            key, value = arg
            set_path(data, (*path, key), value)
    return data


GODA_DATA = tomllib.loads(GODA_TEXT)
TWO_BLOCK_DATA = tomllib.loads(two_block_case("blocks.msh", tail=TWO_BLOCK_TAIL))
BASES = {"goda": GODA_DATA, "goda-resolved": GODA_RESOLVED, "two-block": TWO_BLOCK_DATA}


@PROFILE
@given(st.sampled_from(sorted(BASES)).flatmap(
    lambda base: st.tuples(st.just(base), mutations(BASES[base]))))
@example(("goda", [("set", ("gravity",), [1e308, 1e308])]))  # z7
@example(("goda", [("scale", ("mesh", "refinement"), 1e300)]))  # z3
def test_generated_case_files(here, example):
    base, edits = example
    data = mutate(BASES[base], edits)
    path = here / "case.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    check_case_file(path)


def test_the_bases_load(here):
    """The unedited bases load (so the edits above start from valid cases)."""
    for name, data in BASES.items():
        path = here / f"{name}.toml"
        path.write_text(tomli_w.dumps(data), encoding="utf-8")
        assert isinstance(check_case_file(path, note=False), Case), name


# --- generated overrides ------------------------------------------------------------------

override_keys = st.one_of(
    st.sampled_from([".".join(k) for k in schema_paths(GODA_RESOLVED)]),
    st.sampled_from([".".join(k) for k in paths_of(GODA_RESOLVED)]),
    st.text(max_size=12))
override_texts = st.one_of(values.map(toml_literal), st.text(max_size=12))


@PROFILE
@given(st.lists(st.tuples(override_keys, st.sampled_from(["=", " = ", "", "=="]),
                          override_texts), min_size=1, max_size=2))
@example([("loads.impact.goda.period", "=", "8")])  # tests/bad_cases/run/x7_*
@example([("contact.interface.slave_surface", "=", '""')])  # the file's table, the error
def test_generated_overrides(specs):
    """``--set key=value`` of the Goda case: a case or one line naming ``--set``."""
    overrides = [f"{key}{sep}{text}" for key, sep, text in specs]
    try:
        with time_limit():
            case = load_case(None, overrides)
    except CaseError as e:
        message = str(e)
        assert one_line(message), repr(message)
        # The override, or the case file whose key the override contradicts.
        assert message.startswith(("--set", f"{display(BUILTIN_CASES / 'goda.toml')}: ")), \
            message
        if message.startswith("--set"):
            return
        # A key of a table the file gives (not of one an override made: x7).
        key = re.sub(r"\[\d+\]", "", message.split(": ", 2)[1])
        tables = {".".join(p) for p in paths_of(GODA_DATA)} | {""}
        assert key in tables or key.rpartition(".")[0] in tables, message
        return
    assert isinstance(case, Case)
    assert case.name.splitlines() == [case.name], repr(case.name)  # z2
    with tempfile.TemporaryDirectory() as folder:
        path = pathlib.Path(folder) / "resolved.toml"
        path.write_text(tomli_w.dumps(case.resolved()), encoding="utf-8")
        assert load_case(path).resolved() == case.resolved()


# --- broken TOML text -------------------------------------------------------------------

edits_of_text = st.lists(st.tuples(
    st.sampled_from(["insert", "delete", "replace", "duplicate"]),
    st.floats(0, 1), st.floats(0, 1),
    st.one_of(st.text(max_size=6), st.sampled_from(["[", "]", "=", '"', "'''", "\n",
                                                    "\\", "[[", "#", ".", ",", "{",
                                                    "extends = ", "nan", "inf"]))),
    min_size=1, max_size=3)


def edit_text(text: str, edits: list[tuple[str, float, float, str]]) -> str:
    for kind, a, b, piece in edits:
        i = int(a * len(text))
        j = min(len(text), i + 1 + int(b * 40))
        if kind == "insert":
            text = text[:i] + piece + text[i:]
        elif kind == "delete":
            text = text[:i] + text[j:]
        elif kind == "replace":
            text = text[:i] + piece + text[j:]
        else:
            text = text[:j] + text[i:j] + text[j:]
    return text


@PROFILE
@given(st.sampled_from(["goda", "two-block"]), edits_of_text)
def test_edited_case_text(here, base, edits):
    text = edit_text(GODA_TEXT if base == "goda" else two_block_text(), edits)
    path = here / "text.toml"
    path.write_bytes(text.encode("utf-8", "surrogatepass"))
    check_case_file(path)


def _utf8(data: bytes) -> bool:
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        return False
    return True


# --- generated load tables ----------------------------------------------------------------

def _cell(x: float, style: int) -> str:
    return (repr(x), f"{x:g}", f"{x:.6e}", f"{x:.3f}")[style]


@st.composite
def tables(draw: st.DrawFn) -> tuple[str, list[tuple[float, float]], str | None]:
    """CSV text of a load table, the rows written, and why it must be refused (or None).

    Reasons: ``"cell"`` (a data row that is not two numbers), ``"value"`` (a number
    that is not finite), ``"order"`` (times that do not increase, fewer than 2 rows).
    """
    n = draw(st.integers(0, 6))
    number = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)
    times = draw(st.lists(number, min_size=n, max_size=n))
    if draw(st.integers(0, 3)):  # mostly increasing (the others: "order")
        times.sort()
    style = draw(st.integers(0, 3))
    cells = [[_cell(t, style), _cell(draw(number), style)] for t in times]
    written = [(float(a), float(b)) for a, b in cells]
    separator = draw(st.sampled_from([",", ", ", " ", "\t", "  ,  "]))
    newline = draw(st.sampled_from(["\n", "\r\n", "\r"]))
    # A header in the data's separator (the reader takes one separator per file).
    header = draw(st.sampled_from([None, "t{}value", "time (s){}factor", "t v"]))
    header = None if header is None else header.format(separator)
    reason = None
    if len(written) < 2 or any(b[0] <= a[0] for a, b in itertools.pairwise(written)):
        reason = "order"
    garbage = draw(st.one_of(st.none(), st.tuples(
        st.integers(0, max(0, n - 1)), st.integers(0, 1),
        st.sampled_from(["nan", "inf", "-inf", "1e400", "abc", "", "0x10", "--1", "1;2",
                         "t", "1_0", "\u0663", "0,,1",
                         # a decimal comma: a number in a tab-separated file
                         *(["1,2"] if separator != "\t" else [])]))))
    if garbage is not None and cells:
        i, j, text = garbage
        cells[i][j] = text
        reason = "value" if text in ("nan", "inf", "-inf", "1e400") else "cell"
    lines = [] if header is None else [header]
    for k, row in enumerate(cells):
        if k and draw(st.booleans()):
            lines.append(draw(st.sampled_from(["", "# comment", "   ", "#"])))
        lines.append(separator.join(row) + draw(st.sampled_from(["", "  # note", " "])))
    return newline.join(lines) + draw(st.sampled_from(["", newline])), written, reason


CASE_WITH_TABLE = """extends = "goda"
time.end_time = 0.01
[loads.measured]
group = "impact"
time_function = "table"
pressure = 1e3
[loads.measured.table]
file = "measured.csv"
hold_last = true
"""


@PROFILE
@given(tables())
def test_generated_load_tables(here, table):
    text, rows, reason = table
    (here / "measured.csv").write_bytes(text.encode("utf-8"))
    path = here / "with_table.toml"
    path.write_text(CASE_WITH_TABLE, encoding="utf-8")
    result = check_case_file(path)
    if reason is not None:
        assert isinstance(result, CaseError), text
        # The CSV file and its line (a file of fewer than two rows: the file).
        where = (r"measured\.csv: a table needs at least two" if len(rows) < 2
                 and reason == "order" else r"measured\.csv line \d+")
        assert re.search(where, str(result)), (str(result), text)
        return
    if rows[0][0] >= 0.01:  # at or after CASE_WITH_TABLE's end: the load never acts (t6)
        assert isinstance(result, CaseError), text
        assert "loads.measured.table: the table's first point" in str(result), str(result)
        return
    assert isinstance(result, Case), (str(result), text)
    (load,) = [ld for ld in result.loads if ld.name == "measured"]
    assert load.table is not None
    history = load.table.history()
    assert list(zip(history.times, history.values, strict=True)) == rows
    assert all(map(math.isfinite, (*history.times, *history.values)))


# --- generated study files ----------------------------------------------------------------

CASE_KEYS = ["contact.interface.friction", "bodies.mound.density", "time.dt",
             "time.end_time", "loads.impact.duration", "loads.impact.peak",
             "mesh.goda.bolt_height", "loads.impact.pendulum.cord_length", "description",
             "loads.impact.shape", "calibration.enabled", "output.figures", "gravity",
             "name", "output.directory", "time", "unknown.key", ""]
"""Case keys a study varies: valid ones, reserved ones, tables, unknown ones."""

keys = st.one_of(st.sampled_from(CASE_KEYS), st.text(max_size=8))
small_lists = st.lists(values, min_size=0, max_size=3)
distribution = st.one_of(
    st.fixed_dictionaries({"uniform": st.lists(floats, min_size=0, max_size=3)}),
    st.fixed_dictionaries({"log_uniform": st.lists(floats, min_size=2, max_size=2)}),
    st.fixed_dictionaries({"choice": small_lists}),
    values)


@st.composite
def studies(draw: st.DrawFn) -> dict[str, Any]:
    """A study file's data: base, [set], [grid], [zip], [samples], [[derived]], [figures]."""
    data: dict[str, Any] = {}
    base = draw(st.sampled_from(["goda", "blocks.toml", "missing.toml", "nope", None,
                                 *PATHS]))
    if base is not None:
        data["base"] = base
    if draw(st.booleans()):
        data["name"] = draw(st.one_of(st.sampled_from(["s", "a/b", ""]), values))
    for table in ("set", "grid", "zip"):
        if draw(st.booleans()):
            data[table] = draw(st.dictionaries(keys, small_lists if table != "set"
                                               else values, max_size=2))
    if draw(st.booleans()):
        samples = draw(st.dictionaries(keys, distribution, max_size=2))
        if draw(st.booleans()):
            samples["count"] = draw(st.one_of(st.integers(-1, 3), values,
                                               st.sampled_from([1001, 10**9, 2**63])))
        if draw(st.booleans()):
            samples["seed"] = draw(st.one_of(st.integers(-2**70, 2**70), values))
        data["samples"] = samples
    if draw(st.booleans()):
        varied = [*data.get("grid", {}), *data.get("zip", {})] or ["time.dt"]
        data["derived"] = draw(st.lists(st.fixed_dictionaries(
            {"from": st.one_of(st.sampled_from(varied), values),
             "key": keys,
             "table": st.lists(st.lists(values, min_size=2, max_size=2), max_size=3)},
            optional={"interpolate": st.one_of(st.booleans(), values)}), max_size=2))
    if draw(st.booleans()):
        data["figures"] = draw(st.dictionaries(
            st.sampled_from(["x", "y", "reference", "reference_label", "z"]), values,
            max_size=2))
    if draw(st.booleans()):
        data[draw(st.text(min_size=1, max_size=6))] = draw(values)
    return data


@PROFILE
@given(studies())
def test_generated_study_files(here, data):
    (here / "blocks.toml").write_text(two_block_text(), encoding="utf-8")
    path = here / "study.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    try:
        with time_limit():
            study = load_study(path)
            points, cases = check_points(study, here / "out")
    except CaseError as e:
        message = str(e)
        assert one_line(message), repr(message)
        assert message.startswith(path.name), message
        return
    assert len(points) == len(cases) == len(study.points) >= 1
    assert all(isinstance(c, Case) for c in cases)


@PROFILE
@given(values)
def test_toml_literal_round_trips(value):
    """A study's value is given to its cases as TOML text: it must read back the same."""
    text = toml_literal(value)
    back = tomllib.loads(f"v = {text}")["v"]
    assert _same(back, value), (value, text, back)


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a):
        return math.isnan(b)
    if isinstance(a, list) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(map(_same, a, b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, datetime.time | datetime.datetime) and type(a) is type(b):
        return a == b
    return type(a) is type(b) and a == b
