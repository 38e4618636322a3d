"""The headline columns of a study's ``sweep.csv``: their values and their names.

:func:`headline` takes a run's headline numbers from its ``summary.json`` (and the
moduli from its ``case.toml``); :func:`headline_columns` names the columns a case can
give, before it runs, so that a study's ``[figures]`` columns are checked when the
study is read (a misspelt column drew nothing, silently).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

__all__ = ["FIXED", "RESULTS", "TABLE_COLUMNS", "headline", "headline_columns"]

FIXED = ("time_reached", "time_of_max_ux", "residual_slip", "max_uplift",
         "static_mean_pressure", "energy_balance_error", "external_work", "steps",
         "newton_iterations", "cutbacks", "loop_time")
"""The headline columns of every run."""
PROBE = ("peak_ux", "time_peak_ux", "residual_ux")
"""The headline columns of each point probe, ``<column>.<probe>``."""
STORM = ("storm.total_sliding", "storm.waves_finished", "storm.rigid_total_sliding")
"""The headline columns of a run with a storm."""
RESULTS = ("peak_ux", "time_peak_ux", "residual_ux", "time_of_max_ux", "residual_slip",
           "max_uplift", "energy_balance_error", "external_work", "storm.total_sliding",
           "storm.rigid_total_sliding")
"""The headline columns (a probe's before its ``.``) that only a finished run gives."""
TABLE_COLUMNS = ("case", "folder", "status", "wall_time", "warnings", "error")
"""The columns of ``sweep.csv`` besides the varied keys and the headline numbers."""


def headline(summary: Mapping[str, Any], case_toml: Mapping[str, Any] | None = None
             ) -> dict[str, float]:
    """The headline numbers of a run's summary (and moduli of its ``case.toml``).

    Columns: ``time_reached``; per probe ``peak_ux.<p>``, ``time_peak_ux.<p>``,
    ``residual_ux.<p>``; ``time_of_max_ux``, ``residual_slip``, ``max_uplift``;
    ``static_mean_pressure``; ``energy_balance_error`` (the largest over the run) and
    ``external_work`` (at the end), per metre out of plane; ``steps``,
    ``newton_iterations``, ``cutbacks``; ``loop_time`` (s); a storm's
    ``storm.total_sliding``, ``storm.waves_finished`` and the rigid-block model's
    ``storm.rigid_total_sliding`` (m); per body
    ``shear_modulus.<body>`` of the case as run (the calibrated G included).

    A run that did not finish (failed, interrupted) gives only what it did
    (``time_reached``, the static pressure, the solver's counts, the moduli): its peaks,
    residuals, energies and sliding are those of the steps it took, which a study's
    table would show beside the finished cases' as if they were results (a case failing
    at its first step gave the static state's displacement as its residual).
    """
    out: dict[str, float] = {}
    partial = summary.get("status", "finished") != "finished"

    def put(name: str, value: Any) -> None:
        if partial and (name in RESULTS or name.split(".")[0] in RESULTS):
            return
        if isinstance(value, int | float) and not isinstance(value, bool):
            out[name] = float(value)

    put("time_reached", summary.get("time", {}).get("reached"))
    dyn = summary.get("dynamic") or {}
    for p, v in (dyn.get("peak_ux") or {}).items():
        put(f"peak_ux.{p}", v.get("value"))
        put(f"time_peak_ux.{p}", v.get("time"))
    for p, v in (dyn.get("residual_ux") or {}).items():
        put(f"residual_ux.{p}", v)
    for key in ("time_of_max_ux", "residual_slip", "max_uplift"):
        put(key, dyn.get(key))
    put("static_mean_pressure", (summary.get("static") or {}).get("mean_contact_pressure"))
    energy = summary.get("energy") or {}
    put("energy_balance_error", energy.get("max_balance_error"))
    put("external_work", (energy.get("final") or {}).get("external_work"))
    solver = summary.get("solver") or {}
    put("steps", solver.get("steps"))
    put("newton_iterations", solver.get("newton_iterations"))
    put("cutbacks", solver.get("cutbacks"))
    put("loop_time", solver.get("wall_time"))
    storm = summary.get("storm") or {}
    put("storm.total_sliding", storm.get("total_sliding"))
    put("storm.waves_finished", storm.get("waves_finished"))
    put("storm.rigid_total_sliding", (storm.get("rigid") or {}).get("total_sliding"))
    for name, body in ((case_toml or {}).get("bodies") or {}).items():
        g = body.get("shear_modulus")
        if g is None and body.get("young_modulus") is not None:
            g = body["young_modulus"] / (2.0 * (1.0 + body["poisson"]))
        put(f"shear_modulus.{name}", g)
    return out


def headline_columns(resolved_case: Mapping[str, Any]) -> list[str]:
    """The headline columns a case can give (:func:`headline`'s), from its resolved case.

    A column may still be empty in a row (a failed run's, a value the run did not
    reach), never another name.
    """
    output = resolved_case.get("output") or {}
    probes = list(output.get("probes") or {})
    loads = (resolved_case.get("loads") or {}).values()
    storm = any(isinstance(load, Mapping) and isinstance(load.get("storm"), Mapping)
                for load in loads)
    return [*FIXED, *(f"{c}.{p}" for p in probes for c in PROBE), *(STORM if storm else ()),
            *(f"shear_modulus.{b}" for b in resolved_case.get("bodies") or {})]
