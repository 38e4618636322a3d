"""Meshes made elsewhere: the block-on-base mesh as other tools and options write it.

Each is either read to the same bodies as gmsh's own file (the areas 0.2 × 0.1 and
0.4 × 0.1 m², to round-off: the cells are straight and tile the rectangles) or refused
in one line (a :class:`MeshError` naming the file and what to do). The meshes are made
in the tests with gmsh and meshio (a few hundred cells).
"""

from __future__ import annotations

import logging
import math
import pathlib
import re
from collections.abc import Callable

import gmsh
import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
import dolfinx
import ufl

from breakwater.common.errors import MeshError
from breakwater.common.gmshtools import GroupNameError, gmsh_session, physical_groups
from breakwater.common.parallel import on_rank_zero
from breakwater.model.mesh import group_tag, read_mesh

COMM = MPI.COMM_WORLD

# A block (0.2 x 0.1 m) on a base (0.4 x 0.1 m) sharing their interface (conforming), and
# a third square (0.1 x 0.1 m) that no physical group holds.
GEO = """h = 0.05;
Point(1) = {-0.2, -0.1, 0, h}; Point(2) = {0.2, -0.1, 0, h}; Point(3) = {0.2, 0, 0, h};
Point(4) = {0.1, 0, 0, h}; Point(5) = {-0.1, 0, 0, h}; Point(6) = {-0.2, 0, 0, h};
Point(7) = {0.1, 0.1, 0, h}; Point(8) = {-0.1, 0.1, 0, h};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 5}; Line(5) = {5, 6};
Line(6) = {6, 1}; Line(7) = {4, 7}; Line(8) = {7, 8}; Line(9) = {8, 5};
Curve Loop(1) = {1, 2, 3, 4, 5, 6}; Plane Surface(1) = {1};
Curve Loop(2) = {-4, 7, 8, 9}; Plane Surface(2) = {2};
Physical Surface("base") = {1}; Physical Surface("block") = {2};
Physical Curve("base_bottom") = {1}; Physical Curve("interface") = {4};
Physical Curve("block_left") = {9};
"""
ROCK = """Point(9) = {0.3, 0, 0, h}; Point(10) = {0.4, 0, 0, h}; Point(11) = {0.4, 0.1, 0, h};
Point(12) = {0.3, 0.1, 0, h};
Line(10) = {9, 10}; Line(11) = {10, 11}; Line(12) = {11, 12}; Line(13) = {12, 9};
Curve Loop(3) = {10, 11, 12, 13}; Plane Surface(3) = {3};
"""
AREAS = {"block": 0.02, "base": 0.04}


def write(folder: pathlib.Path, name: str, options: dict[str, float] | None = None,
          geo: str = GEO, order: int = 1, parts: int = 0,
          edit: Callable[[str], str] | None = None) -> pathlib.Path:
    """Mesh ``geo`` with gmsh options (rank 0) into ``folder/name``, optionally edited."""
    path = folder / name

    def build() -> None:
        script = folder / f"{path.stem}.geo"
        script.write_text(geo)
        with gmsh_session(options or {}):
            gmsh.merge(str(script))
            gmsh.model.mesh.generate(2)
            if order > 1:
                gmsh.model.mesh.setOrder(order)
            if parts:
                gmsh.model.mesh.partition(parts)
            gmsh.write(str(path))
        if edit is not None:
            path.write_text(edit(path.read_text()))

    on_rank_zero(COMM, build)
    return path


def areas(data) -> dict[str, float]:
    """Each cell group's area (collective)."""
    dx = ufl.Measure("dx", domain=data.mesh, subdomain_data=data.cell_tags)
    return {name: COMM.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(
        1.0 * dx(data.physical_groups[name].tag)))) for name in AREAS}


def cells(data) -> int:
    return data.mesh.topology.index_map(2).size_global


@pytest.fixture(scope="module")
def native(folder: pathlib.Path) -> int:
    """The cell count of gmsh's own file (format 4.1, ASCII)."""
    data = read_mesh(write(folder, "native.msh"), COMM)
    assert areas(data) == pytest.approx(AREAS, rel=1e-12)
    return cells(data)


def _nodes(text: str, move: Callable[[float, float, float], tuple[float, ...]]) -> str:
    """A format 2.2 ASCII file with its nodes moved."""
    head, rest = text.split("$Nodes\n", 1)
    count, rest = rest.split("\n", 1)
    block, tail = rest.split("$EndNodes\n", 1)
    lines = []
    for line in block.splitlines():
        tag, *xyz = line.split()
        lines.append(" ".join([tag, *map(repr, move(*map(float, xyz)))]))
    return f"{head}$Nodes\n{count}\n" + "\n".join(lines) + f"\n$EndNodes\n{tail}"


def _clockwise(text: str) -> str:
    """A format 2.2 ASCII file with every triangle's nodes in clockwise order."""
    def turn(m: re.Match) -> str:
        head, a, b, c = m.group(1), m.group(2), m.group(3), m.group(4)
        return f"{head}{a} {c} {b}"
    return re.sub(r"^(\d+ 2 \d+(?: \d+)*? )(\d+) (\d+) (\d+)$", turn, text, flags=re.M)


def _orphans(text: str) -> str:
    """A format 2.2 ASCII file with three nodes on no element."""
    head, rest = text.split("$Nodes\n", 1)
    count, rest = rest.split("\n", 1)
    n = int(count)
    extra = "".join(f"{n + k} {5 + k} 5 0\n" for k in (1, 2, 3))
    return head + f"$Nodes\n{n + 3}\n" + rest.replace("$EndNodes", extra + "$EndNodes", 1)


def _without_group_5(text: str) -> str:
    """A format 2.2 ASCII file without the elements of physical group 5 (block_left)."""
    head, rest = text.split("$Elements\n", 1)
    _, rest = rest.split("\n", 1)
    block, tail = rest.split("$EndElements\n", 1)
    kept = [e for e in block.splitlines() if e.split()[1:4] != ["1", "2", "5"]]
    return f"{head}$Elements\n{len(kept)}\n" + "\n".join(kept) + f"\n$EndElements\n{tail}"


V22 = {"Mesh.MshFileVersion": 2.2}
READ = {
    "v22_ascii": dict(options=V22),
    "v22_binary": dict(options={**V22, "Mesh.Binary": 1}),
    "v41_binary": dict(options={"Mesh.Binary": 1}),
    "saveall_v41": dict(options={"Mesh.SaveAll": 1}),
    "order3": dict(order=3),
    "partitioned": dict(parts=2),
    "partitioned_v22": dict(options=V22, parts=2),
    "partitioned_without_topology": dict(options={"Mesh.PartitionCreateTopology": 0}, parts=2),
    "orphan_nodes": dict(options=V22, edit=_orphans),
    "clockwise": dict(options=V22, edit=_clockwise),
    "z_not_zero": dict(options=V22, edit=lambda t: _nodes(t, lambda x, y, z: (x, y, 5.0))),
}


@pytest.mark.parametrize("kind", READ)
def test_read_as_gmsh_writes_it(folder, native, kind):
    # The bodies of gmsh's own file: its cells, its areas.
    data = read_mesh(write(folder, f"{kind}.msh", **READ[kind]), COMM)
    assert cells(data) == native
    assert areas(data) == pytest.approx(AREAS, rel=1e-12)


def test_ghost_cells_are_dropped(folder, native):
    # gmsh's ghost cells copy the neighbour partition's cells, in no physical group: they
    # were refused as "cells 366 and 366 overlap" (a folded mesh).
    path = write(folder, "ghosts.msh", {"Mesh.PartitionCreateGhostCells": 1}, parts=2)
    data = read_mesh(path, COMM)
    assert cells(data) == native
    assert areas(data) == pytest.approx(AREAS, rel=1e-12)


@pytest.mark.parametrize("version", [4.1, 2.2])
@pytest.mark.parametrize("part", [1, 3])
def test_one_file_of_a_split_partition_is_refused(folder, version, part):
    # One file per partition: the first ran alone, a block of a fraction of its weight
    # (format 2.2 does not give the number of partitions: split_1 is told by split_2).
    write(folder, f"split{version}.msh", {"Mesh.PartitionSplitMeshFiles": 1,
                                          "Mesh.MshFileVersion": version}, parts=3)
    with pytest.raises(MeshError, match=rf"split{version}_{part}\.msh: holds only partition "
                       rf"{part} of a partitioned mesh .*give the whole mesh in one file"):
        read_mesh(folder / f"split{version}_{part}.msh", COMM)


def test_a_mesh_partitioned_in_one_reads(folder, native):
    data = read_mesh(write(folder, "one_part.msh", V22, parts=1), COMM)
    assert cells(data) == native


def test_saveall_in_format_22_is_refused_saying_why(folder):
    # gmsh writes every element with physical tag 0 then: "no physical groups: truncated?"
    path = write(folder, "saveall22.msh", {**V22, "Mesh.SaveAll": 1})
    with pytest.raises(MeshError, match=r"no element carries a physical group.*SaveAll"):
        read_mesh(path, COMM)


@pytest.mark.parametrize("options", ["Mesh.MshFileVersion = 2.2; Mesh.SaveAll = 1;",
                                     "Mesh.MshFileVersion = 1;"], ids=["v22_saveall", "v1"])
def test_a_geo_script_s_output_format_is_breakwater_s(folder, native, options):
    # breakwater writes the script's mesh in its own format: the script's 2.2 with
    # SaveAll (every element in group 0) or format 1 (no names) refused its own file.
    script = folder / f"format_{len(options)}.geo"
    on_rank_zero(COMM, lambda: script.write_text(GEO + options + "\n"))
    data = read_mesh(script, COMM)
    assert cells(data) == native
    assert areas(data) == pytest.approx(AREAS, rel=1e-12)


def test_cells_in_no_group_are_left_out_with_a_warning(folder, native, caplog):
    # Mesh.SaveAll writes the third square's cells, in no group: dolfinx raised "All cells
    # are expected to be tagged once" (a traceback).
    path = write(folder, "saveall_rock.msh", {"Mesh.SaveAll": 1}, geo=GEO + ROCK)
    with caplog.at_level(logging.WARNING, logger="breakwater.model.mesh"):
        data = read_mesh(path, COMM)
    assert cells(data) == native
    assert areas(data) == pytest.approx(AREAS, rel=1e-12)

    def in_file() -> int:
        with gmsh_session():
            gmsh.merge(str(path))
            return sum(len(t) for t in gmsh.model.mesh.getElements(2)[1])

    assert data.ungrouped == on_rank_zero(COMM, in_file) - native > 0  # the summary's count
    if COMM.rank == 0:
        assert any(re.search(rf"{data.ungrouped} cells in no physical group \(gmsh Surface "
                             r"3\) are left out", r.getMessage()) for r in caplog.records)


def test_a_node_on_no_cell_numbered_among_the_cells_nodes(folder):
    # A node of a gmsh Point on no curve (tag 4 among the square's 1, 2, 3, 5): dolfinx's
    # reader called MPI_Abort ("Invalid rank has value 1", serially).
    path = folder / "stray_node.msh"

    def build() -> None:
        with gmsh_session():
            s = gmsh.model.addDiscreteEntity(2)
            p = gmsh.model.addDiscreteEntity(0)
            gmsh.model.mesh.addNodes(2, s, [1, 2, 3, 5], [0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0])
            gmsh.model.mesh.addNodes(0, p, [4], [5, 5, 0])
            gmsh.model.mesh.addElementsByType(s, 2, [1, 2], [1, 2, 3, 1, 3, 5])
            gmsh.model.addPhysicalGroup(2, [s], name="square")
            gmsh.option.setNumber("Mesh.SaveAll", 1)
            gmsh.write(str(path))

    on_rank_zero(COMM, build)
    data = read_mesh(path, COMM)
    dx = ufl.Measure("dx", domain=data.mesh)
    area = dolfinx.fem.assemble_scalar(dolfinx.fem.form(1.0 * dx))
    assert COMM.allreduce(area) == pytest.approx(1.0, rel=1e-12)  # the unit square


@pytest.mark.parametrize("move", [lambda x, y, z: (x * math.cos(0.5), y, x * math.sin(0.5)),
                                  lambda x, y, z: (x, y, 0.01 * x)], ids=["tilted", "warped"])
def test_a_2d_mesh_not_flat_is_refused(folder, move):
    # dolfinx keeps x and y: the tilted block's area was its projection's (cos 0.5 of it).
    path = write(folder, "tilted.msh", V22, edit=lambda t: _nodes(t, move))
    with pytest.raises(MeshError, match=r"the 2D mesh is not flat: its z coordinates span"):
        read_mesh(path, COMM)


def test_survey_coordinates_are_refused_saying_to_translate(folder, native):
    # In UTM coordinates (x ~ 5e5 m, y ~ 4e6 m) every 5 cm cell was "degenerate" (its
    # area lost to cancellation); past that, a conforming interface's nodes "did not
    # coincide" (round-off of 4e6 m above 1e-9 of 0.2 m). 3000 m off (7500 times the
    # 0.4 m extent, below FAR) reads the same bodies.
    def shift(dx: float, dy: float) -> Callable[[str], str]:
        return lambda t: _nodes(t, lambda x, y, z: (x + dx, y + dy, z))

    path = write(folder, "utm.msh", V22, edit=shift(512345.0, 4123456.0))
    with pytest.raises(MeshError, match=r"the mesh lies 4\.12e\+06 m from the origin, 1e\+07 "
                       r"times its size \(0\.4 m; survey coordinates\?\).*translate it"):
        read_mesh(path, COMM)
    data = read_mesh(write(folder, "off.msh", V22, edit=shift(2000.0, 2900.0)), COMM)
    assert cells(data) == native
    assert areas(data) == pytest.approx(AREAS, rel=1e-9)  # x carries ~1e-13 m of round-off


def test_cell_quality_far_from_the_origin():
    # The same right triangle (legs 0.02 m: area 2e-4 m², height/longest edge 1/2) at the
    # origin and 4e6 m from it: the shoelace on absolute coordinates lost the area.
    from breakwater.model.mesh import cell_quality

    tri = np.array([[[0.0, 0.0], [0.02, 0.0], [0.0, 0.02]]])
    for offset in (0.0, 512345.0, 4123456.0):
        area, quality = cell_quality(tri + offset)
        assert area[0] == pytest.approx(2e-4, rel=1e-6)  # round-off 4e6 × 2e-16 / 0.02
        assert quality[0] == pytest.approx(0.5, rel=1e-6)


def test_a_name_on_groups_of_two_dimensions_is_refused(folder):
    # dolfinx keeps one group per name: a load on the curve "block" was "a cell group".
    geo = GEO.replace('Physical Curve("block_left")', 'Physical Curve("block")')
    path = write(folder, "same_name.msh", geo=geo)
    message = r"the name 'block' is given to a 2D and a 1D physical group"
    with pytest.raises(GroupNameError, match=message):
        physical_groups(path)
    with pytest.raises(MeshError, match=message):
        read_mesh(path, COMM)


def test_unnamed_groups_say_how_to_name_them(folder):
    # meshio writes tags without names unless given field_data.
    path = write(folder, "unnamed.msh", V22,
                 edit=lambda t: re.sub(r"\$PhysicalNames.*?\$EndPhysicalNames\n", "", t,
                                       flags=re.S))
    with pytest.raises(MeshError, match=r"no named physical groups .*field_data"):
        read_mesh(path, COMM)


def test_a_byte_order_mark_is_named(folder):
    # A .msh saved by a Windows editor: "not a gmsh .msh file (no $MeshFormat header)".
    path = write(folder, "bom.msh", V22)
    on_rank_zero(COMM, lambda: path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes()))
    with pytest.raises(ValueError, match=r"begins with a byte-order mark.*without BOM"):
        physical_groups(path)


def test_format_1_is_named(folder):
    # Format 1 has no header and no names: "not a gmsh .msh file (no $MeshFormat header)".
    path = write(folder, "format1.msh", {"Mesh.MshFileVersion": 1.0})
    with pytest.raises(ValueError, match=r"gmsh format 1, .* format 4\.1"):
        physical_groups(path)


def test_a_fluent_msh_is_named(folder):
    # ANSYS Fluent writes .msh too: "not a gmsh .msh file (no $MeshFormat header)".
    path = folder / "fluent.msh"
    on_rank_zero(COMM, lambda: path.write_text('(0 "fluent mesh")\n(2 2)\n(10 (0 1 4 0))\n'))
    with pytest.raises(ValueError, match=r"an ANSYS Fluent mesh .*export the mesh from gmsh"):
        physical_groups(path)


def test_a_cell_group_without_a_name_is_refused(folder):
    # No body can name it: dolfinx read it as the group "" (left out: "cell group ''").
    path = write(folder, "unnamed_rock.msh", geo=GEO + ROCK + "Physical Surface(7) = {3};\n")
    with pytest.raises(MeshError, match=r"the 2D physical group\(s\) 7 have no name"):
        read_mesh(path, COMM)


def test_names_that_are_not_utf8_are_refused(folder):
    path = write(folder, "latin1.msh", V22)
    if COMM.rank == 0:
        path.write_bytes(path.read_bytes().replace(b'"block"', '"bloque_hormigón"'.encode(
            "latin-1")))
    COMM.barrier()
    with pytest.raises(GroupNameError, match=r"bloque_hormig.n\" is not UTF-8 text"):
        physical_groups(path)


def test_meshio_round_trip_reads_with_names_and_refuses_without(folder, native):
    # meshio keeps the names only as field_data; its cells-only copy keeps the facet
    # names in $PhysicalNames with no elements ("the mesh needs cell and facet groups").
    meshio = pytest.importorskip("meshio")
    source = write(folder, "for_meshio.msh", V22)
    kept = folder / "meshio.msh"
    cells_only = folder / "meshio_cells.msh"

    def convert() -> None:
        m = meshio.read(source)
        meshio.write(kept, meshio.Mesh(m.points[:, :2], m.cells, cell_data=m.cell_data,
                                       field_data=m.field_data), file_format="gmsh22")
        tri = [k for k, c in enumerate(m.cells) if c.type == "triangle"]
        meshio.write(cells_only, meshio.Mesh(
            m.points, [m.cells[k] for k in tri],
            cell_data={n: [v[k] for k in tri] for n, v in m.cell_data.items()},
            field_data=m.field_data), file_format="gmsh22")

    on_rank_zero(COMM, convert)
    data = read_mesh(kept, COMM)
    assert cells(data) == native
    assert areas(data) == pytest.approx(AREAS, rel=1e-12)
    with pytest.raises(MeshError, match=r"no 1D physical group holds elements; base_bottom, "
                       r"interface, block_left are named in the file with none"):
        read_mesh(cells_only, COMM)


def test_meshio_without_entity_tags_says_how_to_give_them(folder, native):
    # meshio given gmsh:physical only writes every element in entity 0: gmsh keeps groups
    # per entity, so both bodies' cells were in both groups ("the cells of gmsh Surface 0
    # are in both 'base' and 'block' ... meshes merged?"). With gmsh:geometrical = the
    # physical tags, as the message says, the bodies are gmsh's.
    meshio = pytest.importorskip("meshio")
    source = write(folder, "for_meshio_tags.msh", V22)
    bare, tagged = folder / "meshio_bare.msh", folder / "meshio_tagged.msh"

    def convert() -> None:
        m = meshio.read(source)
        physical = m.cell_data["gmsh:physical"]
        for path, data in ((bare, {"gmsh:physical": physical}),
                           (tagged, {"gmsh:physical": physical, "gmsh:geometrical": physical})):
            meshio.write(path, meshio.Mesh(m.points, m.cells, cell_data=data,
                                           field_data=m.field_data), file_format="gmsh22")

    on_rank_zero(COMM, convert)
    with pytest.raises(MeshError, match=r"'base' and 'block' are all in elementary entity 0 "
                       r".*cell_data\["):
        read_mesh(bare, COMM)
    data = read_mesh(tagged, COMM)
    assert cells(data) == native
    assert areas(data) == pytest.approx(AREAS, rel=1e-12)


def test_a_group_named_with_no_elements_is_refused_when_used(folder):
    # The cells' and a facet group kept; "block_left" named, its elements dropped.
    path = write(folder, "dropped.msh", V22, edit=_without_group_5)
    data = read_mesh(path, COMM)
    assert group_tag(data, "interface", 1)
    with pytest.raises(MeshError, match=r"'block_left' \(1D\) is named in the mesh file but "
                       "no element carries its tag"):
        group_tag(data, "block_left", 1)


@pytest.mark.parametrize("suffix", [".vtu", ".inp"])
def test_other_formats_say_what_to_do(folder, suffix):
    path = folder / f"mesh{suffix}"
    on_rank_zero(COMM, lambda: path.write_text("<Xdmf/>\n"))
    with pytest.raises(MeshError, match=r"reads gmsh \.msh or \.geo files, not .*: save the "
                       r"mesh from gmsh as \.msh with its physical groups named"):
        read_mesh(path, COMM)


def test_an_xdmf_breakwater_did_not_write_says_what_to_do(folder):
    # An XDMF is read when breakwater wrote it (tests/test_xdmfmesh.py), with its names.
    path = folder / "mesh.xdmf"
    on_rank_zero(COMM, lambda: path.write_text("<Xdmf><Domain/></Xdmf>\n"))
    with pytest.raises(MeshError, match=r"mesh.xdmf: an XDMF without breakwater's physical "
                       r"group names .*`python -m breakwater mesh CASE --out mesh.xdmf`"):
        read_mesh(path, COMM)
    on_rank_zero(COMM, lambda: path.write_text("<Xdmf><Domain>\n"))
    with pytest.raises(MeshError, match=r"mesh.xdmf: cannot read the mesh \(not XDMF"):
        read_mesh(path, COMM)
