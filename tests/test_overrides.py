"""``--set`` overrides: a table value merges into the case's table, new entries, spellings.

Reference values are the built-in Goda case's own (``breakwater/cases/goda.toml``, read
here with :mod:`tomllib`) and the schema's defaults (the dataclasses'), so each test
fails if a table override replaced the case's table (the case's keys set back to their
defaults) instead of merging into it.
"""

from __future__ import annotations

import dataclasses
import pathlib
import re
import tomllib

import pytest

from breakwater.casefile.case import BUILTIN_CASES, CaseError, load_case
from breakwater.casefile.tables import DampingCase
from breakwater.studies.studyfile import check_points, load_study

GODA = tomllib.loads((BUILTIN_CASES / "goda.toml").read_text(encoding="utf-8"))


def test_a_table_value_merges_into_the_case_table():
    """``damping={alpha=0.1}`` changes alpha only: beta stays the case's 0.023.

    Before, the table replaced the case's: beta fell back to its default 0 (Rayleigh
    damping without its stiffness part, silently).
    """
    beta = GODA["damping"]["beta"]
    assert beta != DampingCase().beta  # else the test could not tell merge from replace
    case = load_case(None, ["damping={alpha=0.1}"])
    assert (case.damping.alpha, case.damping.beta) == (0.1, beta)
    # Nested tables and named collections merge too (before: "missing required key").
    case = load_case(None, ["contact={interface={friction=0.3}}",
                            "loads.impact={pendulum={mass=6.0}}"])
    pair, load = case.contact[0], case.loads[0]
    assert (pair.friction, pair.penalty, pair.slave) == \
        (0.3, GODA["contact"]["interface"]["penalty"], "caisson")
    assert (load.pendulum.mass, load.pendulum.cord_length, load.duration) == \
        (6.0, GODA["loads"]["impact"]["pendulum"]["cord_length"],
         GODA["loads"]["impact"]["duration"])


def test_a_table_value_is_the_same_as_its_dotted_keys():
    tables = load_case(None, ["time={dt=5e-5, end_time=0.01}", "calibration={tolerance=1e-3}"])
    dotted = load_case(None, ["time.dt=5e-5", "time.end_time=0.01",
                              "calibration.tolerance=1e-3"])
    assert tables.resolved() == dotted.resolved()


def test_a_merge_that_conflicts_is_refused_naming_the_merge():
    """An impulse merged into a pendulum load: both, refused in one line saying why."""
    with pytest.raises(CaseError) as info:
        load_case(None, ['loads.impact={group="impact", impulse=2.81, duration=1e-3}'])
    message = str(info.value)
    assert "give either impulse or a [pendulum] table" in message and "\n" not in message
    assert "merged a table into the case's loads.impact, whose other keys stay: --set " \
        "'loads.impact={}' first empties it" in message


def test_an_empty_table_empties_the_case_table():
    """``{}`` empties (a merge of nothing would leave the case's table, silently), and
    then a table replaces the case's: the load becomes an impulse, the defaults back."""
    case = load_case(None, ["output.probes={}", "damping={}", "damping.alpha=0.1"])
    assert case.output.probes == () and case.damping == DampingCase(alpha=0.1)
    case = load_case(None, ["loads.impact={}",
                            'loads.impact={group="impact", impulse=2.81, duration=1e-3}'])
    (load,) = case.loads
    assert load.pendulum is None and load.total_impulse == 2.81 and load.duration == 1e-3
    # the table alone, as a new load would be (nothing of the pendulum load left)
    new = load_case(None, ["loads.impact.enabled=false",
                           'loads.pulse={group="impact", impulse=2.81, duration=1e-3}'])
    assert load == dataclasses.replace(new.loads[1], name="impact")


def test_a_load_changed_to_an_impulse_by_a_new_entry():
    """The documented way to replace a load: disable it and add another."""
    case = load_case(None, ["loads.impact.enabled=false",
                            'loads.pulse={group="impact", impulse=2.81, duration=1e-3}'])
    old, new = case.loads
    assert not old.enabled and old.pendulum is not None
    assert new.enabled and new.pendulum is None and new.total_impulse == 2.81


def test_a_new_named_entry():
    """A support added from the command line: given whole it is made; a dotted key into
    an entry the case does not have is refused in one line saying how."""
    case = load_case(None, ["fixed.caisson_rear={components=[0]}"])
    assert [(f.name, f.components) for f in case.fixed] == \
        [("base", tuple(GODA["fixed"]["base"]["components"])), ("caisson_rear", (0,))]
    with pytest.raises(CaseError) as info:
        load_case(None, ["fixed.caisson_rear.components=[0]"])
    message = str(info.value)
    assert "no entry 'caisson_rear' in fixed" in message and "\n" not in message
    assert "a new entry is given whole: --set 'fixed.caisson_rear={key = value, ...}'" \
        in message


def test_quoted_parts_of_a_key_name_entries_as_toml_does(tmp_path: pathlib.Path) -> None:
    """An entry whose name holds a space or a dot (a TOML quoted key in the case file) is
    addressed by quoting that part, as TOML writes it; before, the quotes were part of
    the name and the entry was not found (a quoted key with '=' split at its '=')."""
    case_file = tmp_path / "quoted.toml"
    case_file.write_text('extends = "goda"\n[output.probes."top gauge"]\nbody = "caisson"\n'
                         'group = "gauge_top"\n')
    case = load_case(case_file, ['output.probes."top gauge".group=gauge_bottom',
                                 'time."dt"=2e-4',
                                 "output.probes.'v1.2=x'={body=\"caisson\", "
                                 'group="gauge_top"}',
                                 'output.probes."a\\u0041=b"={body="caisson", '
                                 'group="gauge_top"}'])
    probes = {p.name: p for p in case.output.probes}
    assert probes["top gauge"].group == "gauge_bottom"
    assert probes["v1.2=x"].group == "gauge_top"
    assert probes["aA=b"].group == "gauge_top"
    assert case.time.dt == 2e-4
    with pytest.raises(CaseError, match="did you mean 'group'"):
        load_case(case_file, ['output.probes."top gauge".grup=gauge_bottom'])
    # An escaped quote in a quoted part is TOML's: the name is read, and refused for
    # what it is (before: "expected key=value", the quote taken for the part's end).
    with pytest.raises(CaseError, match=re.escape(
            "output.probes.a\"b.name: 'a\"b' cannot name history.csv columns")):
        load_case(case_file, ['output.probes."a\\"b"={body="caisson", group="gauge_top"}'])


def test_a_path_in_a_table_value_is_relative_to_the_working_directory(tmp_path,
                                                                       monkeypatch):
    """``mesh={source="m.msh"}`` as ``mesh.source=m.msh`` (before: left relative)."""
    from breakwater.meshes import generate
    from mpi4py import MPI

    generate(tmp_path / "m.msh", comm=MPI.COMM_SELF)
    monkeypatch.chdir(tmp_path)
    case = load_case(None, ['mesh={source="m.msh"}'])
    assert case.mesh.source == str((tmp_path / "m.msh").resolve())


@pytest.mark.parametrize(("override", "phrase"), [
    ('time.dt="1e-4"', "expected a number, got '1e-4' (write 1e-4, unquoted)"),
    ("time.dt=.5e-4", "expected a number, got '.5e-4' (write 5e-05, unquoted)"),
    ("output.figures=True", "expected true or false, got 'True' (write true: lowercase, "
                            "unquoted)"),
    ("output.figures=1", "expected true or false, got 1 (write true)"),
    ("time.max_steps=1e6", "expected an integer, got 1000000.0 (write 1000000: an "
                           "integer has no point or exponent)"),
    ('time.max_steps="2000"', "expected an integer, got '2000' (write 2000, unquoted)"),
    ("name=1e3", "expected a string, got 1000.0 (quote it to give text)"),
    ("time.dt=true", "expected a number, got true"),
])
def test_spreadsheet_spellings_are_refused_saying_how_to_write_them(override, phrase):
    with pytest.raises(CaseError) as info:
        load_case(None, [override])
    assert phrase in str(info.value) and "\n" not in str(info.value)


def test_a_study_adds_a_named_entry_and_merges_tables(tmp_path):
    """A study's ``[set]`` as ``--set``: a new support, a merged table, a table's path
    relative to the study file. Before, ``[set]`` was flattened to dotted keys, which
    cannot make an entry ("no entry 'caisson_rear' in fixed")."""
    from breakwater.meshes import generate
    from mpi4py import MPI

    generate(tmp_path / "m.msh", comm=MPI.COMM_SELF)
    path = tmp_path / "s.toml"
    path.write_text('base = "goda"\n[set]\n"fixed.caisson_rear" = {components = [0]}\n'
                    'damping = {alpha = 0.1}\n[grid]\n"mesh" = [{source = "m.msh"}]\n')
    (point,), (case,) = check_points(load_study(path), tmp_path / "out")
    assert [f.name for f in case.fixed] == ["base", "caisson_rear"]
    assert (case.damping.alpha, case.damping.beta) == (0.1, GODA["damping"]["beta"])
    assert case.mesh.source == str((tmp_path / "m.msh").resolve())
    assert dataclasses.asdict(case.mesh)["refinement"] == GODA["mesh"]["refinement"]
    assert pathlib.Path(point.values["mesh"]["source"]).name == "m.msh"
