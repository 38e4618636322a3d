"""The warnings of a case's sizes and units (:mod:`breakwater.outputs.bodysizes`).

A run whose units are off by 1000 is consistent and silent; these lines are its only
trace. The run-level checks are in ``tests/bad_cases/run/`` (u3-u6).
"""

from __future__ import annotations

import json
import logging
import pathlib

import pytest
from blocks import two_rectangles
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)
from breakwater.config.runspec import OutputSpec, TimeSpec
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, ContactPair, Fixed, Material
from breakwater.outputs.bodysizes import DENSITY_RANGE, density_warnings, gravity_warning
from breakwater.run.simulation import run


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


def test_a_model_built_in_python_is_checked_as_a_case_file(
        shared_dir: pathlib.Path, caplog: pytest.LogCaptureFixture) -> None:
    """run() on a model built in Python: its density in g/cm³ is warned about and the
    summary's ``mesh`` gives the bodies' sizes and the line, as a case file's build does
    (before: only a case file's units were checked; the Python path ran silently); its
    ``gravity`` is the one the run applied."""
    comm = MPI.COMM_WORLD
    mesh = two_rectangles(shared_dir / "blocks.msh", comm, a=(0.2, 0.1), b=(0.4, 0.1),
                          h=0.05)
    model = ContactModel(read_mesh(mesh, comm),
                         [Body("a", Material(2.4, 0.2, shear_modulus=2e9)),
                          Body("b", Material(2000.0, 0.25, shear_modulus=3e6))],
                         [ContactPair("interface", "a", "b", 5e8)], [Fixed("b_bottom")],
                         gravity=(0.0, -9.81))
    model.gravity = (0.0, -9.80665)  # set after the build: the summary says this one
    with caplog.at_level(logging.WARNING, logger="breakwater"):
        run(model, TimeSpec(dt=1e-3, end_time=2e-3),
            OutputSpec(directory=shared_dir / "out", figures=False), report=False)
    line = density_warnings({"a": 2.4})[0]
    summary = json.loads((shared_dir / "out" / "summary.json").read_text())
    assert summary["mesh"]["warnings"] == [line]
    assert summary["gravity"] == [0.0, -9.80665]
    # The block's mass per metre: ρ × its area (0.2 × 0.1 m), to round-off.
    assert summary["mesh"]["bodies"]["a"]["mass"] == pytest.approx(2.4 * 0.02, rel=1e-12)
    if comm.rank == 0:  # rank 0 prints
        assert [r.getMessage() for r in caplog.records].count(line) == 1
