"""The after-run warning of a pulse whose applied impulse is not the requested one.

:func:`breakwater.outputs.applied.applied_warnings` reads the summary's ``loads``: in
plane strain the keys per metre (``impulse_per_length``, N s/m), in 3D the whole body's
(``impulse``, N s: :func:`breakwater.outputs.summary.whole_body_keys`). A 3D run whose
pulse lost 10 % of its impulse ended in a KeyError traceback instead of the warning.
"""

from __future__ import annotations

from breakwater.outputs.applied import applied_warnings
from breakwater.outputs.summary import whole_body_keys

# A pulse of 20 N s (per metre in 2D) of which the steps applied 18, predicted 20.
LOADS = {"push": {"impulse_per_length": 20.0, "direction": [1.0, 0.0],
                  "sampled": {"impulse_ratio": 1.0},
                  "applied": {"impulse_per_length": [18.0, 0.0],
                              "impulse_along_direction": 18.0, "impulse_ratio": 0.9}}}


def test_plane_strain_warning_per_metre() -> None:
    (line,) = applied_warnings(LOADS)
    assert "18 N s/m, 90% of the requested 20 N s/m" in line and "\n" not in line


def test_3d_warning_names_the_whole_body_impulse() -> None:
    (line,) = applied_warnings(whole_body_keys(LOADS))
    assert line.startswith("loads.push: the steps applied an impulse of 18 N s, 90% of "
                           "the requested 20 N s ")
    assert "\n" not in line
