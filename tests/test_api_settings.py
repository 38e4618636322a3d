"""The settings dataclasses built or changed from Python are checked as a case file's values.

A notebook user builds :class:`~breakwater.config.runspec.TimeSpec`,
:class:`~breakwater.config.runspec.OutputSpec` and the probes, or changes a loaded case's
tables with :func:`dataclasses.replace`: the reader's type checks
(:mod:`breakwater.config.convert`) are skipped there; notebooks/04_storm.py builds a
:class:`~breakwater.storms.waves.Site` and a :class:`~breakwater.storms.rigid.Caisson`.
Found by a user-path test:
``adaptive="no"`` ran adaptive steps (a non-empty string is true), ``end_time="0.002"``
failed deep in the run with a TypeError. Pure Python (no mesh, no solve).
"""

from __future__ import annotations

import dataclasses
import pathlib
import re
import typing
from typing import Any, Literal

import pytest
from breakwater.meshes import GodaGeometry

from breakwater.casefile.case import CaseError, load_case
from breakwater.casefile.loads import ProfileCase
from breakwater.casefile.stormcase import SeaCase
from breakwater.config.fields import InvalidField, alternatives, optional, type_hints
from breakwater.config.runspec import InitialSpec, OutputSpec, PairProbeSpec, ProbeSpec, TimeSpec
from breakwater.storms.rigid import Caisson
from breakwater.storms.waves import Site

# Pure Python, no communicator: nothing here differs on 2 ranks (the 2-rank stage is for
# partition independence and the ranks' agreement).
pytestmark = pytest.mark.serial

ROOT = pathlib.Path(__file__).parents[1]
CASES = [ROOT / "breakwater/cases/goda.toml", ROOT / "examples/goda_design_wave.toml",
         ROOT / "examples/goda_storm.toml", ROOT / "examples/goda_nonmatching.toml"]


def _instances() -> dict[type, Any]:
    """One instance of every dataclass in the loaded cases' trees, plus the run specs."""
    found: dict[type, Any] = {}

    def walk(obj: Any) -> None:
        if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
            found.setdefault(type(obj), obj)
            for f in dataclasses.fields(obj):
                walk(getattr(obj, f.name))
        elif isinstance(obj, tuple):
            for item in obj:
                walk(item)

    for file in CASES:
        walk(load_case(file))
    walk(OutputSpec(pathlib.Path("out"), probes=(ProbeSpec("p", "caisson", (0.0, 0.1)),),
                    pair_probes=(PairProbeSpec("q", 0, (0.0, 0.0)),)))
    walk(InitialSpec(velocities=(("caisson", (1.0, 0.0)),), loads=(0,)))
    walk(SeaCase(significant_height=8.0, period=14.0, waves=100))
    walk(ProfileCase(points=((0.0, 1e3), (1.0, 0.0))))
    walk(Site(depth=20.0, toe_depth=14.5, berm_depth=11.0, crest_height=5.0,
              base_width=30.0))  # notebooks/04_storm.py's
    walk(Caisson(mass=2100.0 * 30.0 * 19.5, base_width=30.0, toe_depth=14.5, friction=0.6))
    return found


INSTANCES = _instances()
EXPECTED = {"Case", "MeshCase", "GodaGeometry", "Goda3DGeometry", "BodyCase", "ContactCase",
            "FixedCase", "InitialCase", "DampingCase", "CalibrationCase", "TimeSpec",
            "OutputCase", "ProbeCase", "LoadCase", "PendulumCase", "GodaCase", "StormCase",
            "SeaCase", "TableCase", "ProfileCase", "PairProbeCase", "OutputSpec", "ProbeSpec",
            "PairProbeSpec", "InitialSpec", "Site", "Caisson"}
VALUE_ERRORS = (GodaGeometry, Site, Caisson)  # their own checks raise ValueError


def _wrong(tp: Any) -> Any:
    """A value of another type than the annotation ``tp`` allows."""
    inner = optional(tp)
    if inner is not None:
        return _wrong(inner)
    if tp is bool:
        return "no"  # truthy: was taken as True
    if tp is float:
        return "0.002"  # was a TypeError deep in the run
    if tp is int:
        return 2.5
    if tp is str:
        return 3
    if typing.get_origin(tp) is Literal:
        return "none of them"
    if typing.get_origin(tp) is tuple:
        return 5.0
    if alternatives(tp):
        return b"bytes"  # neither member
    if tp is pathlib.Path:
        return 3
    return "a string"  # a dataclass: not one


def _cases() -> list[tuple[str, Any, str]]:
    out = []
    for cls, obj in INSTANCES.items():
        for f in dataclasses.fields(obj):
            if f.init:
                out.append((f"{cls.__name__}.{f.name}", obj, f.name))
    return out


def test_every_settings_class_is_covered() -> None:
    # A class missing here would have no field checked below.
    assert {c.__name__ for c in INSTANCES} >= EXPECTED


@pytest.mark.parametrize(("label", "obj", "name"), _cases(), ids=[c[0] for c in _cases()])
def test_a_wrong_type_is_refused_naming_the_field(label: str, obj: Any, name: str) -> None:
    bad = _wrong(type_hints(type(obj))[name])
    if isinstance(obj, VALUE_ERRORS):  # a ValueError naming the field
        with pytest.raises(ValueError, match=rf"^{name}\b"):
            dataclasses.replace(obj, **{name: bad})
        return
    with pytest.raises(InvalidField, match=rf"^{name}(\[\d+\])?: ") as e:
        dataclasses.replace(obj, **{name: bad})
    assert "\n" not in str(e.value)


def test_the_user_path_findings() -> None:
    time = TimeSpec(dt=1e-4, end_time=2e-3)
    with pytest.raises(InvalidField, match=r"^adaptive: expected true or false, got 'no'$"):
        dataclasses.replace(time, adaptive="no")
    with pytest.raises(InvalidField, match=r"^end_time: expected a number, got '0.002'$"):
        dataclasses.replace(time, end_time="0.002")
    with pytest.raises(InvalidField, match=r"^loading: must be one of .*did you mean "
                       r"'frictionless'"):  # a str field before: a typo ran frictionless
        InitialSpec(loading="frictionles")
    with pytest.raises(InvalidField, match=r"^tolerance: must be in \(0, 1\)"):
        InitialSpec(tolerance=2.0)
    with pytest.raises(InvalidField, match=r"^field_interval: must be >= 0"):
        OutputSpec(pathlib.Path("out"), field_interval=-1)


@pytest.mark.parametrize(("name", "why"), [
    ("a,b", "it holds ','"), ('say "x"', """it holds '"'"""), ("a\nb", "it holds '\\n'"),
    ("", "empty")])
def test_a_probe_name_that_breaks_the_history_is_refused(name: str, why: str) -> None:
    """A probe's name heads history.csv columns: a comma in it split the header (one column
    more than the rows: read_history failed with an IndexError), a quote or a line break
    broke the CSV, and an empty name gave ``caisson@(x, y)_ux``, a comma too."""
    for make in (lambda: ProbeSpec(name, "caisson", (0.0, 0.1)),
                 lambda: PairProbeSpec(name, 0, (0.0, 0.1))):
        with pytest.raises(InvalidField, match=r"^name: ") as e:
            make()
        assert "cannot name history.csv columns (" + why in str(e.value)
        assert "\n" not in str(e.value)
    ProbeSpec("gauge top-1 é", "caisson", (0.0, 0.1))  # spaces, letters of any script


def test_the_same_rule_as_the_reader() -> None:
    # The case file's message, the path prefixed: the one rule from both sides.
    with pytest.raises(CaseError, match=r"time\.adaptive: expected true or false, got 'no'$"):
        load_case("goda", ["time.adaptive='no'"])
    case = load_case("goda")
    with pytest.raises(InvalidField, match=r"^friction: expected a number, got '0.6'$"):
        dataclasses.replace(case.contact[0], friction="0.6")


def test_python_forms_of_the_same_value_are_stored_as_the_reader_stores_them() -> None:
    time = dataclasses.replace(TimeSpec(dt=1e-4, end_time=2e-3), end_time=1)
    assert type(time.end_time) is float and time.end_time == 1.0
    probe = ProbeSpec("p", "caisson", [0, 0.1])  # a list of an int and a float
    assert probe.point == (0.0, 0.1) and all(type(x) is float for x in probe.point)
    output = OutputSpec("out")  # type: ignore[arg-type]  (a str for a path)
    assert output.directory == pathlib.Path("out")


def test_load_case_overrides_not_a_list() -> None:
    """``load_case``'s overrides from a script: a list or a tuple of strings, or None.

    A single string was read character by character (``--set t: expected key=value``),
    a dict by its keys, and None failed with ``'NoneType' object is not iterable``.
    """
    assert load_case("goda", None) == load_case("goda")
    assert load_case("goda", ("time.end_time=0.05",)).time.end_time == 0.05
    assert load_case("goda", (o for o in ["time.end_time=0.05"])).time.end_time == 0.05
    expected = (r"^overrides: expected a list of 'key=value' strings \(e\.g\. load_case\(None, "
                r"\['time\.end_time=0\.05', 'contact\.interface\.friction=0\.5'\]\)\), got ")
    for overrides, got in (("time.end_time=0.05", "str 'time.end_time=0.05'"),
                           ({"time.end_time": 0.05}, "a dict"),
                           (0.05, "float 0.05"),
                           ([b"time.end_time=0.05"], "an item bytes b'time.end_time=0.05'"),
                           ([pathlib.Path("x")], "an item PosixPath PosixPath('x')")):
        with pytest.raises(CaseError, match=expected + re.escape(got) + "$"):
            load_case("goda", overrides)  # type: ignore[arg-type]


@pytest.mark.parametrize("where", ["bodies", "contact", "fixed", "loads", "output.probes",
                                   "output.pair_probes"])
def test_an_entry_given_twice_from_python_is_refused(where: str) -> None:
    """A case file's entries are its tables' keys; ``dataclasses.replace`` could give one
    twice: ``contact=(c, c)`` ran with the pair twice (the Goda case's peak sway at
    t = 2 ms 2.158e-4 m instead of 2.204e-4 m), ``loads=(ld, ld)`` with twice the impulse,
    each silently; the summary kept one entry of the name."""
    case = load_case("goda")

    def with_entries(entries: tuple[Any, ...]) -> Any:
        if where.startswith("output."):
            output = dataclasses.replace(case.output, **{where.split(".")[1]: entries})
            return dataclasses.replace(case, output=output)
        return dataclasses.replace(case, **{where: entries})

    entries = getattr(case.output if where.startswith("output.") else case,
                      where.split(".")[-1])
    last = entries[-1]
    with pytest.raises(InvalidField, match=rf"^{re.escape(where)}\.{last.name}: given twice "
                       r"\(each entry of .* once") as e:
        with_entries((*entries, last))
    assert "\n" not in str(e.value)
    # The entry replaced (the message's advice) is taken.
    with_entries(tuple(dataclasses.replace(x) if x.name == last.name else x for x in entries))
