"""The regularisation velocity χ against the run's speed scale and its round-off
(:mod:`breakwater.casefile.frictionchecks`; the runs: tests/bad_cases/run/v1, v2).

The scales, from the module's argument: V = |g| T + max |v₀| (the speed of a body
falling freely for the whole run) and the round-off of a GN22 step's velocities
δv = 2β₁ ε δ/(β₂ Δt) (∂v₁/∂u₁ = 2β₁/(β₂Δt), ε = 2⁻⁵² the double's round-off, δ = ρ|g|H/ε_n
the penalty's static penetration under the slave's weight). Warned: χ ≥ V, χ < MARGIN δv.
"""

from __future__ import annotations

import json
import logging
import pathlib

import pytest
from blocks import two_rectangles
from mpi4py import MPI

from breakwater.casefile.case import load_case
from breakwater.casefile.frictionchecks import (
    MARGIN,
    case_warnings,
    regularisation_warning,
    speed_scale,
    velocity_roundoff,
)
from breakwater.config.runspec import OutputSpec, TimeSpec
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, ContactPair, Fixed, Material
from breakwater.run.simulation import run

EPS = 2.220446049250313e-16  # numpy.finfo(float).eps
# The Goda case's bodies (breakwater/cases/goda.toml): the caisson 0.205 m wide, 0.202 m
# high; the mound 1.16 m wide (0.4 m crest, 1:2 slopes over 0.19 m), 0.19 m high.
GODA_SIZES = {"caisson": {"extent": [0.205, 0.202]}, "mound": {"extent": [1.16, 0.19]}}


def test_the_scales() -> None:
    assert speed_scale(9.81, 0.15) == pytest.approx(1.4715, rel=1e-12)
    assert speed_scale(9.81, 0.1, 20.0) == pytest.approx(20.981, rel=1e-12)
    # Goda: δ = 2314·9.81·0.202/5e8 = 9.17e-6 m, Δt = 1e-4 s, β = (0.6, 0.605).
    δ = 2314.0 * 9.81 * 0.202 / 5e8
    assert velocity_roundoff(δ, 1e-4, 0.6, 0.605) == pytest.approx(
        2 * 0.6 * EPS * δ / (0.605 * 1e-4), rel=1e-12)
    assert velocity_roundoff(δ, 1e-4, 0.6, 0.605) == pytest.approx(4.04e-17, rel=1e-3)


def test_the_thresholds() -> None:
    V, δv = 1.47, 4.0e-17
    assert regularisation_warning("c", 1e-10, 0.65, V, δv) is None  # the paper's χ
    assert regularisation_warning("c", 0.99 * V, 0.65, V, δv) is None
    above = regularisation_warning("c", V, 0.65, V, δv)
    assert above is not None and above.startswith("contact.c.regularisation = 1.47 m/s")
    assert "1e-10 m/s" in above and "\n" not in above
    assert regularisation_warning("c", 1.01 * MARGIN * δv, 0.65, V, δv) is None
    below = regularisation_warning("c", 0.99 * MARGIN * δv, 0.65, V, δv)
    assert below is not None and "set it to 1e-10 m/s or more" in below
    # A round-off above the paper's χ: the advice is the next power of ten above 10 MARGIN δv.
    worse = regularisation_warning("c", 1e-10, 0.65, V, 3e-14)
    assert worse is not None and "set it to 1e-08 m/s or more" in worse
    # No friction: χ plays no part. No gravity nor initial speed (V = 0), δ = 0: unchecked.
    assert regularisation_warning("c", 1e6, 0.0, V, δv) is None
    assert regularisation_warning("c", 1e-30, 0.0, V, δv) is None
    assert regularisation_warning("c", 1e6, 0.65, 0.0, 0.0) is None


def test_goda_warns_only_at_the_extremes() -> None:
    """The built-in case (χ = 1e-10 m/s) is not warned about; χ = 1e6 m/s (friction a weak
    dashpot, ran without a word) and 1e-30 m/s (failed its first step after 226 s, no
    hint) are, in one line each naming the key."""
    assert case_warnings(load_case(None), GODA_SIZES) == []
    for chi, phrase in ((1e6, "is not below the run's speed scale V = 1.47 m/s"),
                        (1e-30, "is below 10000 times the round-off of the slip velocities, "
                                "4e-17 m/s")):
        lines = case_warnings(load_case(None, [f"contact.interface.regularisation={chi}"]),
                              GODA_SIZES)
        assert len(lines) == 1 and phrase in lines[0], lines
        assert lines[0].startswith("contact.interface.regularisation = ")


def test_a_model_built_in_python_is_checked(shared_dir: pathlib.Path,
                                            caplog: pytest.LogCaptureFixture) -> None:
    """run() on a model built in Python with χ = 1000 m/s, far above V = |g| T = 0.0196
    m/s: the line is logged once and kept in the summary's ``mesh.warnings``, as a case
    file's run does (before 2026-11-29 only a case file's build checked χ: the model ran
    without a word)."""
    comm = MPI.COMM_WORLD
    mesh = two_rectangles(shared_dir / "blocks.msh", comm, a=(0.2, 0.1), b=(0.4, 0.1),
                          h=0.05)
    model = ContactModel(read_mesh(mesh, comm),
                         [Body("a", Material(2400.0, 0.2, shear_modulus=2e9)),
                          Body("b", Material(2000.0, 0.25, shear_modulus=3e6))],
                         [ContactPair("interface", "a", "b", 5e8, friction=0.6,
                                      regularisation=1e3)], [Fixed("b_bottom")],
                         gravity=(0.0, -9.81))
    line = regularisation_warning("interface", 1e3, 0.6, speed_scale(9.81, 2e-3), 0.0)
    assert line is not None and "V = 0.0196 m/s" in line
    with caplog.at_level(logging.WARNING, logger="breakwater"):
        run(model, TimeSpec(dt=1e-3, end_time=2e-3),
            OutputSpec(directory=shared_dir / "out", figures=False), report=False)
    summary = json.loads((shared_dir / "out" / "summary.json").read_text())
    assert summary["mesh"]["warnings"] == [line]
    if comm.rank == 0:  # rank 0 prints
        assert [r.getMessage() for r in caplog.records].count(line) == 1
