"""The case a run writes: the resolved case with the settings the run was given.

:func:`breakwater.run.simulation.run` takes the time and output settings
(:class:`~breakwater.config.runspec.TimeSpec`, :class:`~breakwater.config.runspec.OutputSpec`)
and, apart, the resolved case it writes as ``case.toml`` and fingerprints for
``--resume``. From Python the two can differ: a notebook runs a built model again with
``dataclasses.replace(time, dt=5e-5)`` and the same ``built.case.resolved()``. The run
used the spec's Δt while ``case.toml`` said the old one (``python -m breakwater run
case.toml`` then ran another case) and a checkpoint of the one resumed under the other.
:func:`case_as_run` writes the specs' values into the resolved case's ``[time]`` and
``[output]`` tables, and the model's damping and gravity (``model.damping`` and
``model.gravity.value`` may be set on a built model), and says which keys it changed.
"""

from __future__ import annotations

import copy
import dataclasses
import json
from collections.abc import Mapping, Sequence
from dataclasses import MISSING
from typing import TYPE_CHECKING, Any

from breakwater.common.files import to_jsonable
from breakwater.config.fields import to_toml
from breakwater.config.runspec import OutputSpec, TimeSpec

if TYPE_CHECKING:
    from breakwater.model.parts import Damping

__all__ = ["case_as_run", "changed_line", "checked_arguments", "checked_extra"]


def checked_arguments(model: Any, time: Any, output: Any, resolved_case: Any
                      ) -> Mapping[str, Any] | None:
    """:func:`~breakwater.run.simulation.run`'s arguments checked; the case as a mapping.

    A :class:`~breakwater.casefile.case.Case` given as ``resolved_case`` (``built.case``,
    "the case as run") is taken for its ``resolved()``: it failed with ``TypeError:
    'Case' object is not iterable`` from inside the run, as a ``dict`` given for
    ``time`` did with ``AttributeError: 'dict' object has no attribute 'dt'``.

    The probes are checked against the model here, before the output folder is
    touched: a probe naming a body or a pair the model does not have, or a point
    outside its body, was refused only once the run had cleared the earlier run's
    outputs in the folder.

    Raises:
        TypeError: An argument of another type (one line naming it).
        CaseError: A probe naming a body or a pair the model does not have, or a
            gravity that pulls a body off its supports (one line).
        MeshError: A probe's point outside its body, or a general pair's surface with
            collapsed faces (:func:`~breakwater.contact.surfaces.check_faces`; one line).
    """
    from breakwater.common.errors import CaseError
    from breakwater.contact.surfaces import check_faces
    from breakwater.model.model import ContactModel
    from breakwater.model.pairs import probed_pair
    from breakwater.model.pointprobe import check_body, check_point
    from breakwater.statics.initial import gravity_problem

    for name, value, cls, hint in (
            ("model", model, ContactModel, "built.model"),
            ("time", time, TimeSpec, "built.time, or TimeSpec(dt=..., end_time=...)"),
            ("output", output, OutputSpec, "built.output, or OutputSpec(directory=...)")):
        if not isinstance(value, cls):
            raise TypeError(f"run: {name}: expected {cls.__name__} ({hint}), got "
                            f"{type(value).__name__}")
    for p in output.probes:  # (the point: collective, each rank searches its cells)
        check_body(p.name, p.body, [b.spec.name for b in model.bodies])
        check_point(model, p.name, p.body, p.point)
    general = [p.name for p in model.surface_pairs]
    for q in output.pair_probes:
        probed_pair(q.name, q.pair, len(model.pairs), general)
    why = gravity_problem(model)  # (collective) a gravity set since the build
    if why is not None:
        raise CaseError(f"run: {why}")
    check_faces(model)  # (collective) collapsed contact faces of a model built in Python
    if resolved_case is None or isinstance(resolved_case, Mapping):
        return resolved_case
    resolved = getattr(resolved_case, "resolved", None)
    if callable(resolved):
        return resolved()  # type: ignore[no-any-return]
    raise TypeError("run: resolved_case: expected a case's resolved() (a mapping, e.g. "
                    f"built.case.resolved()), got {type(resolved_case).__name__}")


RUN_ENTRIES = ("case_name", "dimension", "finished", "status", "error", "time", "static",
               "dynamic", "contact_quality", "solver", "energy", "checkpoint",
               "resumed_from", "outputs", "versions", "work", "gravity", "fixed")
"""The entries of ``summary.json`` that the run writes itself
(:func:`~breakwater.outputs.summary.run_summary`, :class:`~breakwater.run.session.Session`);
a case's build adds ``mesh``, ``calibration`` and ``loads``."""


def checked_extra(extra_summary: Any) -> Mapping[str, Any] | None:
    """``run``'s ``extra_summary`` checked: a mapping that ``summary.json`` can hold.

    NumPy numbers and arrays are written as numbers and lists
    (:func:`~breakwater.common.files.to_jsonable`); a value JSON cannot hold (a set, an
    object) failed with ``json``'s traceback at the first summary write, once the
    outputs of an earlier run in the folder had been cleared.

    A key of the run's own (:data:`RUN_ENTRIES`) overwrote the run's entry:
    ``{"status": "draft"}`` made ``summary.json`` say ``draft`` for a finished run (a
    study's rerun reads it), ``{"time": {"dt": 1}}`` changed the time step it reports; or
    was overwritten by it (``work``, ``gravity``), silently.

    Raises:
        TypeError: Not a mapping, a key of the run's own, or a value of a key JSON cannot
            hold (one line naming the key; nothing is written).
    """
    if extra_summary is None:
        return None
    if not isinstance(extra_summary, Mapping):
        raise TypeError("run: extra_summary: expected a mapping (e.g. {'note': 'trial 3'}), "
                        f"got {type(extra_summary).__name__}")
    for key, value in extra_summary.items():
        if key in RUN_ENTRIES:
            raise TypeError(f"run: extra_summary[{key!r}]: summary.json's own entry, which "
                            "the run writes: give yours under another key (e.g. "
                            "extra_summary={'notes': {...}})")
        try:
            json.dumps(to_jsonable(value))
        except (TypeError, ValueError) as e:  # (ValueError: a circular reference)
            raise TypeError(f"run: extra_summary[{key!r}]: summary.json cannot hold it ({e}): "
                            "give numbers, strings, bools, None, lists and dicts of them "
                            "(NumPy numbers and arrays are converted)") from None
    return extra_summary


def case_as_run(resolved_case: Mapping[str, Any], time: TimeSpec, output: OutputSpec,
                damping: Damping | None = None, gravity: Sequence[float] | None = None
                ) -> tuple[dict[str, Any], list[tuple[str, Any, Any]]]:
    """The resolved case with the run's time, output and damping settings written in.

    Only tables that ``resolved_case`` has are touched; a key a table leaves out (a
    partial case from Python) stands for its default, and is written only when the
    run's value is another (a required key left out stays out). The output's probes
    are left (the case names them by group or point, the spec by coordinates), as is
    the case's name (a spec's ``case_name`` is only the reports' label).

    Args:
        resolved_case: The resolved case given to the run (not modified).
        time: The time settings the run uses.
        output: The output settings the run uses.
        damping: The model's Rayleigh damping (``model.damping``, which a notebook may
            set on a built model).
        gravity: The model's gravity (``model.gravity.value``, a constant a notebook
            may set alike).

    Returns:
        The case as run, and the keys changed as ``(dotted key, value run, value
        given)``.
    """
    case = copy.deepcopy(dict(resolved_case))
    changed: list[tuple[str, Any, Any]] = []

    def put(table: dict[str, Any], prefix: str, key: str, value: Any) -> None:
        if table.get(key) != value:
            changed.append((f"{prefix}{key}", value, table.get(key)))
            table[key] = value

    if isinstance(case.get("time"), dict):
        table = case["time"]
        run = to_toml(time)
        defaults = {f.name: f.default for f in dataclasses.fields(TimeSpec)}
        for key in sorted(set(table) | set(run)):
            if key in table and key not in run:  # a None field (min_dt): left out
                changed.append((f"time.{key}", None, table.pop(key)))
            elif key in table or (defaults.get(key, MISSING) is not MISSING
                                  and run[key] != to_toml(defaults[key])):
                put(table, "time.", key, run[key])  # a key left out is its default
    if isinstance(case.get("output"), dict):
        table = case["output"]
        put(table, "output.", "directory", str(output.directory))
        for key in ("field_interval", "figures", "checkpoint_interval"):
            put(table, "output.", key, getattr(output, key))
    if damping is not None and isinstance(case.get("damping"), dict):
        put(case["damping"], "damping.", "alpha", damping.alpha)
        put(case["damping"], "damping.", "beta", damping.beta)
    if gravity is not None and "gravity" in case:
        put(case, "", "gravity", [float(g) for g in gravity])
    return case, changed


def changed_line(changed: list[tuple[str, Any, Any]]) -> str | None:
    """The one-line warning of :func:`case_as_run`'s changes, None if none is worth one.

    Only the keys that change the numbers (``time.*``, ``damping.*``, ``gravity``) are
    named: another output folder, field interval or figures switch is an ordinary
    change of a run again, written in without a word.
    """
    keys = ", ".join(f"{key} = {_value(run)} (resolved_case: {_value(given)})"
                     for key, run, given in changed if not key.startswith("output."))
    if not keys:
        return None
    return (f"case.toml: written with the settings run() was given, not resolved_case's: "
            f"{keys} (to keep them in step, pass dataclasses.replace(built.case, "
            f"time=time, damping=...).resolved())")


def _value(value: Any) -> str:
    return "unset" if value is None else f"{value:g}" if isinstance(value, float) \
        else repr(value) if isinstance(value, str) else str(value)
