"""The nodal stresses of the snapshots (``static.npz``): the same on any number of ranks.

The stress of P2 displacements is discontinuous between cells; the snapshot's value
at a vertex was the value of one of its cells, whichever interpolation met last (von
Mises up to 30 % apart between 1 and 2 ranks at some nodes, found by a user-path
test). Now it is the volume-weighted average of the cells at the vertex
(:mod:`breakwater.outputs.vertexaverage`).

The field: the P2 interpolant of a smooth displacement whose stress is not piecewise
linear (u = 1e-3 (sin 3x cos 2y, x³y) m on two blocks, an unstructured mesh), so the
cells' stresses differ at a shared vertex (by ~1 % of the stress here). Checked:

- against the definition f̄(v) = Σ_c |c| f_c(v) / Σ_c |c|, computed here from the
  fields evaluated at the vertex in each cell (``Function.eval``: a path other than the
  interpolation) and the triangles' areas from their vertices (shoelace formula);
- on 2 ranks: the distributed mesh's snapshot against a serial one (COMM_SELF) of the
  same mesh file, node by node (by coordinates), to round-off (1e-12 of the largest
  value: sums of a few cells' terms in another order).
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
from blocks import two_rectangles
from dolfinx import fem
from mpi4py import MPI

from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Fixed, Material
from breakwater.outputs.writers import BodyFields

COMM = MPI.COMM_WORLD
FIELDS = ("von_mises", "stress_yy", "stress_xx", "stress_xy", "stress_zz")


@pytest.fixture(scope="module")
def mesh_path(folder: pathlib.Path) -> pathlib.Path:
    return two_rectangles(folder / "blocks.msh", COMM, (1.0, 0.5), (2.0, 0.5), 0.2,
                          structured=False)


def _snapshot(path: pathlib.Path, comm: MPI.Comm) -> tuple[list[BodyFields], list[dict | None]]:
    material = Material(2000.0, 0.25, young_modulus=1e9)
    model = ContactModel(read_mesh(path, comm), [Body("a", material), Body("b", material)],
                         fixed=[Fixed("b_bottom")])
    fields, nodal = [], []
    for i, body in enumerate(model.bodies):
        u = fem.Function(body.V)
        u.interpolate(lambda x: 1e-3 * np.vstack([np.sin(3 * x[0]) * np.cos(2 * x[1]),
                                                  x[0] ** 3 * x[1]]))
        f = BodyFields(model, i)
        f.update(u)
        fields.append(f)
        nodal.append(f.nodal())
    return fields, nodal


def _by_coordinates(data: dict) -> dict[str, np.ndarray]:
    order = np.lexsort((data["x"][:, 1], data["x"][:, 0]))
    return {k: np.asarray(data[k])[order] for k in ("x", *FIELDS)}


def _definition(f: BodyFields) -> dict[str, np.ndarray]:
    """Σ_c |c| f_c(v) / Σ_c |c| at every vertex, from Function.eval in each cell (serial)."""
    sub = f.stress.function_space.mesh
    x = sub.geometry.x
    cells = sub.geometry.dofmaps[0][:, :3]  # the triangles' vertices (first in the dofmap)
    p = x[cells]
    area = 0.5 * np.abs((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
                        - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
    points = p.reshape(-1, 3)
    owner = np.repeat(np.arange(len(cells), dtype=np.int32), 3)
    values = {"von_mises": f.von_mises.eval(points, owner)[:, 0],
              "stress_yy": f.stress_yy.eval(points, owner)[:, 0]}
    σ = f.stress.eval(points, owner).reshape(-1, 3, 3)
    values |= {"stress_xx": σ[:, 0, 0], "stress_xy": σ[:, 0, 1], "stress_zz": σ[:, 2, 2]}
    vertex = cells.ravel()
    weight = np.bincount(vertex, np.repeat(area, 3), minlength=len(x))
    out = {"x": x[:, :2]}
    for k, v in values.items():
        out[k] = np.bincount(vertex, np.repeat(area, 3) * v, minlength=len(x)) / weight
    used = weight > 0
    return _by_coordinates({k: a[used] for k, a in out.items()})


def test_nodal_stresses_are_the_vertex_averages(mesh_path: pathlib.Path) -> None:
    fields, nodal = _snapshot(mesh_path, MPI.COMM_SELF)
    for f, data in zip(fields, nodal, strict=True):
        got, want = _by_coordinates(data), _definition(f)
        np.testing.assert_allclose(got["x"], want["x"], atol=1e-12)
        for k in FIELDS:
            scale = np.abs(want[k]).max()
            # the cells differ at a vertex: a single cell's value is not the average
            assert scale > 0
            np.testing.assert_allclose(got[k], want[k], rtol=0, atol=1e-12 * scale,
                                       err_msg=f"{f.name}_{k}")


@pytest.mark.skipif(COMM.size == 1, reason="the partition's effect needs 2 ranks")
def test_nodal_stresses_do_not_depend_on_the_partition(mesh_path: pathlib.Path) -> None:
    _, distributed = _snapshot(mesh_path, COMM)
    serial = _snapshot(mesh_path, MPI.COMM_SELF)[1] if COMM.rank == 0 else None
    if COMM.rank != 0:
        assert distributed == [None, None]
        return
    assert serial is not None
    for a, b in zip(distributed, serial, strict=True):
        got, want = _by_coordinates(a), _by_coordinates(b)
        np.testing.assert_allclose(got["x"], want["x"], atol=1e-12)
        for k in FIELDS:
            np.testing.assert_allclose(got[k], want[k], rtol=0,
                                       atol=1e-12 * np.abs(want[k]).max(), err_msg=k)
