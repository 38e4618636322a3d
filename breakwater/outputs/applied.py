"""The loads a run actually applied: resultant force and impulse, integrated on the mesh.

A load of the model is ``amplitude(t) × unit traction`` on its facets
(:class:`~breakwater.model.model.SurfaceLoad`), so its resultant force is ``amplitude(t) R``
with ``R = ∫ unit traction ds`` a constant vector (N/m per unit amplitude in plane
strain), assembled once. :class:`AppliedLoads` records, at every accepted step end,
the amplitudes the stepper evaluated (GN22 evaluates the loads at the step ends) and
integrates, per load of the case (its model loads summed: a Goda load's uplift too),

- the impulse with GN22's own momentum rule, ``Σ Δt [(1 − β₁) F(t₀) + β₁ F(t₁)]``: the
  stepper's momentum update is ``M (v₁ − v₀) = Δt [(1 − β₁) M a₀ + β₁ M a₁]`` with
  ``M a = F − ...``, so this is the impulse the model received (the trapezoidal rule at
  β₁ = ½; at a constant Δt, and for a load zero at both ends of the run, ``Δt Σ F(t_n)``
  for any β₁);
- the largest |F(t_n)| and its instant, and F at the last step end.

The cost per step is a few multiplications per load. The sums live in the run state
(:class:`~breakwater.run.runstate.RunState`), so a resumed run continues them.
"""

from __future__ import annotations

from collections.abc import Mapping, MutableMapping, Sequence
from typing import Any

import numpy as np

from breakwater.model.model import ContactModel
from breakwater.model.parts import StageWatch

__all__ = ["AppliedLoads", "applied_warnings"]

TOLERANCE = 0.01
"""A pulse's applied impulse may differ from the requested by this fraction unwarned."""


class AppliedLoads:
    """Integrates the resultant force of each load of the case over the run.

    Args:
        model: The contact model (collective: assembles each load's unit resultant).
        beta1: GN22's β₁ (the momentum rule's weight of the step end).
        state: The sums (a dictionary of plain numbers, kept in the run state and
            updated in place; empty for a new run).

    """

    def __init__(self, model: ContactModel, beta1: float,
                 state: MutableMapping[str, Any]) -> None:
        self.beta1 = beta1
        self.model = model
        gdim = model.gdim
        # The resultants with the load vectors' own quadrature (ContactModel.load_resultant).
        self._forms = [[model.form(model.load_resultant(ld, i)) for i in range(gdim)]
                       for ld in model.loads]
        unit = [[model.assemble(f) for f in forms] for forms in self._forms]
        # The loads whose field changes at given times: ``unit`` assembled again then.
        self._watch = StageWatch(model.loads)
        self.names: list[str] = []
        for k, ld in enumerate(model.loads):
            name = ld.spec.name or f"load {k}"
            if name not in self.names:
                self.names.append(name)
        # Force of each case load = owner @ (amplitudes[:, None] * unit).
        self.unit = np.array(unit, dtype=float).reshape(len(model.loads), gdim)
        self.owner = np.zeros((len(self.names), len(model.loads)))
        for k, ld in enumerate(model.loads):
            self.owner[self.names.index(ld.spec.name or f"load {k}"), k] = 1.0
        self.state = state
        if not state:
            state.update({"t": None, "force": None,
                          "impulse": [[0.0] * gdim for _ in self.names],
                          "peak": [0.0] * len(self.names),
                          "time_of_peak": [None] * len(self.names)})

    def forces(self, amplitudes: Sequence[float] | None = None) -> np.ndarray:
        """The resultant force (N/m) of each case load at the loads' current amplitudes.

        A staged load's unit resultant is assembled again when its stage changed
        (collective: every rank sets the stages from the same time).

        Args:
            amplitudes: The model loads' amplitudes instead of their current ones.
        """
        for k in self._watch.changed():
            self.unit[k] = [self.model.assemble(f) for f in self._forms[k]]
        if amplitudes is None:
            amplitudes = [float(ld.amplitude.value) for ld in self.model.loads]
        return self.owner @ (np.asarray(amplitudes, dtype=float)[:, None] * self.unit)

    def record(self, t: float, amplitudes: Sequence[float] | None = None) -> None:
        """Add the step ending at ``t`` (the loads at their amplitudes there).

        Args:
            t: The step's end.
            amplitudes: The amplitudes the stepper took there, where not the loads'
                current ones (the start of a run: a load left out of the initial state
                is not in a₀, :meth:`breakwater.stepping.gn22.GN22.initialise`).
        """
        st = self.state
        if not self.names:
            return
        force = self.forces(amplitudes)
        if st["t"] is not None:
            dt = t - st["t"]
            f0 = np.array(st["force"])
            impulse = np.array(st["impulse"]) + dt * ((1.0 - self.beta1) * f0
                                                      + self.beta1 * force)
            st["impulse"] = impulse.tolist()
        size = np.linalg.norm(force, axis=1) if len(force) else np.zeros(0)
        for i, f in enumerate(size.tolist()):
            if st["time_of_peak"][i] is None or f > st["peak"][i]:
                st["peak"][i], st["time_of_peak"][i] = f, t
        st["t"], st["force"] = t, force.tolist()

    def summary(self) -> dict[str, dict[str, Any]]:
        """Per load of the case, its ``applied`` entry of the summary."""
        st = self.state
        out = {}
        for i, name in enumerate(self.names):
            out[name] = {"applied": {
                "impulse_per_length": st["impulse"][i],
                "peak_force_per_length": st["peak"][i],
                "time_of_peak": st["time_of_peak"][i],
                "final_force_per_length": None if st["force"] is None else st["force"][i],
                "unit_resultant_per_length": (self.owner[i] @ self.unit).tolist(),
                "until": st["t"],
                "rule": "GN22 momentum rule: sum of dt ((1 - beta1) F(t0) + beta1 F(t1)), "
                        "F at the step ends",
            }}
        return out


def compare(loads: Mapping[str, Mapping[str, Any]]) -> dict[str, dict[str, Any]]:
    """The applied-over-requested ratios of the pulses (``applied.impulse_ratio``).

    Args:
        loads: The summary's ``loads`` entry (requested values, with ``applied``).
    """
    out: dict[str, dict[str, Any]] = {}
    for name, info in loads.items():
        applied = info.get("applied")
        if applied is None or "impulse_per_length" not in info or "direction" not in info:
            continue
        along = float(np.dot(applied["impulse_per_length"], info["direction"]))
        out[name] = {"applied": {
            "impulse_along_direction": along,
            "impulse_ratio": along / info["impulse_per_length"],
            "peak_force_ratio": applied["peak_force_per_length"]
            / info["peak_force_per_length"]}}
    return out


def applied_warnings(loads: Mapping[str, Mapping[str, Any]]) -> list[str]:
    """One-line warnings for pulses whose applied impulse differs from the requested.

    Only those the warning before the run did not announce: the applied impulse differs
    from the requested by more than :data:`TOLERANCE` and from what the nominal steps
    sample (``sampled``, predicted before the run) by more than that too.

    Args:
        loads: The summary's ``loads`` entry: plane strain's keys (``impulse_per_length``,
            N s/m) or a 3D run's (``impulse``, N s: the whole body's,
            :func:`breakwater.outputs.summary.whole_body_keys`).
    """
    lines = []
    for name, info in loads.items():
        applied = info.get("applied", {})
        ratio = applied.get("impulse_ratio")
        if ratio is None or abs(ratio - 1.0) <= TOLERANCE:
            continue
        sampled = info.get("sampled", {}).get("impulse_ratio")
        if sampled is not None and abs(ratio - sampled) <= TOLERANCE:
            continue
        key, unit = (("impulse_per_length", "N s/m") if "impulse_per_length" in info
                     else ("impulse", "N s"))
        lines.append(f"loads.{name}: the steps applied an impulse of "
                     f"{applied['impulse_along_direction']:.4g} {unit}, {100 * ratio:.3g}% of "
                     f"the requested {info[key]:.4g} {unit} (cut-backs moved "
                     "the step ends; summary.json loads.{name}.applied)".replace("{name}", name))
    return lines
