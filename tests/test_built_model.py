"""What a notebook may change on a built model, and what it is told when it may not.

A built :class:`~breakwater.model.model.ContactModel`'s bodies, pairs and loads are
built into its forms and solvers. Assigning a part's settings (``model.pairs[0].spec =
dataclasses.replace(spec, friction=0.1)``) or an item of its lists was taken without a
word and changed nothing: on the Goda case the run's numbers were those of μ = 0.65 to
the last digit, and ``case.toml`` said 0.65. Now refused in one line saying what to do.
The gravity may be set as a vector (before, the assignment replaced the forms'
constant, and the run failed on it with a traceback).
"""

from __future__ import annotations

import dataclasses
import pathlib
import re

import numpy as np
import pytest
from blocks import two_rectangles
from mpi4py import MPI

from breakwater.casefile.case import load_case
from breakwater.common.errors import CaseError, MeshError
from breakwater.config.runspec import InitialSpec, OutputSpec, TimeSpec
from breakwater.model.built import REBUILD
from breakwater.model.mesh import read_mesh
from breakwater.model.model import (
    Body,
    ContactModel,
    ContactPair,
    Damping,
    Fixed,
    Material,
    SurfaceLoad,
    SurfacePair,
)
from breakwater.run.asrun import RUN_ENTRIES, checked_arguments, checked_extra
from breakwater.run.simulation import run

COMM = MPI.COMM_WORLD


@pytest.fixture(scope="module")
def model(folder: pathlib.Path) -> ContactModel:
    path = two_rectangles(folder / "stacked.msh", COMM, (1.0, 0.5), (2.0, 0.5), 0.5)
    material = Material(2000.0, 0.2, young_modulus=1e8)
    return ContactModel(read_mesh(path, COMM), [Body("a", material), Body("b", material)],
                        [ContactPair("interface", "a", "b", penalty=1e10, friction=0.6,
                                     regularisation=1e-10)],
                        [Fixed("b_bottom")], [SurfaceLoad("a_left", (1.0, 0.0), lambda t: t)],
                        gravity=(0.0, -9.81))


def _refused(what: str) -> str:
    return f"^cannot change {re.escape(what)}: {re.escape(REBUILD)}$"


def test_parts_of_a_built_model_are_refused(model: ContactModel) -> None:
    pair, body, load = model.pairs[0], model.bodies[0], model.loads[0]
    spec = pair.spec
    attempts = {
        "model.pairs[k].spec": lambda: setattr(pair, "spec",
                                               dataclasses.replace(spec, friction=0.1)),
        "model.pairs[k].law": lambda: setattr(pair, "law", None),
        "model.bodies[k].spec": lambda: setattr(
            body, "spec", Body("a", Material(1000.0, 0.3, young_modulus=1e7))),
        "model.bodies[k].μ": lambda: setattr(body, "μ", None),
        "model.loads[k].spec": lambda: setattr(load, "spec", None),
        "model.pairs": lambda: model.pairs.__setitem__(0, pair),
    }
    for what, attempt in attempts.items():
        with pytest.raises(AttributeError, match=_refused(what)):
            attempt()
    for what, attempt in {"model.pairs": lambda: setattr(model, "pairs", []),
                          "model.bodies": lambda: model.bodies.append(body),
                          "model.surface_pairs": lambda: model.surface_pairs.extend([1]),
                          "model.loads": lambda: model.loads.pop()}.items():
        with pytest.raises(AttributeError, match=_refused(what)):
            attempt()
    # A frozen setting of the model says the same.
    with pytest.raises(dataclasses.FrozenInstanceError,
                       match=r"^cannot assign to field 'friction' of ContactPair: "
                             + re.escape(REBUILD) + "$"):
        spec.friction = 0.1  # type: ignore[misc]
    assert model.pairs[0] is pair and pair.spec is spec and spec.friction == 0.6
    assert len(model.bodies) == 2 and len(model.loads) == 1 and not model.surface_pairs
    # What the model changes itself stays changeable (a staged load's stage).
    load.stage = load.stage


def test_gravity_set_on_a_built_model(model: ContactModel) -> None:
    """``model.gravity = (gx, gy)`` sets the forms' constant (the one they were built on)."""
    constant = model.gravity
    try:
        model.gravity = (0.0, -2.0)  # type: ignore[assignment]
        assert model.gravity is constant
        assert constant.value.tolist() == [0.0, -2.0]
        for bad in ((0.0, -9.81, 0.0), (0.0, "a"), (0.0, np.nan)):
            with pytest.raises(ValueError, match=r"^gravity: expected 2 finite numbers "
                                                 r"\(m/s²\), got "):
                model.gravity = bad  # type: ignore[assignment]
        assert constant.value.tolist() == [0.0, -2.0]
    finally:
        model.gravity = (0.0, -9.81)  # type: ignore[assignment]


def test_a_misspelt_setting_of_a_built_model_is_refused(model: ContactModel) -> None:
    """An attribute the built model does not have is refused when set, in one line.

    Before, ``model.dampng = Damping(...)`` made a new attribute nothing read: the run
    went on with the old damping (α, β still 0), as ``model.gravty`` with the old gravity.
    """
    damping, gravity = model.damping, model.gravity.value.tolist()
    tail = ", so setting it would change nothing (model.damping, model.gravity and " \
           "model.initial may be set)"
    for name, value, closest in (("dampng", Damping(alpha=20.0), "damping"),
                                 ("gravty", (0.0, -1.0), "gravity"),
                                 ("intial", InitialSpec(undeformed=True), "initial")):
        with pytest.raises(AttributeError, match=re.escape(
                f"model.{name}: a built ContactModel has no attribute '{name}' (did you "
                f"mean '{closest}'?){tail}") + "$"):
            setattr(model, name, value)
        assert name not in vars(model)
    assert model.damping is damping and model.gravity.value.tolist() == gravity
    assert (float(model.α.value), float(model.β.value)) == (0.0, 0.0)
    # What it was built from is refused too (before: model.degree = 1 was taken and the
    # spaces stayed quadratic); its private attributes are set as before.
    for name, value in (("degree", 1), ("mesh", model.mesh), ("bcs", [])):
        before = getattr(model, name)
        with pytest.raises(AttributeError, match=re.escape(
                f"cannot change model.{name}: the built model's spaces, forms and "
                f"conditions were made from it; give ContactModel the new {name}") +
                ".*build it again"):
            setattr(model, name, value)
        assert getattr(model, name) is before
    model._solvers += 1
    model._scratch = 1
    del model._scratch


def test_two_pairs_of_one_name_are_refused(folder: pathlib.Path) -> None:
    """Two contact pairs of one name, built in Python, are refused in one line.

    The case file names each ``[contact.<name>]`` once (and a case from Python refuses
    a name given twice); the model took both: the interface's contact twice.
    """
    path = two_rectangles(folder / "stacked.msh", COMM, (1.0, 0.5), (2.0, 0.5), 0.5)
    material = Material(2000.0, 0.2, young_modulus=1e8)
    pair = ContactPair("interface", "a", "b", penalty=1e10, friction=0.6)
    general = SurfacePair("interface", "a", "b", "a_bottom", "b_top", penalty=1e10)
    message = ("contact 'interface': two pairs of this name (each pair once: a conforming "
               "pair is named by its interface group, a general pair by its name)")
    for pairs, surface_pairs in (([pair, dataclasses.replace(pair, friction=0.3)], []),
                                 ([pair], [general]), ([], [general, general])):
        with pytest.raises(CaseError, match=f"^{re.escape(message)}$"):
            ContactModel(read_mesh(path, COMM), [Body("a", material), Body("b", material)],
                         pairs, [Fixed("b_bottom")], surface_pairs=surface_pairs)


@pytest.mark.parametrize(("obj", "name", "hint"), [
    (TimeSpec(dt=1e-4, end_time=1e-3), "dt",
     "of TimeSpec: make another, dataclasses.replace(time, dt=...), and pass it to run"),
    (OutputSpec("out"), "field_interval",
     "of OutputSpec: make another, dataclasses.replace(output, field_interval=...), "
     "and pass it to run"),
    (Damping(1.0, 0.0), "alpha",
     "of Damping: model.damping = dataclasses.replace(model.damping, alpha=...)"),
    (Material(2000.0, 0.2, young_modulus=1e8), "density", "of Material: " + REBUILD),
])
def test_frozen_settings_say_what_to_do(obj: object, name: str, hint: str) -> None:
    with pytest.raises(dataclasses.FrozenInstanceError,
                       match=f"^cannot assign to field '{name}' {re.escape(hint)}$"):
        setattr(obj, name, 1.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        delattr(obj, name)


def test_damping_checks_its_fields_as_every_setting() -> None:
    """``Damping`` takes NumPy numbers and stores floats; the rest is refused in one line.

    Before, ``Damping(np.float32(1e-3))`` was refused ("must be a number >= 0 (got
    np.float32(0.001))"), ``Damping(np.float64(0.5))`` kept a NumPy number and
    ``Damping(1)`` an int, where the other settings (``check_fields``) store floats.
    """
    for given, stored in ((np.float32(0.5), 0.5), (np.float64(1e-3), 1e-3), (1, 1.0),
                          (np.int64(2), 2.0)):
        damping = Damping(alpha=given, beta=given)  # type: ignore[arg-type]
        assert type(damping.alpha) is float and damping.alpha == stored
        assert type(damping.beta) is float and damping.beta == stored
    for value, problem in ((True, ": expected a number, got true"),
                           ("0.1", ": expected a number, got '0.1'"),
                           (np.nan, ": must be finite (got nan)"),
                           (-1.0, " must be a number >= 0 (got -1.0)"),
                           (np.float32(-1.0), " must be a number >= 0 (got -1.0)")):
        with pytest.raises(ValueError, match=f"^damping beta{re.escape(problem)}$"):
            Damping(beta=value)  # type: ignore[arg-type]


def test_initial_set_on_a_built_model(model: ContactModel) -> None:
    """``model.initial`` is checked against the model when set, in one line.

    Before, an initial velocity of a body the model does not have (a misspelt name) was
    taken and ignored: the run started at rest; a load index beyond ``model.loads`` left
    every load out of the static state; a velocity of 3 components on a 2D model failed
    the run with NumPy's broadcast error.
    """
    kept = model.initial
    try:
        good = InitialSpec(velocities=(("a", (0.5, 0.0)),), loads=(0,))
        model.initial = good
        assert model.initial is good
        refused = {
            r"^initial\.velocities: no body named 'aa' \(did you mean 'a'\?\) "
            r"\(bodies: a, b\)$": InitialSpec(velocities=(("aa", (0.5, 0.0)),)),
            r"^initial\.velocities: body 'a' given twice$":
                InitialSpec(velocities=(("a", (0.5, 0.0)), ("a", (0.0, 0.1)))),
            r"^initial\.velocities: 'a': expected 2 components \(a 2D model\), got "
            r"\[0\.5, 0\.0, 0\.0\]$": InitialSpec(velocities=(("a", (0.5, 0.0, 0.0)),)),
            r"^initial\.loads: no load 1 in model\.loads \(indices 0 to 0\)$":
                InitialSpec(loads=(0, 1)),
            r"^initial\.loads: no load -1 in model\.loads": InitialSpec(loads=(-1,)),
        }
        for message, spec in refused.items():
            with pytest.raises(CaseError, match=message):
                model.initial = spec
            assert model.initial is good  # unchanged
        with pytest.raises(TypeError, match=r"^initial: expected an InitialSpec, got dict$"):
            model.initial = {"undeformed": True}  # type: ignore[assignment]
    finally:
        model.initial = kept


def test_run_arguments_of_another_type(model: ContactModel, folder: pathlib.Path) -> None:
    """``run``'s arguments are checked first, in one line naming the argument.

    ``resolved_case=built.case`` ("the case as run", Running: From Python) failed from
    inside the run with ``TypeError: 'Case' object is not iterable``; it is taken for its
    ``resolved()``. A dict for ``time`` failed with ``AttributeError: 'dict' object has
    no attribute 'dt'``.
    """
    time, out = TimeSpec(dt=1e-4, end_time=1e-3), folder / "never_written"
    output = OutputSpec(out)
    case = load_case("goda")
    assert checked_arguments(model, time, output, case) == case.resolved()
    assert checked_arguments(model, time, output, None) is None
    for args, message in (
            ((model, {"dt": 1e-4, "end_time": 1e-3}, output),
             "run: time: expected TimeSpec (built.time, or TimeSpec(dt=..., end_time=...)), "
             "got dict"),
            ((model, time, None), "run: output: expected OutputSpec (built.output, or "
                                  "OutputSpec(directory=...)), got NoneType"),
            ((None, time, output), "run: model: expected ContactModel (built.model), got "
                                   "NoneType")):
        with pytest.raises(TypeError, match=f"^{re.escape(message)}$"):
            run(*args, report=False)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"^run: resolved_case: expected a case's resolved\(\)"):
        run(model, time, output, resolved_case=["goda"], report=False)  # type: ignore[arg-type]
    assert not out.exists()  # refused before anything is written


def test_extra_summary_that_json_cannot_hold(model: ContactModel, folder: pathlib.Path) -> None:
    """A value of ``extra_summary`` that ``summary.json`` cannot hold is refused first.

    A set or an object failed at the first summary write with ``json``'s traceback
    (``TypeError: Object of type set is not JSON serializable``), once an earlier run's
    outputs in the folder had been cleared. NumPy numbers and arrays are written as
    numbers and lists (:func:`~breakwater.common.files.to_jsonable`): taken.
    """
    time, out = TimeSpec(dt=1e-4, end_time=1e-3), folder / "never_written_extra"
    output = OutputSpec(out)
    numbers = {"g": np.float32(0.5), "x": np.arange(3), "note": "trial", "n": None}
    assert checked_extra(numbers) is numbers and checked_extra(None) is None
    tail = "): give numbers, strings, bools, None, lists and dicts of them (NumPy numbers " \
           "and arrays are converted)"
    for extra, message in (
            ({"g": 1.0, "tags": {"a"}}, "run: extra_summary['tags']: summary.json cannot "
             "hold it (Object of type set is not JSON serializable" + tail),
            ({"model": {"m": model}}, "run: extra_summary['model']: summary.json cannot "
             "hold it (Object of type ContactModel is not JSON serializable" + tail),
            ([("g", 1.0)], "run: extra_summary: expected a mapping (e.g. {'note': "
             "'trial 3'}), got list")):
        with pytest.raises(TypeError, match=f"^{re.escape(message)}$"):
            run(model, time, output, extra_summary=extra, report=False)  # type: ignore[arg-type]
    assert not out.exists()  # refused before anything is written


def test_extra_summary_of_the_runs_own_entries(model: ContactModel,
                                               folder: pathlib.Path) -> None:
    """A key of ``extra_summary`` that the run writes itself is refused first.

    ``{"status": "bogus", "steps": -1}`` made ``summary.json`` say ``"status": "bogus"``
    for a finished run (what a study's rerun and ``--resume`` read); ``work`` and
    ``gravity`` given were overwritten by the run's, silently. The list of the run's own
    entries is checked against a run's summary: every entry but the build's (``mesh``,
    ``calibration``, ``loads``) and the one given is in it.
    """
    time = TimeSpec(dt=1e-4, end_time=3e-4)
    out = folder / "never_written_own"
    for key in RUN_ENTRIES:
        with pytest.raises(TypeError, match=rf"^run: extra_summary\['{key}'\]: summary\.json's "
                           r"own entry, which the run writes: give yours under another key"):
            run(model, time, OutputSpec(out), extra_summary={"note": 1, key: 2}, report=False)
    assert not out.exists()
    summary = run(model, time, OutputSpec(folder / "own_entries"), report=False,
                  extra_summary={"notes": {"status": "draft"}})
    assert summary["status"] == "finished" and summary["notes"] == {"status": "draft"}
    assert set(summary) - set(RUN_ENTRIES) <= {"mesh", "calibration", "loads", "notes"}


def test_gravity_set_upwards_is_refused_before_the_run(model: ContactModel,
                                                        folder: pathlib.Path) -> None:
    """``model.gravity = (0, 9.81)`` on a built model: refused in one line naming the body
    and the direction, as the case file's build refuses it, before the folder is touched.

    It ran into the static state, whose Newton failed after 40 iterations with and without
    friction (the Goda case: 'no static equilibrium ...; leave loads out of it ..., or set
    [initial] undeformed = true'), the earlier outputs of the folder cleared.
    """
    out = folder / "never_written_up"
    try:
        model.gravity = (0.0, 9.81)  # type: ignore[assignment]
        with pytest.raises(CaseError, match=r"^run: bodies\.a: nothing beneath it: gravity "
                           r"\(0\.0, 9\.81\) pulls it off its contact interfaces "
                           r"\('interface'\), .*gravity points up\?") as e:
            run(model, TimeSpec(dt=1e-4, end_time=3e-4), OutputSpec(out), report=False)
        assert "\n" not in str(e.value)
    finally:
        model.gravity = (0.0, -9.81)  # type: ignore[assignment]
    assert not out.exists()


def test_collapsed_contact_facet_of_a_model_built_in_python(folder: pathlib.Path) -> None:
    """A model built in Python whose general pair's master surface has a collapsed facet
    (tests/bad_cases/run/y_collapsed_quad.msh: a quadrilateral with two corners at
    (0.75, 0)): run() refuses it in one line before the folder is touched, on every
    rank (the case path refuses it when its model is built: y1_*)."""
    path = pathlib.Path(__file__).parent / "bad_cases" / "run" / "y_collapsed_quad.msh"
    material = Material(2314.0, 0.2, shear_modulus=2e9)
    model = ContactModel(read_mesh(path, COMM), [Body("block", material),
                                                 Body("base", material)],
                         fixed=[Fixed("base_bottom")], gravity=(0.0, -9.81), degree=1,
                         surface_pairs=[SurfacePair("sliding", "block", "base",
                                                    "block_bottom", "base_top",
                                                    penalty=5e10)])
    out = folder / "collapsed_facet"
    with pytest.raises(MeshError, match=r"^contact\.sliding\.master_surface: 'base_top' on "
                       r"'base' has 1 collapsed facet\(s\) \(no length: its two ends at one "
                       r"point\), the first centred at \(0\.75, 0\) m: remesh there$"):
        run(model, TimeSpec(dt=1e-3, end_time=2e-3), OutputSpec(out), report=False)
    assert not out.exists()
