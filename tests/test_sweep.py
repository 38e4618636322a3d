"""Parameter studies (breakwater.studies.studyfile, breakwater.studies.sweep): points, bad
studies, MPI groups, resume after a kill, a failing point.

The sweeps run the Goda case for 3 ms (30 steps, about 1 s a case): the numbers are
the headline numbers of real runs, compared across the ways of running them.
"""

from __future__ import annotations

import csv
import json
import math
import os
import pathlib
import re
import signal
import subprocess
import sys
import time

import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports the PETSc of the dolfinx wheel first)

# isort: split
from breakwater import cli
from breakwater.casefile.case import load_case
from breakwater.common.errors import CaseError
from breakwater.outputs import checkpoint
from breakwater.studies.columns import TABLE_COLUMNS, headline_columns
from breakwater.studies.studyfile import check_points, load_study, toml_literal
from breakwater.studies.sweep import RECORD, TABLE, run_study

COMM = MPI.COMM_WORLD
BAD = pathlib.Path(__file__).parent / "bad_studies"
BAD_FILES = sorted(BAD.glob("*.toml"))
EXAMPLES = pathlib.Path(__file__).parents[1] / "examples"

SHORT = '''base = "goda"
[set]
"time.end_time" = {end}
"output.field_interval" = 0
"output.figures" = false
'''


def study_file(folder: pathlib.Path, body: str, end: float = 0.003,
               name: str = "study.toml") -> pathlib.Path:
    """A study of the short Goda case (written by rank 0, seen by every rank)."""
    path = folder / name
    if COMM.rank == 0:
        path.write_text(SHORT.format(end=end) + body)
    COMM.barrier()
    return path


def read_table(path: pathlib.Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def expected(path: pathlib.Path) -> str:
    first = path.read_text().splitlines()[0]
    assert first.startswith("# expect: "), path
    return first.removeprefix("# expect: ")


# --- study files ------------------------------------------------------------------

def test_grid_zip_samples_and_derived(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('''base = "goda"
[grid]
"contact.interface.friction" = [0.5, 0.8]
"mesh.goda.bolt_height" = [0.034, 0.1345]
[zip]
"loads.impact.duration" = [1e-3, 2e-3]
"loads.impact.peak" = [0.5, 0.25]
[samples]
count = 3
seed = 7
"bodies.mound.density" = {uniform = [1600, 2000]}
"bodies.mound.poisson" = {choice = [0.2, 0.3]}
[[derived]]
from = "mesh.goda.bolt_height"
key = "loads.impact.pendulum.cord_length"
table = [[0.034, 3.527], [0.101, 3.46], [0.168, 3.393]]
interpolate = true
''')
    study = load_study(path)
    # product: 2 (grid) x 2 (grid) x 2 (zip rows) x 3 (sample rows), last fastest
    assert len(study.points) == 24
    assert study.keys == ("contact.interface.friction", "mesh.goda.bolt_height",
                          "loads.impact.duration", "loads.impact.peak",
                          "bodies.mound.density", "bodies.mound.poisson",
                          "loads.impact.pendulum.cord_length")
    p = study.points
    assert p[0].values["contact.interface.friction"] == 0.5
    assert p[12].values["contact.interface.friction"] == 0.8
    assert (p[3].values["loads.impact.duration"], p[3].values["loads.impact.peak"]) \
        == (2e-3, 0.25)
    assert p[0].values["bodies.mound.density"] == p[3].values["bodies.mound.density"]
    assert all(1600 <= q.values["bodies.mound.density"] < 2000 for q in p)
    # samples are reproducible from the seed
    assert [q.values for q in load_study(path).points] == [q.values for q in p]
    points, cases = check_points(study, tmp_path / "out")
    cords = [q.values["loads.impact.pendulum.cord_length"] for q in points]
    assert cords[0] == 3.527  # a row of the table
    # 0.1345 is halfway between the rows 0.101 and 0.168: linear interpolation
    assert math.isclose(cords[6], (3.46 + 3.393) / 2, rel_tol=1e-12)
    assert cases[6].loads[0].pendulum.cord_length == cords[6]
    assert cases[6].mesh.goda.bolt_height == 0.1345
    assert cases[5].output_directory == tmp_path / "out" / points[5].folder
    assert points[5].folder.startswith("case-0005_friction=0.5_bolt_height=0.034_")


def test_toml_literal_round_trip():
    import tomllib

    for value in (0.1 + 0.2, 1e-300, -3, True, "a \"b\" \\ é", [1, 2.5], {"k": [0.5]}):
        assert tomllib.loads(f"v = {toml_literal(value)}")["v"] == value


def test_enough_bad_studies():
    assert len(BAD_FILES) >= 10


@pytest.mark.parametrize("path", BAD_FILES, ids=lambda p: p.stem)
def test_bad_study_message(path, tmp_path):
    with pytest.raises(CaseError) as info:
        check_points(load_study(path), tmp_path)
    message = str(info.value)
    assert expected(path) in message
    assert "\n" not in message
    # a line to read: at most SHOWN_ERRORS of the bad points' errors (18: 200 sampled
    # points, each its own error, made a line of 26 kB)
    assert len(message) < 2000, len(message)
    assert message.startswith(path.name)  # the study file is named first


@pytest.mark.parametrize("path", [BAD / "03_invalid_point.toml", BAD / "04_empty_study.toml"],
                         ids=lambda p: p.stem)
def test_bad_study_through_main(path, shared_dir, capsys):
    out = shared_dir / "out"
    assert cli.main(["sweep", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    if COMM.rank == 0:
        assert err.count("\n") == 1 and expected(path) in err and "Traceback" not in err
    assert not any(out.glob("case-*"))  # nothing ran


@pytest.mark.parametrize(("override", "message"), [
    # a bad value of every case: its line as run --set's, the study named after it
    ("bodies.mound.density=-1", "--set: bodies.mound.density: must be > 0 (got -1) (every "
     "case of study.toml)"),
    ("mesh.refinement=1e3", "--set: mesh.max_elements: refinement 1000 with the mesh.goda "
     "dimensions"),
    ("time.dtt=1", "--set time.dtt: unknown key 'time.dtt' (did you mean 'dt'?)"),
    # of one point: the point named, the value's source --set
    ("time.end_time=1.5e-4", "study.toml: 1 of 2 points make an invalid case: case-0001 "
     "(time.dt=0.0002): --set: time.dt: must be smaller than end_time (0.0002 >= 0.00015)"),
    ("time.dt=1e-4", "--set time.dt: the study varies it (a key is varied, derived or set "
     "only once)"),
    ("output.directory=x", "--set output.directory: is set by the sweep"),
])
def test_a_bad_set_value_is_named_as_sweep_set(override, message, shared_dir, capsys):
    """A bad value given by ``sweep --set`` was named as the study file's (``study.toml:
    ... case-0000 (...): bodies.mound.density: must be > 0``), or as the base case's."""
    path = study_file(shared_dir, '[grid]\n"time.dt" = [1e-4, 2e-4]\n')
    with pytest.raises(CaseError) as info:
        check_points(load_study(path, [override]), shared_dir / "out")
    assert str(info.value) == message or str(info.value).startswith(message), info.value
    assert "\n" not in str(info.value)
    # a study's own bad value is still the study's, the point named
    bad = study_file(shared_dir, '[grid]\n"time.dt" = [1e-4, -1.0]\n', name="bad.toml")
    with pytest.raises(CaseError, match=r"^bad\.toml: 1 of 2 points make an invalid case: "
                       r"case-0001 \(time\.dt=-1\.0\): time\.dt: must be > 0"):
        check_points(load_study(bad), shared_dir / "out")


def test_max_points_flag(shared_dir, capsys):
    """The limit on points is counted before any point is drawn; --max-points raises it."""
    big = BAD / "s1_five_million_samples.toml"
    start = time.perf_counter()
    with pytest.raises(CaseError, match="5e\\+06 points, above the limit of 1000"):
        load_study(big)
    assert time.perf_counter() - start < 1.0  # not 5 million draws
    path = study_file(shared_dir, '[grid]\n"contact.interface.friction" = [0.5, 0.6, 0.7]\n')
    assert cli.main(["sweep", str(path), "--out", str(shared_dir / "out"),
                     "--max-points", "2"]) == 2
    err = capsys.readouterr().err
    if COMM.rank == 0:
        assert err.count("\n") == 1 and "3 points, above the limit of 2" in err, err
        assert "--max-points N raises the limit" in err
    assert len(load_study(path, max_points=3).points) == 3


def test_paths_relative_to_the_study_file(shared_dir, monkeypatch):
    """A mesh named in a study ([set] or [grid]) is found beside the study file, not in
    the working directory (before: 'mesh file not found' from any other folder)."""
    sub = shared_dir / "studies"
    if COMM.rank == 0:
        sub.mkdir()
    COMM.barrier()
    assert cli.main(["mesh", "--out", str(sub / "goda.msh"), "--quiet"]) == 0
    body = '"mesh.source" = "goda.msh"\n[grid]\n"time.dt" = [1e-4, 5e-5]\n'  # in [set]
    fixed = study_file(sub, body, name="fixed.toml")
    varied = study_file(sub, '[grid]\n"mesh.source" = ["goda.msh", "goda"]\n',
                        name="varied.toml")
    monkeypatch.chdir(shared_dir)  # another folder than the study's
    mesh = str((sub / "goda.msh").resolve())
    _, cases = check_points(load_study(fixed), shared_dir / "out")
    assert [c.mesh.source for c in cases] == [mesh, mesh]
    points, cases = check_points(load_study(varied), shared_dir / "out")
    assert [c.mesh.source for c in cases] == [mesh, "goda"]
    assert points[0].values["mesh.source"] == "goda.msh"  # the table shows what was given


def test_examples_are_valid(tmp_path):
    bolts = load_study(EXAMPLES / "bolt_heights.toml")
    points, cases = check_points(bolts, tmp_path)
    assert len(points) == 9
    for p, c in zip(points, cases, strict=True):  # the cord follows the bolt (Goda 1994)
        cord = {0.034: 3.527, 0.101: 3.46, 0.168: 3.393}[c.mesh.goda.bolt_height]
        assert c.loads[0].pendulum.cord_length == cord == \
            p.values["loads.impact.pendulum.cord_length"]
    calibration = load_study(EXAMPLES / "paper_calibration.toml")
    assert len(check_points(calibration, tmp_path)[0]) == 48


def test_ranks_per_case_must_divide(shared_dir, capsys):
    path = study_file(shared_dir, '[grid]\n"contact.interface.friction" = [0.5]\n')
    assert cli.main(["sweep", str(path), "--ranks-per-case", str(COMM.size + 1)]) == 2
    if COMM.rank == 0:
        assert "--ranks-per-case" in capsys.readouterr().err
    for k in ("0", "-1"):  # (they said "must divide the number of ranks")
        assert cli.main(["sweep", str(path), "--ranks-per-case", k]) == 2
        if COMM.rank == 0:
            assert capsys.readouterr().err == f"breakwater: error: --ranks-per-case {k}: " \
                f"must be >= 1 (and divide the number of ranks, {COMM.size})\n"


def test_study_arguments_from_python_are_refused_in_one_line(shared_dir):
    """A notebook's calls, each refused in one line before the study's folder is made.

    ``run_study("study.toml")`` failed with ``AttributeError: 'str' object has no
    attribute 'points'``, ``load_study(path, "time.end_time=0.05")`` read the string
    character by character (``--set t: expected key=value``), ``load_study(path, None)``
    and ``load_case({...})`` with TypeErrors of ``list`` and ``pathlib``. Every rank
    refuses alike (the same arguments): no rank is left waiting.
    """
    path = study_file(shared_dir, '[grid]\n"contact.interface.friction" = [0.5]\n')
    study = load_study(path, None)  # None: no overrides, as load_case
    assert load_study(path, ("time.end_time=0.002",)).fixed["time.end_time"] == "0.002"
    out = shared_dir / "never"
    for call, message in (
            (lambda: run_study(str(path), out),  # type: ignore[arg-type]
             r"^run_study: study: expected a Study, got a path: read it first, "
             rf"run_study\(load_study\('{re.escape(str(path))}'\), \.\.\.\)$"),
            (lambda: run_study({"base": "goda"}, out),  # type: ignore[arg-type]
             r"^run_study: study: expected a Study \(run_study\(load_study\('study\.toml'\), "
             r"\.\.\.\)\), got dict "),
            (lambda: run_study(study, out, ranks_per_case="1"),  # type: ignore[arg-type]
             r"^run_study: ranks_per_case: expected an integer, got str '1'$"),
            (lambda: run_study(study, out, comm="world"),  # type: ignore[arg-type]
             r"^run_study: comm: expected an MPI communicator .*, got str 'world'$"),
            (lambda: run_study(study, 5),  # type: ignore[arg-type]
             r"^run_study: out: expected a folder as a str or a pathlib\.Path .*got int 5$")):
        with pytest.raises(TypeError, match=message):
            call()
    for call, message in (
            (lambda: load_study(path, "time.end_time=0.002"),  # type: ignore[arg-type]
             r"^overrides: expected a list of 'key=value' strings \(e\.g\. load_study\("
             r"'study\.toml', \['time\.end_time=0\.05'\]\)\), got str "
             r"'time\.end_time=0\.002'$"),
            (lambda: load_study({"base": "goda"}),  # type: ignore[arg-type]
             r"^path: expected a study file as a str or a pathlib\.Path, got dict "),
            (lambda: load_case({"name": "x"}),  # type: ignore[arg-type]
             r"^path: expected a case file \(or a built-in case's name, 'goda'\) as a str "
             r"or a pathlib\.Path, got dict ")):
        with pytest.raises(CaseError, match=message):
            call()
    assert not out.exists()


@pytest.mark.timeout(120)
def test_a_case_that_one_rank_cannot_read_stops_every_rank(shared_dir, monkeypatch):
    """Rank 0 checks the points, then every rank reads the cases itself: a rank that
    met an error alone (a file changed since) raised while the others went on into the
    fingerprints' broadcast and waited there (the time limit, 120 s here, stopped the
    suite). Every rank now raises it."""
    from breakwater.studies import sweep

    path = study_file(shared_dir, '[grid]\n"contact.interface.friction" = [0.5]\n')
    calls = []

    def changed(study, folder):
        calls.append(1)
        if len(calls) == (2 if COMM.rank == 0 else 1):  # each rank's own reading (rank
            raise CaseError("mesh.source: injected")  # 0's after its check of every point)
        return check_points(study, folder)

    if COMM.rank == COMM.size - 1:
        monkeypatch.setattr(sweep, "check_points", changed)
    with pytest.raises(CaseError, match="injected"):
        run_study(load_study(path), shared_dir / "out", quiet=True)


# --- running studies ---------------------------------------------------------------

NUMBERS_EXCLUDED = ("wall_time", "loop_time", "newton_iterations")  # clocks; counts apart
DISPLACEMENTS = ("peak_ux", "residual_ux", "residual_slip", "max_uplift")


def numbers(rows: list[dict[str, str]]) -> dict[str, list[float]]:
    """The numeric columns of a table (the clocks left out)."""
    out: dict[str, list[float]] = {}
    for column in rows[0]:
        if column in NUMBERS_EXCLUDED:
            continue
        try:
            out[column] = [float(r[column]) for r in rows]
        except ValueError:
            continue
    return out


def column_of(rows: list[dict[str, str]], name: str) -> list[float]:
    return [float(r[name]) for r in rows]


def test_groups_give_the_same_table(shared_dir):
    """2 groups of 1 rank and 1 group of 2 ranks: the same numbers.

    Each case's headline numbers come from its history; the fast solver's histories on
    1 and 2 ranks agree to 5e-11 of their scale, its displacements to 1.3e-10 (README,
    test_fastpath), so 1e-9 of a column's largest value is a margin of 7 or more. The
    displacements (peaks, residuals, slip, uplift) share one scale, the largest of
    them: the slip is a difference of the two sides' displacements, which carries their
    round-off (measured: 5e-14 m on a 5e-6 m slip, 1e-10 of the 5e-4 m peak). Likewise
    the energy balance error is a sum of the ledger's terms, on the scale of the
    external work (measured: 6e-11 J/m against 0.05 J/m of work). Newton iteration
    totals are compared apart: an iterate whose residual lands at the tolerance may
    pass on one partition and not on the other (measured: 147 against 146 iterations in
    30 steps; README: a Newton count may differ by one across ranks); allowed: 2.
    """
    path = study_file(shared_dir, '''[grid]
"contact.interface.friction" = [0.5, 0.8]
"loads.impact.duration" = [1e-3, 2e-3]
''')
    study = load_study(path)
    tables = {}
    for k in sorted({1, COMM.size}):
        out = shared_dir / f"groups{k}"
        outcome = run_study(study, out, ranks_per_case=k, quiet=True)
        assert outcome.complete and outcome.finished == 4 and outcome.skipped == 0
        tables[k] = read_table(out / TABLE)
        assert [r["status"] for r in tables[k]] == ["finished"] * 4
        assert [float(r["contact.interface.friction"]) for r in tables[k]] == \
            [0.5, 0.5, 0.8, 0.8]
        assert all(float(r["steps"]) == 30 for r in tables[k])
        # the cases' warnings are the study's too (they were dropped): the Goda case's
        # penalty is too soft for its static settlement (docs/outputs.md)
        assert all(r["warnings"].startswith("contact 'interface': penalty") and
                   "is too soft" in r["warnings"] for r in tables[k]), tables[k]
    # every column is one that a study's [figures] may name (headline_columns in step
    # with headline: a column it missed would refuse a valid study)
    known = {*study.keys, *TABLE_COLUMNS,
             *headline_columns(check_points(study, shared_dir)[1][0].resolved())}
    assert set(tables[1][0]) <= known, set(tables[1][0]) - known
    a, b = numbers(tables[1]), numbers(tables[COMM.size])
    assert a.keys() == b.keys() and "residual_slip" in a and "peak_ux.gauge_top" in a
    lengths = [c for c in a if c.split(".")[0] in DISPLACEMENTS]
    length_scale = max(abs(v) for c in lengths for v in a[c])
    for column, values in a.items():
        scale = length_scale if column in lengths else max(abs(v) for v in values) or 1.0
        if column == "energy_balance_error":
            scale = max(abs(v) for v in a["external_work"])
        for x, y in zip(values, b[column], strict=True):
            assert abs(x - y) <= 1e-9 * scale, (column, x, y)
    for x, y in zip(*(column_of(t, "newton_iterations") for t in (tables[1], tables[COMM.size])),
                    strict=True):
        assert abs(x - y) <= 2
    # the pulse matters: a shorter pulse of the same impulse gives a larger peak at 3 ms
    assert a["peak_ux.gauge_top"][0] > a["peak_ux.gauge_top"][1] > 0
    # the figures: one per varied key
    figures = sorted(p.name for p in (shared_dir / "groups1" / "figures").glob("*.png"))
    assert figures == ["vs_contact_interface_friction.png", "vs_loads_impact_duration.png"]
    # a rerun skips every finished case: no record is rewritten
    out = shared_dir / "groups1"
    records = sorted(out.glob(f"case-*/{RECORD}"))
    stamps = [p.stat().st_mtime_ns for p in records]
    outcome = run_study(study, out, quiet=True)
    assert outcome.complete and outcome.skipped == 4
    assert [p.stat().st_mtime_ns for p in records] == stamps


def test_failing_point(shared_dir, capsys):
    """A case whose steps cannot converge (one Newton iteration, no cut-back) fails; the
    study records its one-line error, runs the others and exits 1."""
    path = study_file(shared_dir, '''"time.max_cutbacks" = 0
[grid]
"time.newton_max_it" = [40, 1]
''')
    out = shared_dir / "failing"
    assert cli.main(["sweep", str(path), "--out", str(out)]) == 1
    rows = read_table(out / TABLE)
    assert [r["status"] for r in rows] == ["finished", "failed"]
    assert rows[0]["error"] == ""
    # the failed case's row gives what it did, not the partial run's peaks and residuals
    # (its first step failed: they were the static state's)
    assert rows[0]["residual_slip"] != "" and rows[0]["peak_ux.gauge_top"] != ""
    assert rows[1]["residual_slip"] == rows[1]["peak_ux.gauge_top"] == ""
    assert rows[1]["residual_ux.gauge_top"] == rows[1]["external_work"] == ""
    assert rows[1]["steps"] != "" and rows[1]["static_mean_pressure"] != ""
    assert "did not converge" in rows[1]["error"] and "\n" not in rows[1]["error"]
    printed = capsys.readouterr().out
    if COMM.rank == 0:
        assert "1/2 finished, 1 failed" in printed
    # the failed case is run again on a rerun (and fails again); the finished one is not
    finished = out / rows[0]["folder"] / RECORD
    stamp = finished.stat().st_mtime_ns
    assert cli.main(["sweep", str(path), "--out", str(out), "-q"]) == 1
    again = read_table(out / TABLE)
    assert [r["status"] for r in again] == ["finished", "failed"]
    assert again[1]["error"] == rows[1]["error"]
    assert finished.stat().st_mtime_ns == stamp


class _Killed(Exception):
    """Stands for a kill of the study (not an error the study records)."""


def test_a_case_killed_before_its_record_is_recorded_not_rerun(shared_dir, monkeypatch):
    """A study killed after a case's run wrote its summary ("finished") and before the
    case's record: the rerun ran the whole case again (its record said ``running``). It
    now records the case from its summary, unless an output the summary names is gone.
    (One group of every rank: the kill is raised on every rank.)"""
    from breakwater.common import files

    path = study_file(shared_dir, '[grid]\n"contact.interface.friction" = [0.5]\n')
    out = shared_dir / "out"
    write_json = files.atomic_write_json

    def killed(target, data):
        if pathlib.Path(target).name == RECORD and data.get("status") != "running":
            raise _Killed("killed before the record")
        return write_json(target, data)

    with monkeypatch.context() as mp:
        mp.setattr(files, "atomic_write_json", killed)
        with pytest.raises(_Killed):
            run_study(load_study(path), out, quiet=True, ranks_per_case=COMM.size)
    (case,) = out.glob("case-*/")
    summary = json.loads((case / "summary.json").read_text())
    assert summary["status"] == "finished"
    assert json.loads((case / RECORD).read_text())["status"] == "running"
    stamp = (case / "summary.json").stat().st_mtime_ns
    COMM.barrier()  # (every rank has read the folder before the rerun writes in it)

    outcome = run_study(load_study(path), out, quiet=True, ranks_per_case=COMM.size)
    assert outcome.complete and outcome.skipped == 1  # not run again:
    assert (case / "summary.json").stat().st_mtime_ns == stamp
    record = json.loads((case / RECORD).read_text())
    assert record["status"] == "finished" and record["wall_time"] == \
        summary["solver"]["wall_time"]
    (row,) = read_table(out / TABLE)
    assert row["status"] == "finished"
    assert float(row["steps"]) == summary["solver"]["steps"]
    assert float(row["time_reached"]) == summary["time"]["reached"]

    # The same kill, but an output the summary names is gone: the case runs again.
    COMM.barrier()  # (every rank has read the folder before rank 0 changes it)
    if COMM.rank == 0:
        (case / RECORD).write_text(json.dumps({**record, "status": "running"}))
        (case / "snapshot_max_ux.npz").unlink()
    COMM.barrier()
    outcome = run_study(load_study(path), out, quiet=True, ranks_per_case=COMM.size)
    assert outcome.complete and outcome.skipped == 0
    assert (case / "summary.json").stat().st_mtime_ns != stamp
    assert (case / "snapshot_max_ux.npz").is_file()


def test_a_study_interrupted_from_python_says_so_and_goes_on(shared_dir, monkeypatch):
    """A KeyboardInterrupt in a case's run (a second interrupt in a notebook) came out of
    ``run_study`` with the case's record left ``running`` and ``sweep.csv`` saying
    ``pending``. Both now say ``interrupted`` before it goes on; the study run again in
    the same process resumes the case and gives the table of an uninterrupted study.
    (One group of every rank: the interrupt is raised on every rank.)"""
    from breakwater.stepping.gn22 import GN22

    path = study_file(shared_dir, '"output.checkpoint_interval" = 1\n'
                      '[grid]\n"contact.interface.friction" = [0.5, 0.6]\n')
    out = shared_dir / "out"
    solve, steps = GN22.solve, []

    def interrupted(self: GN22) -> int:
        steps.append(1)
        if len(steps) == 10:
            raise KeyboardInterrupt
        return solve(self)

    with monkeypatch.context() as mp:
        mp.setattr(GN22, "solve", interrupted)
        with pytest.raises(KeyboardInterrupt):
            run_study(load_study(path), out, quiet=True, ranks_per_case=COMM.size)
    rows = read_table(out / TABLE)
    assert [r["status"] for r in rows] == ["interrupted", "pending"]
    (case,) = out.glob("case-0000*/")
    record = json.loads((case / RECORD).read_text())
    assert record["status"] == "interrupted" and "KeyboardInterrupt" in record["error"]
    assert json.loads((case / "summary.json").read_text())["status"] == "interrupted"
    COMM.barrier()

    outcome = run_study(load_study(path), out, quiet=True, ranks_per_case=COMM.size)
    assert outcome.complete and outcome.finished == 2
    again = shared_dir / "again"
    run_study(load_study(path), again, quiet=True, ranks_per_case=COMM.size)
    # Bit for bit on one rank. On two, MUMPS's distributed solves round off in an order
    # of their own: the resumed case's peak differed from the uninterrupted one's in the
    # 12th digit on a loaded machine (2026-11-28; equal in other runs): 1e-9 relative.
    for a, b in zip(read_table(out / TABLE), read_table(again / TABLE), strict=True):
        for key in ("status", "steps", "time_reached"):
            assert a[key] == b[key], key
        for key in ("peak_ux.gauge_top", "residual_slip"):
            if COMM.size == 1:
                assert a[key] == b[key], key
            else:
                assert float(a[key]) == pytest.approx(float(b[key]), rel=1e-9), key


# --- killed studies (a real process) ------------------------------------------------------

def _sweep(path: pathlib.Path, out: pathlib.Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "breakwater", "sweep", str(path),
                             "--out", str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "OMP_NUM_THREADS": "1"})


def _wait_for_finished(out: pathlib.Path, count: int, process: subprocess.Popen,
                       timeout: float = 120.0) -> None:
    start = time.monotonic()
    while time.monotonic() - start < timeout:
        done = [p for p in out.glob(f"case-*/{RECORD}")
                if json.loads(p.read_text()).get("status") == "finished"]
        if len(done) >= count:
            return
        assert process.poll() is None, process.communicate()
        time.sleep(0.05)
    raise TimeoutError


@pytest.mark.serial
@pytest.mark.parametrize("how", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
def test_resume_after_a_kill(tmp_path, how):
    """Kill a sweep after its first case, rerun: the finished case is not run again, a
    half-run case is never counted as finished, and every case finishes."""
    if COMM.size > 1:
        pytest.skip("subprocess sweeps run serially")
    path = study_file(tmp_path, '[grid]\n"contact.interface.friction" = [0.5, 0.6, 0.7, 0.8]\n',
                      end=0.01)
    out = tmp_path / "out"
    process = _sweep(path, out)
    _wait_for_finished(out, 1, process)
    process.send_signal(how)
    _, err = process.communicate(timeout=120)
    assert process.returncode == (-signal.SIGKILL if how == signal.SIGKILL else 1), err
    records = {p.parent.name: json.loads(p.read_text()) for p in out.glob(f"case-*/{RECORD}")}
    finished = {k for k, r in records.items() if r["status"] == "finished"}
    assert 1 <= len(finished) < 4
    for name, r in records.items():
        summary = out / name / "summary.json"
        if r["status"] != "finished":  # a half-run case is not finished in any way
            assert not summary.exists() or json.loads(summary.read_text())["status"] \
                != "finished" or how == signal.SIGKILL
    if how == signal.SIGTERM:
        statuses = [r["status"] for r in read_table(out / TABLE)]
        assert statuses.count("finished") == len(finished)
        assert "interrupted" in statuses or "pending" in statuses
    stamps = {k: (out / k / RECORD).stat().st_mtime_ns for k in finished}
    rerun = _sweep(path, out)
    printed, err = rerun.communicate(timeout=300)
    assert rerun.returncode == 0, err
    assert f"{len(finished)} finished before, {4 - len(finished)} to run" in printed
    assert {k: (out / k / RECORD).stat().st_mtime_ns for k in finished} == stamps
    rows = read_table(out / TABLE)
    assert [r["status"] for r in rows] == ["finished"] * 4


def _case_at_its_checkpoint(tmp_path: pathlib.Path, end: float
                            ) -> tuple[pathlib.Path, pathlib.Path, subprocess.Popen]:
    """A one-case study (checkpoints every 20 steps, to ``end``) run in a subprocess
    until its case has written a checkpoint and the summary that records it: the study
    file, its output folder and the running process.

    The summary is rewritten after the checkpoint file: a kill between the two (a poll
    that saw only ``checkpoint.npz``) left a summary without the checkpoint, and the
    rerun's wall time could not count the killed run's (the SIGKILL test failed 2 runs
    in 3 on a busy machine).
    """
    path = study_file(tmp_path, '"mesh.refinement" = 0.5\n"output.checkpoint_interval" = 20\n'
                      '[grid]\n"contact.interface.friction" = [0.5]\n', end=end)
    out = tmp_path / "out"
    process = _sweep(path, out)
    start = time.monotonic()
    while not _checkpoint_recorded(out):
        assert process.poll() is None and time.monotonic() - start < 120, \
            process.communicate()
        time.sleep(0.02)
    return path, out, process


def _checkpoint_recorded(out: pathlib.Path) -> bool:
    """Whether the case's summary.json records a checkpoint (written atomically)."""
    for summary in out.glob("case-*/summary.json"):
        try:
            if json.loads(summary.read_text()).get("checkpoint"):
                return True
        except (OSError, json.JSONDecodeError):  # between two writes
            pass
    return False


@pytest.mark.serial
def test_resumed_case_counts_its_wall_time(tmp_path):
    """A case interrupted (SIGTERM) and resumed from its checkpoint: its ``wall_time`` is
    that of both runs, as its ``loop_time`` (the summary's, summed over the runs).

    Before, the resumed run's own time only: measured 3.2 s against a loop time of
    4.5 s (the interrupted run had taken 1.9 s). The first run's time is in its
    record; the total must be at least that plus the loop time of the second run (the
    mesh and the static state come on top: bounded by 300 s).

    500 steps (end 0.05 s; was 0.2 s, 2000 steps, of which the resumed run did about
    1980 for the same assertions): the SIGTERM follows the first checkpoint (step 20)
    within a 20 ms poll, 480 steps before the run could end.
    """
    if COMM.size > 1:
        pytest.skip("subprocess sweeps run serially")
    path, out, process = _case_at_its_checkpoint(tmp_path, end=0.05)
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=120)
    assert process.returncode == 1, err
    (first,) = read_table(out / TABLE)
    assert first["status"] == "interrupted", first
    # the way on is to rerun the study (a sweep has no --resume: it said so)
    assert first["error"].endswith("(run the study again to go on)"), first["error"]
    assert "--resume" not in first["error"]
    # The first run as if it had lasted 1000 s (its record is what the rerun reads):
    # the total is then 1000 s plus the second run's, which holds the rest of the loop.
    record = out / first["folder"] / RECORD
    record.write_text(json.dumps({**json.loads(record.read_text()), "wall_time": 1000.0}))
    rerun = _sweep(path, out)
    _, err = rerun.communicate(timeout=300)
    assert rerun.returncode == 0, err
    (row,) = read_table(out / TABLE)
    summary = json.loads((out / row["folder"] / "summary.json").read_text())
    assert summary["resumed_from"] and row["status"] == "finished"
    second_loop = float(row["loop_time"]) - float(first["loop_time"])
    assert 1000.0 + second_loop <= float(row["wall_time"]) < 1300.0


@pytest.mark.serial
def test_a_case_killed_by_sigkill_reads_stopped_and_keeps_its_wall_time(tmp_path):
    """SIGKILL of a study in a case's time loop, after a checkpoint.

    Before: the case's record and ``summary.json`` said ``running`` for good (sweep.csv
    too, when read after the kill), and the rerun's ``wall_time`` counted the rerun
    only (the record of a killed case has none). Now both record the process: the
    table reads ``stopped``, and the rerun adds the killed run's wall time to its last
    checkpoint (its summary's): made 1000 s here, so the total is at least 1000 s plus
    the rerun's part of the loop (mesh and static state on top: below 1300 s).

    500 steps (end 0.05 s, as test_resumed_case_counts_its_wall_time; was 0.2 s, 2000
    steps, of which the rerun did about 1980 for the same assertions): the SIGKILL
    follows the first checkpoint (step 20) within a 20 ms poll, 480 steps before the run
    could end.
    """
    from breakwater.common import liveness
    from breakwater.studies.sweep import write_table

    if COMM.size > 1:
        pytest.skip("subprocess sweeps run serially")
    path, out, process = _case_at_its_checkpoint(tmp_path, end=0.05)
    process.send_signal(signal.SIGKILL)
    process.communicate(timeout=120)
    (folder,) = out.glob("case-*")
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["status"] == "running" and summary["process"]["pid"] == process.pid
    assert liveness.process_state(summary["process"]) == "gone"
    study = load_study(path)
    points, cases = check_points(study, out)
    fingerprints = [checkpoint.case_fingerprint(c.resolved()) for c in cases]
    write_table(out, points, study.keys, fingerprints)  # as any reader of the folder
    (row,) = read_table(out / TABLE)
    assert row["status"] == "stopped" and row["wall_time"] == "", row
    killed = summary["solver"]["wall_time"]
    (folder / "summary.json").write_text(json.dumps(
        {**summary, "solver": {**summary["solver"], "wall_time": 1000.0}}))
    rerun = _sweep(path, out)
    _, err = rerun.communicate(timeout=300)
    assert rerun.returncode == 0, err
    (row,) = read_table(out / TABLE)
    resumed = json.loads((folder / "summary.json").read_text())
    assert resumed["resumed_from"] and row["status"] == "finished"
    second_loop = float(row["loop_time"]) - killed  # (the checkpoint's wall time is
    assert 1000.0 + second_loop <= float(row["wall_time"]) < 1300.0  # at most `killed`)


@pytest.mark.serial
def test_killed_case_counts_its_wall_time(tmp_path):
    """A case killed (SIGKILL: its record still says ``running``, with no wall time) and
    resumed from its checkpoint: its ``wall_time`` counts the killed run's time up to
    the checkpoint (the checkpoint's ``wall_before``).

    Before, the resumed run's own time only: the killed runs' time was lost (measured:
    7.7 s for a case killed after 261 of its 300 steps, against 20 to 25 s for the
    cases that ran whole). The checkpoint is made to say 1000 s, so the total must be
    at least the summary's (``loop_time``: the runs' own, from the checkpoint's on).

    500 steps (end 0.05 s; was 0.2 s): as
    test_a_case_killed_by_sigkill_reads_stopped_and_keeps_its_wall_time.
    """
    if COMM.size > 1:
        pytest.skip("subprocess sweeps run serially")
    from breakwater.outputs import checkpoint as ckpt

    path, out, process = _case_at_its_checkpoint(tmp_path, end=0.05)
    process.kill()
    process.communicate(timeout=60)
    (case,) = out.glob("case-*/")
    assert json.loads((case / RECORD).read_text())["wall_time"] is None
    meta, arrays = ckpt.read(case / ckpt.CHECKPOINT)
    meta["state"]["wall_before"] = 1000.0
    ckpt.write(case / ckpt.CHECKPOINT, meta, arrays)
    rerun = _sweep(path, out)
    _, err = rerun.communicate(timeout=300)
    assert rerun.returncode == 0, err
    (row,) = read_table(out / TABLE)
    assert row["status"] == "finished"
    # The summary's wall time (loop_time) is the runs' own, from the checkpoint's 1000 s
    # on; the case's holds it, with the mesh and the static state on top.
    assert 1000.0 < float(row["loop_time"]) <= float(row["wall_time"]) < 1300.0


# --- the calibration's reading of K_x (the paper-calibration study) -----------------------

def test_stiffness_basis(shared_dir):
    """``calibration.stiffness_basis``: Goda's K_x = 500 kN/m divided by the 0.205 m block
    length (default) or taken per metre of plane strain; the calibration meets it."""
    from breakwater.casefile.case import load_case

    block = load_case()
    metre = load_case(None, ['calibration.stiffness_basis="metre"'])
    assert block.calibration.stiffness_basis == "block"
    assert block.calibration.per_metre(500e3, 0.205) == 500e3 / 0.205
    assert metre.calibration.per_metre(500e3, 0.205) == 500e3
    data = metre.read_mesh(COMM, shared_dir)
    result = metre.calibrate(data)
    assert result.target == 500e3
    assert abs(result.stiffness - 500e3) <= metre.calibration.tolerance * 500e3
    # the softer reading: G = 0.434 MPa at refinement 1 (README), against 2.28 MPa
    assert 0.40e6 < result.shear_modulus < 0.47e6


def test_a_stop_poll_does_not_wait_for_rank_0():
    # The shared counter lives on rank 0, and an atomic read of it completes only when
    # rank 0 makes MPI progress. A group's run polls it for a stop request once a
    # second: the poll must not wait (it did, and a group's case took four times as
    # long while rank 0 computed its own). Here rank 0 computes for 2 s without any
    # MPI call; every other rank's poll returns at once (bound 0.5 s, against the 2 s
    # a waiting read takes), and a stop posted by rank 0 reaches every rank's poll.
    from breakwater.studies.sweep import _Counter

    counter = _Counter(COMM)
    try:
        COMM.Barrier()
        if COMM.rank == 0:
            end = time.monotonic() + 2.0
            while time.monotonic() < end:  # busy, no MPI progress
                pass
            counter.stop(int(signal.SIGTERM))
        else:
            start = time.monotonic()
            assert counter.stopped() == 0
            assert time.monotonic() - start < 0.5
        COMM.Barrier()
        deadline = time.monotonic() + 30.0
        while counter.stopped() != int(signal.SIGTERM):
            assert time.monotonic() < deadline, "the stop never reached this rank"
            time.sleep(0.01)
        assert counter.next() >= counter.STOP_UNIT  # no case is taken any more
    finally:
        COMM.Barrier()
        counter.free()
