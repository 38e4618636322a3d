"""The figures' section of a 3D model (breakwater.outputs.section).

A hexahedron is cut along its edges, where its Q1 values are linear (exact), the
polygon fanned around its centroid; the section's plane is the row of the first pair's
interface nodes nearest the interface's mid z (the static pressure figure's row).
Before: hexahedra were split into six tetrahedra around a diagonal (not exact for Q1,
not mirror-symmetric: 20 % of the largest σ_yy off the mirror image on a centred
block), and the plane was the model's mid-plane, which missed a block standing off the
middle of its base (the run's figures ended in a traceback). The summary's static edge
and centre pressures on a tetrahedral interface are read on the facets cut by that
line (before: at the few nodes at the z nearest it, which did not reach the ends).
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, ContactPair, Material
from breakwater.outputs.section import section, section_plane
from breakwater.outputs.writers import BodyFields

COMM = MPI.COMM_WORLD


def test_trilinear_field_is_exact_on_a_hexahedron_section() -> None:
    # f = x y z is Q1 on the unit cube: linear along its edges, and on the section
    # z = 0.5 the bilinear x y / 2, whose value at the square's centre is the mean of
    # its corners'. The diagonal's tetrahedra gave f = 0.5 at (0.5, 0.5), not 0.125.
    corners = np.array([[k & 1, k >> 1 & 1, k >> 2 & 1] for k in range(8)], float)
    f = corners[:, 0] * corners[:, 1] * corners[:, 2]
    xy, tri, values = section(corners, np.arange(8)[None, :], {"f": f}, 0.5)
    assert np.allclose(values["f"], 0.5 * xy[:, 0] * xy[:, 1], atol=1e-15)
    p = xy[tri]
    area = 0.5 * np.abs((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
                        - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
    assert area.sum() == pytest.approx(1.0, rel=1e-14)


def _off_centre_block(path: pathlib.Path) -> pathlib.Path:
    """Linear hexahedra: a 0.4 x 0.3 x 0.15 block at z in [0, 0.15] on a 1 x 0.2 x 0.4
    base (conforming, OCC boxes fragmented); groups block, base, interface."""
    import gmsh
    from breakwater.meshes import gmsh_session

    from breakwater.common.parallel import on_rank_zero

    def build() -> None:
        with gmsh_session():
            occ = gmsh.model.occ
            xs, zs = (0.0, 0.3, 0.7, 1.0), (0.0, 0.15, 0.4)
            for i in range(3):
                for j in range(2):
                    occ.addBox(xs[i], 0, zs[j], xs[i + 1] - xs[i], 0.2, zs[j + 1] - zs[j])
            occ.addBox(0.3, 0.2, 0.0, 0.4, 0.3, 0.15)
            occ.fragment([(3, k) for k in range(1, 7)], [(3, 7)])
            occ.synchronize()
            volumes = [t for _, t in gmsh.model.getEntities(3)]
            up = [t for t in volumes if occ.getCenterOfMass(3, t)[1] > 0.2]
            gmsh.model.addPhysicalGroup(3, up, name="block")
            gmsh.model.addPhysicalGroup(3, [t for t in volumes if t not in up], name="base")
            top = [t for _, t in gmsh.model.getEntities(2)
                   if np.allclose(occ.getCenterOfMass(2, t), (0.5, 0.2, 0.075))]
            gmsh.model.addPhysicalGroup(2, top, name="interface")
            gmsh.option.setNumber("Mesh.MeshSizeMax", 0.1)
            gmsh.model.mesh.setTransfiniteAutomatic(recombine=True)
            gmsh.model.mesh.generate(3)
            gmsh.write(str(path))

    on_rank_zero(COMM, build)
    return pathlib.Path(COMM.bcast(str(path), root=0))


def test_section_cuts_a_block_off_the_middle_of_its_base(folder: pathlib.Path) -> None:
    # The interface spans z in [0, 0.15] in three cells (0.1 m elements): its node rows
    # at 0, 0.05, 0.1, 0.15; the model's mid-plane z = 0.2 misses the block. The
    # section is at the row nearest 0.075 (0.05 and 0.1 tie to rounding) and cuts both
    # bodies: the block's section is its 0.4 x 0.3 rectangle, the base's 1 x 0.2.
    mat = Material(2400.0, 0.2, young_modulus=3e10)
    model = ContactModel(read_mesh(_off_centre_block(folder / "off.msh"), COMM),
                         [Body("block", mat), Body("base", mat)],
                         [ContactPair("interface", "block", "base", penalty=1e12)])
    assert min(abs(section_plane(model) - z) for z in (0.05, 0.1)) < 1e-12
    for k, area in ((0, 0.4 * 0.3), (1, 1.0 * 0.2)):
        data = BodyFields(model, k).nodal()
        if COMM.rank == 0:
            assert data is not None
            p = data["x"][data["triangles"]]
            a = 0.5 * np.abs((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
                             - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
            assert a.sum() == pytest.approx(area, rel=1e-12)


def _tet_block(path: pathlib.Path) -> pathlib.Path:
    """Linear tetrahedra (unstructured): a 0.4 x 0.3 x 0.2 block centred on a
    1 x 0.2 x 0.4 base; groups block, base, interface."""
    import gmsh
    from breakwater.meshes import gmsh_session

    from breakwater.common.parallel import on_rank_zero

    def build() -> None:
        with gmsh_session():
            occ = gmsh.model.occ
            occ.addBox(0.0, 0.0, 0.0, 1.0, 0.2, 0.4)
            occ.addBox(0.3, 0.2, 0.1, 0.4, 0.3, 0.2)
            occ.fragment([(3, 1)], [(3, 2)])
            occ.synchronize()
            gmsh.model.addPhysicalGroup(3, [2], name="block")
            gmsh.model.addPhysicalGroup(3, [1], name="base")
            face = [t for _, t in gmsh.model.getEntities(2)  # (not the base's top)
                    if np.allclose(gmsh.model.getBoundingBox(2, t),
                                   (0.3, 0.2, 0.1, 0.7, 0.2, 0.3), atol=1e-7)]
            gmsh.model.addPhysicalGroup(2, face, name="interface")
            bottom = [t for _, t in gmsh.model.getEntities(2)
                      if abs(gmsh.model.getBoundingBox(2, t)[4]) < 1e-6]
            gmsh.model.addPhysicalGroup(2, bottom, name="base_bottom")
            gmsh.option.setNumber("Mesh.MeshSizeMax", 0.07)
            gmsh.model.mesh.generate(3)
            gmsh.write(str(path))

    on_rank_zero(COMM, build)
    return pathlib.Path(COMM.bcast(str(path), root=0))


def test_static_pressure_row_of_a_tetrahedral_interface(folder: pathlib.Path) -> None:
    # The summary's edge and centre pressures are read along z = the interface's mid z
    # (0.2). Unstructured triangles have no node row there: the nodes at the z nearest
    # it did not reach the block's ends x = 0.3, 0.7. The facets cut by the plane give
    # the whole line, and a P1 pressure p = 1000 + 100 x + 10 z exactly on it.
    from breakwater.contact.conforming import interface_nodes
    from breakwater.outputs.staticsummary import static_summary, triangle_row

    mat = Material(2400.0, 0.2, young_modulus=3e10)
    model = ContactModel(read_mesh(_tet_block(folder / "tets.msh"), COMM),
                         [Body("block", mat), Body("base", mat)],
                         [ContactPair("interface", "block", "base", penalty=1e12)],
                         degree=1)
    x = interface_nodes(model)[0].x

    def f(p: np.ndarray) -> np.ndarray:
        return 1000.0 + 100.0 * p[..., 0] + 10.0 * p[..., 2]

    cut = triangle_row(model, "interface", x, f(x))
    assert cut is not None
    points, p = cut
    assert np.allclose(points[:, 1:], [0.2, 0.2], atol=1e-12)
    assert points[0, 0] == pytest.approx(0.3, abs=1e-12)
    assert points[-1, 0] == pytest.approx(0.7, abs=1e-12)
    assert np.allclose(p, f(points), rtol=1e-12)
    # The summary's values: f at (0.3, 0.2), (0.7, 0.2), (0.5, 0.2) (x, z).
    static = static_summary(model, {"interface_contact_length": 0.08,
                                    "interface_normal_force": 80.0},
                            {"contact_interface_x": x, "contact_interface_pressure": f(x)}, 0)
    assert np.allclose(static["edge_pressures"], [1032.0, 1072.0], rtol=1e-12)
    assert static["center_pressure"] == pytest.approx(1052.0, rel=1e-12)


def test_static_npz_holds_the_tetrahedral_row(folder: pathlib.Path) -> None:
    # A run's static.npz holds that cut (contact_<pair>_row_*), the pressure figure's
    # line: from the block's front to its rear, its ends the summary's edge pressures.
    from breakwater.config.runspec import OutputSpec, TimeSpec
    from breakwater.model.model import Fixed
    from breakwater.run import simulation

    mat = Material(2400.0, 0.2, young_modulus=3e10)
    model = ContactModel(read_mesh(_tet_block(folder / "tets_run.msh"), COMM),
                         [Body("block", mat), Body("base", mat)],
                         [ContactPair("interface", "block", "base", penalty=1e12)],
                         [Fixed("base_bottom")], gravity=(0.0, -9.81, 0.0), degree=1)
    out = folder / "tets_run"
    summary = simulation.run(model, TimeSpec(dt=1e-3, end_time=2e-3),
                             OutputSpec(out, field_interval=0, figures=False,
                                        progress=False), report=False)
    if COMM.rank == 0:
        with np.load(out / "static.npz") as data:
            x, p = data["contact_interface_row_x"], data["contact_interface_row_pressure"]
        assert x[0, 0] == pytest.approx(0.3, abs=1e-12)
        assert x[-1, 0] == pytest.approx(0.7, abs=1e-12)
        assert np.allclose(summary["static"]["edge_pressures"], [p[0], p[-1]], rtol=1e-12)


def test_pressure_figure_draws_the_tetrahedral_row(tmp_path: pathlib.Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    # static.npz of a tetrahedral interface holds the facets' cut (contact_<pair>_row_*,
    # written by breakwater.run.begin): the figure draws it, from end to end, not the
    # nodes at the z nearest the middle (here two, at x = 0.3 and 0.64).
    from breakwater.outputs import figures

    drawn = {}
    monkeypatch.setattr(figures, "_save", lambda fig, path: drawn.setdefault("fig", fig))
    nodes = np.array([[0.3, 0.2, 0.2], [0.64, 0.2, 0.2], [0.5, 0.2, 0.1]])
    row = np.array([[0.3, 0.2, 0.2], [0.5, 0.2, 0.2], [0.7, 0.2, 0.2]])
    np.savez(tmp_path / "static.npz", contacts=np.array(["interface"]),
             contact_interface_x=nodes, contact_interface_pressure=np.array([9.0, 6.0, 5.0]),
             contact_interface_row_x=row, contact_interface_row_pressure=np.array([9.0, 5.5, 9.1]))
    with np.load(tmp_path / "static.npz") as data:
        figures._static_pressure(data, {}, tmp_path / "p.png")
    line = drawn["fig"].axes[0].lines[0]
    assert np.allclose(line.get_xdata(), [0.3, 0.5, 0.7])
    assert np.allclose(line.get_ydata(), [9.0, 5.5, 9.1])
