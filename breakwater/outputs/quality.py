"""Quality of a penalty contact: penetration and penalty stiffness of each pair.

A penalty contact lets the bodies interpenetrate by ``δ = p / ε_n`` where the contact
pressure is ``p``. Too soft a penalty ε_n and the penetration is a visible part of the
result (the paper asks for "no noticeable interpenetration", the paper's §5.4); too stiff and
it buys nothing but a worse-conditioned Jacobian. The measures, per contact pair:

- ``h``, the element size at the interface: the mean length of the interface facets;
- ``h_δ``, the size of the facet where the static penetration is largest (the smallest
  facet at its node, or, for a conforming pair, at the nodes within 1 % of it:
  :func:`breakwater.model.pairs.penetration_facet`; the interface's smallest facet when
  nothing penetrates): the
  penetration is compared with the facets it distorts, not with the mean (on a graded
  mesh, fine where the contact presses and coarse elsewhere, the mean hid a penetration
  of several % of the pressed facets: before 2026-11-28);
- ``δ_static`` and ``δ_dynamic``, the largest nodal penetration ``max ⟨−g_n⟩₊`` over
  the interface nodes, in the static state and over the time steps (m);
- ``s``, the static settlement: the mean, over the interface nodes, of the normal
  displacement of the interface in the static state (both sides' nodes averaged,
  ``|mean(½(u_s + u_m)·n)|``), the deformation scale that the penetration spoils;
- ``ε_n h / E`` of each side: the penalty's stiffness over that of a layer of the
  body one element thick (``E/h`` per unit area).

Thresholds (constants below) and why:

- too soft: ``max(δ_static, δ_dynamic) > 1% h_δ`` (:data:`MAX_PENETRATION_OVER_H`): the
  penetration then distorts the interface elements themselves by more than the
  error of a P2 interpolation of a smooth field on them, and it is visible on a
  deformed plot scaled to show the elements; or ``δ_static > 10% s``
  (:data:`MAX_PENETRATION_OVER_SETTLEMENT`): more than a tenth of the static
  settlement is the penalty's artefact, not the bodies' deformation (the settlement
  of a rigid slave on a rigid master is all penetration). Only the static
  penetration is compared with the settlement: an impact concentrates the pressure
  under a corner, so the dynamic penetration there is compared with ``h`` only.
- too stiff: ``ε_n h / E > 1000`` for the softer side
  (:data:`MAX_STIFFNESS_RATIO`): the penetration is then below 0.1% of the elastic
  deformation of the interface elements, far below the discretisation error, while
  the interface rows of the Jacobian are a thousand times stiffer than the bulk rows,
  so its condition number and the round-off of the contact residual (Newton's floor)
  grow in proportion. The softer side is used because it deforms the most and it has
  the smallest diagonal stiffness.

The suggested ε_n range: the upper end is ``1000 E_soft / h``; the lower end is the
smallest ε_n meeting the penetration criteria while the bodies' own deformation stays.
The largest penetration does not scale as 1/ε_n where it matters: at the edge of a
stiff body on a soft one (the caisson's corner on the mound) the pressure has the
flat punch's r^(-1/2) singularity, which the penalty cuts off at a length ∝ 1/ε_n, so
the edge pressure grows as ε_n^(1/2) and the penetration falls as ε_n^(-1/2) only; an
impact's penetration (½ ε_n δ² = the kinetic energy) falls alike. Measured on
``examples/goda_nonmatching.toml``: δ ∝ ε_n^(-0.57) from 5e8 to 9.6e8 N/m³, ε_n^(-0.48)
from 9.6e8 to 1.0e11; the 1/ε_n rule suggested 9.57e8, and a run at 9.58e8 was still
too soft. So a criterion failing by the ratio r > 1 (the penetration over what is
allowed) asks for ε_n (r / :data:`PENETRATION_MARGIN`)² (:data:`EDGE_EXPONENT` ½, the
penetration aimed at 80 % of the allowed: an exponent a little below ½ over a factor r
up to 250, as measured, still passes); where that is above the upper end, the lower
end is the upper end, unless even the 1/ε_n rule (the least a stiffer penalty can
need) is above it: then no ε_n meets both criteria, refine the mesh at the interface.
A criterion that holds (r ≤ 1) lowers ε_n only as far as the 1/ε_n rule allows, ε_n r
(a softer penalty's penetration grows at most as 1/ε_n), and the settlement's against
the bodies' own settlement only (a softer penalty adds the mean penetration's half to
the settlement, less than the largest's). The current ε_n is inside the range exactly
when the verdict is ``ok``.

Everything here is a pure function of numbers (no dolfinx): the run layer measures
the inputs (each pair's :meth:`breakwater.model.pairs.Pair.static_measures`, made
:class:`PairInputs` in :mod:`breakwater.outputs.summary`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from breakwater.model.pairs import StaticMeasures, max_penetration, settlement

__all__ = [
    "EDGE_EXPONENT",
    "MAX_PENETRATION_OVER_H",
    "MAX_PENETRATION_OVER_SETTLEMENT",
    "MAX_STIFFNESS_RATIO",
    "PENETRATION_MARGIN",
    "ContactQuality",
    "PairInputs",
    "assess",
    "max_penetration",
    "settlement",
    "stiffness_ratio",
    "suggested_penalty",
]

MAX_PENETRATION_OVER_H = 0.01
"""Largest penetration accepted, as a fraction of the interface element size."""
MAX_PENETRATION_OVER_SETTLEMENT = 0.1
"""Largest static penetration accepted, as a fraction of the static settlement."""
MAX_STIFFNESS_RATIO = 1e3
"""Largest ε_n h / E (softer side) before the penalty costs conditioning."""
EDGE_EXPONENT = 0.5
"""The slowest fall of the largest penetration with ε_n: δ ∝ ε_n^(-½) at a stiff body's edge."""
PENETRATION_MARGIN = 0.8
"""A stiffer penalty is suggested for this fraction of the allowed penetration."""


def stiffness_ratio(penalty: float, h: float, young_modulus: float) -> float:
    """``ε_n h / E``: the penalty over the stiffness E/h of a one-element layer."""
    return penalty * h / young_modulus


def suggested_penalty(penalty: float, h: float, young_moduli: tuple[float, float],
                      static_penetration: float, settlement_: float,
                      dynamic_penetration: float | None = None,
                      penetration_size: float | None = None) -> tuple[float, float]:
    """The ε_n range meeting the criteria of this module (see its docstring).

    Args:
        penalty: The current ε_n (N/m³).
        h: Mean interface element size (m), of the stiffness criterion.
        young_moduli: Young's moduli of the two sides (Pa).
        static_penetration: Static penetration at ``penalty`` (m).
        settlement_: Static settlement (m), penetration included.
        dynamic_penetration: Largest penetration over the time steps (m), if known.
        penetration_size: The facet size h_δ the penetration is compared with (m);
            None: ``h``.

    Returns:
        ``(low, high)``: ``low`` from the penetration criteria (0 without
        penetration), ``high = MAX_STIFFNESS_RATIO · min(E) / h``; ``low > high``: no
        ε_n meets both.
    """
    δ = max(static_penetration, dynamic_penetration or 0.0)
    # Each criterion's ratio r: the penetration over what it allows (> 1: fails).
    ratios = [δ / (MAX_PENETRATION_OVER_H * (penetration_size or h))]
    # The settlement (both sides averaged) holds at most half the largest penetration:
    # s' = s − (δ − δ')/2 at ε' > ε_n, s_b = s − δ/2 the bodies' own part at least.
    # δ' ≤ f s' is δ' (1 − f/2) ≤ f s_b: r = δ (1 − f/2) / (f s_b), exactly δ ≤ f s at
    # ε' = ε_n.
    δ_s, f = static_penetration, MAX_PENETRATION_OVER_SETTLEMENT
    body = settlement_ - 0.5 * δ_s
    softer = ratios[0]
    if δ_s > 0:
        ratios.append(δ_s * (1 - 0.5 * f) / (f * body) if body > 0 else np.inf)
        # A softer ε' may add less than (δ' − δ)/2 to the settlement (the mean
        # penetration's half): δ' ≤ f s_b is what it surely keeps (at most ε_n itself).
        softer = max(softer, min(δ_s / (f * body) if body > 0 else np.inf, 1.0))
    r = max(ratios)
    high = MAX_STIFFNESS_RATIO * min(young_moduli) / h
    if r <= 1:  # met: a softer ε' keeps it while δ ε_n / ε' (the fastest growth) does
        return float(penalty * softer), float(high)
    smooth = penalty * r  # the least a stiffer penalty can need (δ ∝ 1/ε_n)
    edge = penalty * (r / PENETRATION_MARGIN) ** (1 / EDGE_EXPONENT)  # (δ ∝ ε_n^-½)
    return float(max(smooth, min(edge, high))), float(high)


@dataclass(frozen=True)
class ContactQuality:
    """The quality measures of one contact pair (see the module docstring).

    Attributes:
        penalty: ε_n (N/m³).
        element_size: Mean interface facet length h (m).
        settlement: Static settlement s (m).
        penetration_size: The facet size h_δ the penetrations are compared with (m).
        static_penetration: Largest static penetration (m).
        dynamic_penetration: Largest penetration over the steps (m), None before.
        time_of_dynamic_penetration: When it occurred (s).
        stiffness_ratio: ``ε_n h / E`` of the slave and of the master.
        issues: Codes of the criteria failed: ``static_penetration_over_h``,
            ``dynamic_penetration_over_h``, ``penetration_over_settlement``,
            ``stiff``.
        suggested_penalty: ``(low, high)`` ε_n range (N/m³).
        warnings: One message per issue, with the suggested range.
    """

    penalty: float
    element_size: float
    settlement: float
    static_penetration: float
    dynamic_penetration: float | None
    time_of_dynamic_penetration: float | None
    stiffness_ratio: tuple[float, float]
    issues: tuple[str, ...]
    suggested_penalty: tuple[float, float]
    warnings: tuple[str, ...]
    penetration_size: float = 0.0

    @property
    def verdict(self) -> str:
        """``ok``, ``too soft``, ``too stiff`` or ``too soft and too stiff``."""
        soft = any(i != "stiff" for i in self.issues)
        stiff = "stiff" in self.issues
        return {(False, False): "ok", (True, False): "too soft", (False, True): "too stiff",
                (True, True): "too soft and too stiff"}[(soft, stiff)]

    def as_dict(self) -> dict[str, object]:
        """The summary entry (``contact_quality.<pair>`` in ``summary.json``)."""
        h, s = self.element_size, self.settlement
        h_δ = self.penetration_size or h

        def over(x: float | None, y: float) -> float | None:
            return None if x is None or not y > 0 else x / y

        return {
            "penalty": self.penalty,
            "element_size": h,
            "penetration_element_size": h_δ,
            "static_settlement": s,
            "static_penetration": self.static_penetration,
            "static_penetration_over_h": over(self.static_penetration, h_δ),
            "static_penetration_over_settlement": over(self.static_penetration, s),
            "dynamic_penetration": self.dynamic_penetration,
            "time_of_dynamic_penetration": self.time_of_dynamic_penetration,
            "dynamic_penetration_over_h": over(self.dynamic_penetration, h_δ),
            "dynamic_penetration_over_settlement": over(self.dynamic_penetration, s),
            "penalty_h_over_E": {"slave": self.stiffness_ratio[0],
                                 "master": self.stiffness_ratio[1]},
            "verdict": self.verdict,
            "issues": list(self.issues),
            "suggested_penalty": list(self.suggested_penalty),
            "thresholds": {"penetration_over_h": MAX_PENETRATION_OVER_H,
                           "static_penetration_over_settlement":
                               MAX_PENETRATION_OVER_SETTLEMENT,
                           "penalty_h_over_E": MAX_STIFFNESS_RATIO},
            "warnings": list(self.warnings),
        }


def assess(name: str, penalty: float, element_size: float,
           young_moduli: tuple[float, float], static_penetration: float,
           settlement_: float, dynamic_penetration: float | None = None,
           time_of_dynamic_penetration: float | None = None,
           penetration_size: float | None = None) -> ContactQuality:
    """Assess one contact pair against the thresholds of this module.

    Args:
        name: Pair name, for the messages.
        penalty: ε_n (N/m³).
        element_size: Mean interface facet length h (m).
        young_moduli: Young's moduli (slave, master) (Pa).
        static_penetration: Largest static penetration (m).
        settlement_: Static settlement (m), see :func:`settlement`.
        dynamic_penetration: Largest penetration over the steps (m), if any.
        time_of_dynamic_penetration: When it occurred (s).
        penetration_size: The size h_δ of the facet where the static penetration is
            largest (the interface's smallest facet when nothing penetrates) (m): the
            penetrations are compared with it; None (not measured): the mean ``h``.
    """
    h, s = element_size, settlement_
    h_δ = penetration_size or h
    at = ("the facet where it is largest" if static_penetration > 0 else
          "the smallest facet of the interface") if penetration_size else "the mean facet"
    ratios = (stiffness_ratio(penalty, h, young_moduli[0]),
              stiffness_ratio(penalty, h, young_moduli[1]))
    low, high = suggested_penalty(penalty, h, young_moduli, static_penetration, s,
                                  dynamic_penetration, h_δ)
    advice = f"suggested ε_n in [{low:.3g}, {high:.3g}] N/m³" if low < high else (
        f"suggested ε_n = {high:.3g} N/m³, the stiffest accepted (at a stiff body's edge "
        "the penetration falls as ε_n^-½ only: if it is still too soft, refine the mesh "
        "at the interface)" if low == high else
        f"no ε_n meets both criteria ({low:.3g} > {high:.3g} N/m³): refine the mesh at "
        "the interface")
    issues: list[str] = []
    warnings: list[str] = []
    pre = f"contact '{name}': penalty ε_n = {penalty:.3g} N/m³"
    limit = MAX_PENETRATION_OVER_H * h_δ
    if static_penetration > limit:
        issues.append("static_penetration_over_h")
        warnings.append(f"{pre} is too soft: static penetration {static_penetration:.3g} m "
                        f"> {MAX_PENETRATION_OVER_H:.0%} of the element size h = {h_δ:.3g} m,"
                        f" {at}; {advice}")
    if dynamic_penetration is not None and dynamic_penetration > limit:
        when = ("" if time_of_dynamic_penetration is None
                else f" at t = {time_of_dynamic_penetration:.4g} s")
        issues.append("dynamic_penetration_over_h")
        where = at.replace("where it is", "where the static penetration is")
        warnings.append(f"{pre} is too soft: penetration {dynamic_penetration:.3g} m{when} "
                        f"> {MAX_PENETRATION_OVER_H:.0%} of the element size h = {h_δ:.3g} m,"
                        f" {where}; {advice}")
    if static_penetration > MAX_PENETRATION_OVER_SETTLEMENT * s:
        issues.append("penetration_over_settlement")
        warnings.append(f"{pre} is too soft: static penetration {static_penetration:.3g} m "
                        f"> {MAX_PENETRATION_OVER_SETTLEMENT:.0%} of the static settlement "
                        f"{s:.3g} m; {advice}")
    if max(ratios) > MAX_STIFFNESS_RATIO:
        issues.append("stiff")
        warnings.append(f"{pre} is stiffer than needed: ε_n h / E = {max(ratios):.3g} > "
                        f"{MAX_STIFFNESS_RATIO:.3g} (softer side; h = {h:.3g} m) costs "
                        f"conditioning for no accuracy; {advice}")
    return ContactQuality(penalty, h, s, static_penetration, dynamic_penetration,
                          time_of_dynamic_penetration, ratios, tuple(issues), (low, high),
                          tuple(warnings), h_δ)


@dataclass(frozen=True)
class PairInputs:
    """The static measures of one contact pair that its quality is assessed from.

    Plain numbers, measured once on the static state and saved with a checkpoint.

    Attributes:
        name: Pair name, for the messages.
        penalty: ε_n (N/m³).
        element_size: Mean interface facet length h (m).
        young_moduli: Young's moduli (slave, master) (Pa).
        static_penetration: Largest static penetration (m).
        settlement: Static settlement (m), see :func:`settlement`.
        penetration_size: The facet size h_δ where the static penetration is largest
            (m), None: not measured (a checkpoint of an earlier version).

    The pair's largest penetration over a run is its history column
    ``<name>_penetration``.
    """

    name: str
    penalty: float
    element_size: float
    young_moduli: tuple[float, float]
    static_penetration: float
    settlement: float
    penetration_size: float | None = None

    def __post_init__(self) -> None:
        a, b = self.young_moduli  # (a list when read back from JSON)
        object.__setattr__(self, "young_moduli", (a, b))

    def assess(self, dynamic_penetration: float | None = None,
               time_of_dynamic_penetration: float | None = None) -> ContactQuality:
        """The quality of the pair (:func:`assess`), with the dynamic penetration if known."""
        return assess(self.name, self.penalty, self.element_size, self.young_moduli,
                      self.static_penetration, self.settlement, dynamic_penetration,
                      time_of_dynamic_penetration, self.penetration_size)

    @classmethod
    def of(cls, name: str, measures: StaticMeasures) -> PairInputs:
        """The inputs of the pair ``name`` from its static measures."""
        return cls(name, measures.penalty, measures.element_size, measures.young_moduli,
                   measures.static_penetration, measures.settlement,
                   measures.penetration_size)
