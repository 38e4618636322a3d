"""The warnings of a case's sizes and units (:mod:`breakwater.outputs.bodysizes`).

A run whose units are off by 1000 is consistent and silent; these lines are its only
trace. The run-level checks are in ``tests/bad_cases/run/`` (u3-u6).
"""

from __future__ import annotations

import pytest

from breakwater.outputs.bodysizes import DENSITY_RANGE, density_warnings, gravity_warning


@pytest.mark.parametrize(("density", "warned"), [
    (2.4, "below"),          # concrete in g/cm³ (2400 kg/m³)
    (9.99, "below"),
    (10.0, None),            # EPS geofoam's lightest
    (1650.0, None),          # the Goda mound's
    (22590.0, None),         # osmium
    (23000.0, None),
    (2.4e6, "above"),        # concrete in g/m³
])
def test_a_density_outside_any_solid_s_is_warned(density: float, warned: str | None) -> None:
    """Below EPS geofoam's 10 kg/m³ or above osmium's 22 590 (:data:`DENSITY_RANGE`):
    one line naming the body and the reading in kg/m³."""
    assert DENSITY_RANGE == (10.0, 23000.0)
    lines = density_warnings({"caisson": density, "mound": 1650.0})
    if warned is None:
        assert lines == []
        return
    (line,) = lines
    assert line.startswith(f"bodies.caisson: density {density:g} kg/m³, {warned} any ")
    if warned == "below":
        assert line.endswith(f"({density:g} g/cm³ = {1000 * density:g} kg/m³)")


def test_gravity_in_mm_per_s2_is_warned_and_a_centrifuge_s_is_not() -> None:
    """9810 m/s² (±5 %): g typed in mm/s²; 100 g of a centrifuge model: not warned."""
    assert gravity_warning((0.0, -9810.0)) is not None
    assert gravity_warning((0.0, -9810.0, 0.0)).endswith("[0.0, -9.81, 0.0]")  # type: ignore[union-attr]
    assert gravity_warning((0.0, -9.81)) is None
    assert gravity_warning((0.0, -981.0)) is None
