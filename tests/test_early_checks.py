"""Inputs refused before the calibration: what the calibrated modulus cannot change.

A goda3d case with gravity typed upwards calibrated the mound (24 s on 2 cores) before
``bodies.caisson: nothing beneath it`` refused it; the model's checks now run on the
model at the calibration's initial guess first (:func:`breakwater.casefile.build.build`).
The calibration's solve (``calibrate_shear_modulus``, which ``python -m breakwater
calibrate`` and a run reach through :func:`breakwater.casefile.build.calibrate`) is
replaced by one that fails the test: a refusal must come before it. A free rigid mode is
refused before a calibration whatever the initial state: its stiffness is singular.
"""

from __future__ import annotations

import pathlib

import pytest
from mpi4py import MPI

from breakwater.casefile import build
from breakwater.casefile.case import load_case
from breakwater.common.errors import CaseError
from breakwater.statics import calibrate

COMM = MPI.COMM_WORLD


def _never(*args: object, **kwargs: object) -> None:
    raise AssertionError("calibrated before the case was refused")


@pytest.mark.parametrize(("overrides", "phrase"), [
    (["gravity=[0.0, 9.81, 0.0]"], "bodies.caisson: nothing beneath it: gravity (0.0, 9.81, 0.0)"),
    (["fixed.base.components=[0]"], "leave the rigid translation along y"),
    (["fixed.base.components=[0, 1]", "fixed.mound_sides.components=[0]"],
     "leave the rigid translation along z free"),
    # Undeformed, no static state is needed, but the calibration's stiffness is singular.
    (["initial.undeformed=true", "fixed.base.components=[0, 1]",
      "fixed.mound_sides.components=[0]"],
     "translation along z free: hold z on a [fixed] group (add 2 to fixed.base.components) "
     "(nothing holds it there, and the stiffness the calibration solves, its interfaces "
     "bonded, is singular)"),
    # Started undeformed, gravity up has no static state to spoil: the run calibrates.
    (["initial.undeformed=true", "gravity=[0.0, 9.81, 0.0]"], None),
], ids=["gravity_up", "base_rollers_x", "walls_rollers_x", "undeformed_walls_rollers_x",
        "undeformed"])
def test_refused_before_calibration(overrides: list[str], phrase: str | None,
                                    shared_dir: pathlib.Path,
                                    monkeypatch: pytest.MonkeyPatch) -> None:
    case = load_case("goda3d", [*overrides, f"output.directory={shared_dir / 'out'}"])
    assert case.calibration.enabled
    monkeypatch.setattr(calibrate, "calibrate_shear_modulus", _never)
    if phrase is None:  # nothing to refuse: the calibration is reached
        with pytest.raises(AssertionError, match="calibrated before"):
            build.build(case, COMM)
        return
    with pytest.raises(CaseError) as e:
        build.build(case, COMM)
    assert phrase in str(e.value) and "\n" not in str(e.value)
