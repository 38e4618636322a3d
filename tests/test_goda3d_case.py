"""The built-in 3D Goda case (``python -m breakwater run goda3d``), briefly.

The whole run (0.15 s, about 9 minutes on 2 cores) is measured in docs/threed.md; here
its set-up and first steps: what the case applies, checked against the paper's data.
"""

from __future__ import annotations

import pathlib

import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)
from breakwater.casefile.case import load_case
from breakwater.loads.signals import pendulum_impulse
from breakwater.run import simulation

COMM = MPI.COMM_WORLD


@pytest.mark.serial
@pytest.mark.timeout(300)
def test_goda3d_first_steps(folder: pathlib.Path) -> None:
    # The mound's shear modulus given (the calibrated value of a full run, 2.247 MPa:
    # docs/threed.md), 1 ms of the pulse. The static contact resultant is the block's
    # weight ρ g (0.205 × 0.202 × 0.205) m³ (Newton's 1e-9); the impulse is the
    # pendulum's (eq. 29: M ω (1 + e₀), ω = s₀ sqrt(g/l₀)) over the 10 mm × 10 mm patch,
    # applied so far by GN22's momentum rule Σ Δt ((1 − β₁) F₀ + β₁ F₁) (1e-12): on the
    # rising half of the triangle (peak P = 2I/T at T/2 = 1 ms) the trapezoidal I/2 plus
    # (β₁ − ½) Δt P. Serial only (the 3D model on 4 ranks: tests/test_threed.py).
    case = load_case("goda3d", ["calibration.enabled=false",
                                "bodies.mound.shear_modulus=2.247e6",
                                "time.end_time=0.001", "output.figures=false",
                                "output.field_interval=0", "output.checkpoint_interval=0",
                                f"output.directory=\"{folder / 'goda3d'}\""])
    built = case.build(COMM)
    summary = simulation.run(built.model, built.time, built.output,
                             extra_summary=built.extra, report=False)
    assert summary["finished"] and summary["dimension"] == 3
    volume = 0.205 * 0.202 * 0.205
    weight = 2314.0 * 9.81 * volume
    static = summary["static"]
    assert static["weight"] == pytest.approx(weight, rel=1e-12)
    assert static["contact_resultant"] == pytest.approx(weight, rel=1e-9)
    assert static["contact_area"] == pytest.approx(0.205 * 0.205, rel=1e-12)
    impact = summary["loads"]["impact"]
    assert impact["patch_area"] == pytest.approx(0.010 * 0.010, rel=1e-12)
    assert impact["impulse"] == pytest.approx(pendulum_impulse(5.5, 3.393, 0.25, 0.2),
                                              rel=1e-12)
    impulse, T, dt, β1 = impact["impulse"], 2e-3, 1e-4, 0.6
    assert impact["applied"]["impulse"][0] == pytest.approx(
        0.5 * impulse + (β1 - 0.5) * dt * 2 * impulse / T, rel=1e-12)
    assert summary["mesh"]["cells"] == {"caisson": 210, "mound": 822}
    # What holds it (summary.json's fixed): the flume's floor under the mound in x, y
    # and z (its 1.16 m base across the 0.205 m flume), the glass walls as rollers (u_z
    # on the mound's two faces across the flume: twice its cross-section, its volume
    # over the flume's width); the block's sides free (no group).
    fixed = summary["fixed"]
    assert list(fixed) == ["base", "mound_sides"]
    assert fixed["base"]["components"] == ["x", "y", "z"]
    assert fixed["base"]["bodies"]["mound"]["area"] == pytest.approx(1.16 * 0.205, rel=1e-12)
    assert fixed["mound_sides"]["components"] == ["z"]
    section = summary["mesh"]["bodies"]["mound"]["volume"] / 0.205
    assert fixed["mound_sides"]["bodies"] == {
        "mound": {"area": pytest.approx(2 * section, rel=1e-12)}}
