"""The bodies' mean rotation (``<body>_rotation``) and the small-rotation warning.

- The column of a linear field u = c + φ e_z × x (the linear model's rigid rotation) is
  φ exactly, in 2D (quadratic quadrilaterals) and in 3D (quadratic hexahedra and
  tetrahedra, the rotation about an arbitrary axis: |φ|): the elements hold a linear
  field, and ∫ ½ curl u dx / V of it is φ; round-off of the assembled vector, 1e-12.
  A translation reads 0.
- :func:`breakwater.outputs.rotation.rotation_warning`: a body past 0.05 rad is named
  with its rotation in degrees; 0.049 rad is not warned; the Goda caisson's rocking
  (its uplift of 2.4 mm over the 0.205 m base: ≈ 0.012 rad) is within the limit.
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from blocks3d import block_pair
from dolfinx import fem

from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Material
from breakwater.outputs.rotation import Rotations, rotation_warning

COMM = MPI.COMM_WORLD


def _model(path: pathlib.Path) -> ContactModel:
    mat = Material(2000.0, 0.25, young_modulus=1e9)
    return ContactModel(read_mesh(path, COMM), [Body("a", mat), Body("b", mat)])


def _linear(model: ContactModel, c: np.ndarray, φ: np.ndarray) -> list[fem.Function]:
    """u = c + φ × x on every body (2D: φ = (0, 0, φ_z))."""
    d = model.gdim
    out = []
    for body in model.bodies:
        u = fem.Function(body.V)

        def field(x: np.ndarray) -> np.ndarray:
            rot = np.cross(φ, x.T).T  # (3, m)
            return c[:d, None] + rot[:d]

        u.interpolate(field)
        out.append(u)
    return out


@pytest.mark.parametrize("kind", ["2d", "hexahedra", "tetrahedra"])
def test_rotation_of_a_linear_field(folder: pathlib.Path, kind: str) -> None:
    three = kind != "2d"
    path = block_pair(folder / f"rot_{kind}.msh", COMM, 0.3, (0.1, 0.2), 0.05,
                      thickness=0.15 if three else None, tetrahedra=kind == "tetrahedra")
    model = _model(path)
    rotations = Rotations(model)
    assert rotations.columns == ["a_rotation", "b_rotation"]
    φ = np.array([0.02, -0.05, 0.03]) if three else np.array([0.0, 0.0, -0.07])
    c = np.array([0.4, -0.1, 0.2])
    values = rotations.values(_linear(model, c, φ))
    expected = float(np.linalg.norm(φ)) if three else φ[2]
    for name in ("a_rotation", "b_rotation"):
        assert values[name] == pytest.approx(expected, abs=1e-12)
    moved = rotations.values(_linear(model, c, np.zeros(3)))
    assert all(abs(v) < 1e-14 for v in moved.values())


def test_rotation_warning() -> None:
    def dynamic(ω: float) -> dict:
        return {"max_rotation": {"mound": {"value": 1e-4, "time": 0.05},
                                 "cylinder": {"value": ω, "time": 0.2}}}

    line = rotation_warning(dynamic(0.81))
    assert line is not None and "\n" not in line
    assert line.startswith("body 'cylinder' rotates by 0.81 rad (46.4°) at t = 0.2 s")
    assert "not reliable" in line
    assert rotation_warning(dynamic(0.049)) is None
    assert rotation_warning(dynamic(2.44e-3 / 0.205)) is None
    assert rotation_warning({}) is None


def test_largest_reads_the_columns_whole(monkeypatch: pytest.MonkeyPatch) -> None:
    # The largest |ω| and its (first) time, read from whole columns: the summary written
    # at every checkpoint looped over the rows in Python (HistoryRows.__getitem__, a
    # dict per row), half of a run's time with a checkpoint every step (profiled: 69 s
    # of 139 s over 3000 steps; quadratic in the steps). Reference: numpy's argmax.
    from breakwater.outputs.historyrows import HistoryRows
    from breakwater.outputs.rotation import largest

    rng = np.random.default_rng(3)
    data = np.column_stack([np.arange(5000) * 1e-4, rng.normal(size=(5000, 2))])
    data[[700, 900], 2] = [-9.0, 9.0]  # a tie of |ω|: the first counts
    rows = HistoryRows(("t", "a_rotation", "b_rotation"), data)

    def per_row(self: HistoryRows, *index: int | slice) -> None:
        raise AssertionError("a row read one by one")

    monkeypatch.setattr(HistoryRows, "__getitem__", per_row)
    monkeypatch.setattr(HistoryRows, "__iter__", per_row, raising=False)
    got = largest(rows, ["a", "b"])
    assert got["b"] == {"value": 9.0, "time": data[700, 0]}
    k = int(np.argmax(np.abs(data[:, 1])))
    assert got["a"] == {"value": abs(data[k, 1]), "time": data[k, 0]}
    monkeypatch.undo()
    assert largest([rows[i] for i in range(len(rows))], ["a", "b"]) == got  # plain rows
