"""Failures that must end in one line, or in consistent outputs: a truncated mesh, a
static state that cannot be found (the bad case files of ``[initial]`` are in
tests/bad_cases, ``i*.toml``).
"""

from __future__ import annotations

import json
import pathlib
import sys

import gmsh
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater.meshes import gmsh_session

from breakwater import cli
from breakwater.common.errors import MeshError
from breakwater.config.runspec import OutputSpec, TimeSpec
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, ContactPair, Fixed, Material, SurfaceLoad
from breakwater.run import simulation

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from blocks import two_block_case, two_rectangles

COMM = MPI.COMM_WORLD


@pytest.fixture(scope="module")
def mesh_path(folder: pathlib.Path) -> pathlib.Path:
    return two_rectangles(folder / "whole.msh", COMM, a=(0.2, 0.05), b=(0.2, 0.05), h=0.025)


def _truncated(mesh_path: pathlib.Path, folder: pathlib.Path, section: str) -> pathlib.Path:
    """The mesh cut just before a section (``$Entities``, ``$Nodes``...) or at its end."""
    lines = mesh_path.read_text().splitlines(keepends=True)
    cut = next(i for i, line in enumerate(lines) if line.strip() == section)
    path = folder / f"cut_{section.strip('$')}.msh"
    if COMM.rank == 0:
        path.write_text("".join(lines[:cut + 1]))
    COMM.barrier()
    return path


# Cut after the physical names (dolfinx: "RuntimeError: No 'physical groups' in gmsh
# mesh"), after the entities (no nodes: an IndexError) and after the nodes (no cells).
SECTIONS = ["$EndPhysicalNames", "$EndEntities", "$EndNodes", "$Nodes", "$Elements"]


@pytest.mark.parametrize("section", SECTIONS)
def test_truncated_mesh_is_a_mesh_error(mesh_path, folder, section):
    path = _truncated(mesh_path, folder, section)
    with pytest.raises(MeshError, match="cannot read the mesh"):
        read_mesh(path, COMM)


@pytest.mark.parametrize("section", ["$EndPhysicalNames", "$EndEntities", "$EndNodes"])
def test_truncated_mesh_exit_2(mesh_path, folder, section, capsys):
    path = _truncated(mesh_path, folder, section)
    case = folder / f"truncated_{section.strip('$')}.toml"
    if COMM.rank == 0:
        case.write_text(two_block_case(path, 'name = "truncated"'))
    COMM.barrier()
    assert cli.main(["run", str(case), "--out", str(folder / "never"), "--quiet"]) == 2
    err = capsys.readouterr().err
    if COMM.rank == 0:
        assert err.count("\n") == 1 and "Traceback" not in err
        assert err.startswith(f"breakwater: error: mesh.source: {path}: cannot read the mesh")


def test_failed_static_state_report_and_summary(mesh_path, shared_dir, capsys):
    # No static state: a load at t = 0 pulls the block off its base (100 times its weight),
    # so no frictional (nor a held) equilibrium exists: an error naming [initial]
    # undeformed, the key that starts the run undeformed. Nothing of the run is written
    # but the summary, which says so and names no file that was not written; the report
    # has no "None" or "n/a" solver line (it had "(mean n/a, max None)"). (A gravity
    # pulling the block off, as here before, is refused before the run:
    # test_built_model.py.)
    material = Material(2000.0, 0.25, young_modulus=1e9)
    weight = 2000.0 * 0.2 * 0.05 * 9.81  # N/m, block a: 0.2 × 0.05 m
    model = ContactModel(read_mesh(mesh_path, COMM), [Body("a", material), Body("b", material)],
                         [ContactPair("interface", "a", "b", penalty=1e12, friction=0.3)],
                         [Fixed("b_bottom")],
                         [SurfaceLoad("a_top", (0.0, 100.0 * weight / 0.2), lambda t: 1.0)],
                         gravity=(0.0, -9.81))
    out = shared_dir / "failed"
    with pytest.raises(simulation.SimulationFailed,
                       match=r"no static equilibrium .*Newton did not converge.*\[initial\] "
                             "undeformed = true"):
        simulation.run(model, TimeSpec(dt=1e-4, end_time=1e-3),
                       OutputSpec(out, figures=False, progress=False))
    report = capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and "[initial] undeformed" in summary["error"]
    assert summary["outputs"]["static"] is None and summary["outputs"]["history"] is None
    assert not (out / "static.npz").exists() and not (out / "history.csv").exists()
    if COMM.rank == 0:
        assert "solver: no time step taken" in report
        assert "None" not in report and "mean n/a" not in report


def _rectangle_mesh(path: pathlib.Path, name: str, y0: float, first_tag: int,
                    entity: int) -> None:
    """A 0.2 × 0.05 rectangle at height y0, meshed alone (cells ``name``, gmsh Surface
    ``entity``), its node and element tags from ``first_tag`` (rank 0)."""
    with gmsh_session():
        occ = gmsh.model.occ
        surface = occ.addRectangle(-0.1, y0, 0.0, 0.2, 0.05, tag=entity)
        occ.synchronize()
        gmsh.model.addPhysicalGroup(2, [surface], first_tag, name)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.025)
        gmsh.model.mesh.generate(2)
        gmsh.option.setNumber("Mesh.FirstNodeTag", first_tag)
        gmsh.option.setNumber("Mesh.FirstElementTag", first_tag)
        gmsh.model.mesh.renumberNodes()
        gmsh.model.mesh.renumberElements()
        gmsh.write(str(path))


def _merged(folder: pathlib.Path, name: str, second_tag: int, second_entity: int
            ) -> pathlib.Path:
    """Two rectangles meshed apart (``a`` on ``b``) and merged into one ``.msh`` by gmsh:
    ``a``'s node and element tags from ``second_tag``, its surface ``second_entity``
    (``b``'s: 1 and 1)."""
    path = folder / f"{name}.msh"
    if COMM.rank == 0:
        _rectangle_mesh(folder / f"{name}_b.msh", "b", 0.0, 1, 1)
        _rectangle_mesh(folder / f"{name}_a.msh", "a", 0.05, second_tag, second_entity)
        with gmsh_session():
            gmsh.merge(str(folder / f"{name}_b.msh"))
            gmsh.merge(str(folder / f"{name}_a.msh"))
            gmsh.write(str(path))
    COMM.barrier()
    return path


def test_meshes_merged_with_repeated_node_tags_are_refused(folder):
    # Each body meshed alone numbers its nodes from 1; gmsh merges the two files keeping
    # both sets, so tags repeat and dolfinx joined cells to the other body's nodes (the
    # run refused "cells overlap" or "curved cell folds", blaming the mesh's shape).
    with pytest.raises(MeshError, match=r"node tags appear twice .*Mesh\.FirstNodeTag"):
        read_mesh(_merged(folder, "merged_repeated", 1, 2), COMM)


def test_meshes_merged_with_repeated_entity_tags_are_refused(folder):
    # Both files' rectangles are gmsh Surface 1: the merge joins them into one entity in
    # both cell groups (dolfinx: "All cells are expected to be tagged once", a traceback).
    with pytest.raises(MeshError, match=r"Surface 1 are in both 'b' and 'a'"):
        read_mesh(_merged(folder, "merged_entities", 100000, 1), COMM)


def test_meshes_merged_with_distinct_tags_read(folder):
    # The same merge with the second body's tags from 100000 (gmsh's Mesh.FirstNodeTag):
    # legal, but tags with a gap made dolfinx's reader fail (AssertionError). Read, each
    # body's area is its rectangle's, 0.2 × 0.05 = 0.01 m² (to round-off).
    import dolfinx
    import ufl

    data = read_mesh(_merged(folder, "merged_apart", 100000, 2), COMM)
    for name in ("a", "b"):
        dx = ufl.Measure("dx", domain=data.mesh, subdomain_data=data.cell_tags)
        area = dolfinx.fem.assemble_scalar(dolfinx.fem.form(
            1.0 * dx(data.physical_groups[name].tag)))
        assert COMM.allreduce(area) == pytest.approx(0.01, rel=1e-12)
