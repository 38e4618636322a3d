"""The XDMF mesh of ``breakwater mesh --out x.xdmf``, read back as a case's ``mesh.source``.

The XDMF is dolfinx's (``XDMFFile``: mesh and meshtags) with the physical groups' names
in a ``breakwater_groups`` record; breakwater reads it on any number of ranks. Each
group read back from it is the ``.msh``'s: the same measure (area, length; a group's
points the same coordinates) to round-off, the same geometric degree, and a case run
from either gives the same history. An XDMF without the names (meshio's, bare dolfinx
meshtags) or without its ``.h5`` is refused in one line.
"""

from __future__ import annotations

import csv
import pathlib

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
import dolfinx
import ufl

from breakwater import cli
from breakwater.common.errors import MeshError
from breakwater.common.parallel import on_rank_zero
from breakwater.model.mesh import group_points, group_tag, mesh_geo, read_mesh
from breakwater.model.xdmfmesh import write_xdmf

COMM = MPI.COMM_WORLD
RUNS = pathlib.Path(__file__).parent / "bad_cases" / "run"
FOREIGN = r"an XDMF without breakwater's physical group names .*`python -m breakwater mesh"


def measures(data) -> dict[str, float]:
    """Each named group's measure (collective): area or volume, length or area; a point
    group's coordinates summed (every rank's the same)."""
    msh = data.mesh
    tdim = msh.topology.dim
    one = dolfinx.fem.Constant(msh, 1.0)
    dx = ufl.Measure("dx", msh, subdomain_data=data.cell_tags)
    ds = ufl.Measure("ds", msh, subdomain_data=data.facet_tags)
    dS = ufl.Measure("dS", msh, subdomain_data=data.facet_tags)
    out = {}
    for name, (dim, tag) in data.physical_groups.items():
        if dim == 0:
            out[name] = float(group_points(data, name).sum())
            continue
        form = one * dx(tag) if dim == tdim else one * ds(tag) + ufl.avg(one) * dS(tag)
        out[name] = COMM.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(form)))
    return out


def test_a_curved_second_order_mesh_reads_back_with_every_group(folder):
    # The cylinder on a slope: six-node triangles on its circular rim, a point group.
    # The rim's length from the XDMF is the curved P2 one (2πR to 1e-6 at this mesh,
    # not the polygon's), the same as the .msh's to round-off.
    msh = read_mesh(RUNS / "q_cylinder_on_slope.geo", COMM)
    out = folder / "cylinder.xdmf"
    write_xdmf(msh, out)
    xdmf = read_mesh(out, COMM)
    assert xdmf.mesh.geometry.cmaps[0].degree == msh.mesh.geometry.cmaps[0].degree == 2
    assert xdmf.physical_groups == msh.physical_groups
    cells = [d.mesh.topology.index_map(2).size_global for d in (msh, xdmf)]
    assert cells[0] == cells[1]
    a, b = measures(msh), measures(xdmf)
    assert set(a) == {"slope", "cylinder", "slope_top", "slope_bottom", "rim", "centre"}
    assert b == pytest.approx(a, rel=1e-12, abs=1e-15)
    assert a["rim"] == pytest.approx(2 * np.pi * 0.05, rel=1e-5)  # curved, not a polygon
    assert np.allclose(group_points(xdmf, "centre"), group_points(msh, "centre"), atol=1e-15)


def test_the_library_conversion_writes_breakwaters_xdmf(folder):
    """``breakwater.model.mesh.convert_to_xdmf(msh, "x.xdmf")`` writes the XDMF
    ``breakwater mesh --out`` writes: read back by group names (every group, the same
    measures to round-off, the point group's coordinates), so it serves as a case's
    mesh.source. ``breakwater.meshes.convert(msh, "x.xdmf")`` wrote meshio's XDMF
    without the names, refused as a case's mesh: it now refuses in one line naming the
    way that writes the names."""
    from breakwater import meshes  # type: ignore[attr-defined]
    from breakwater.model.mesh import convert_to_xdmf

    source = mesh_geo(RUNS / "q_cylinder_on_slope.geo", folder / "convert.msh", COMM)
    out = convert_to_xdmf(source, folder / "sub" / "converted.xdmf", COMM)
    assert out == folder / "sub" / "converted.xdmf" and out.with_suffix(".h5").is_file()
    msh, xdmf = read_mesh(source, COMM), read_mesh(out, COMM)
    assert xdmf.physical_groups == msh.physical_groups
    assert measures(xdmf) == pytest.approx(measures(msh), rel=1e-12, abs=1e-15)
    assert np.allclose(group_points(xdmf, "centre"), group_points(msh, "centre"), atol=1e-15)
    with pytest.raises(MeshError, match=r"mesh file not found: .*missing\.msh$"):
        convert_to_xdmf(folder / "missing.msh", folder / "missing.xdmf", COMM)
    meshio_xdmf = folder / "meshio.xdmf"
    with pytest.raises(ValueError, match=r"^" + str(meshio_xdmf) + r": meshio's XDMF holds "
                       r"no physical group names, which a case reads its mesh by: write "
                       r"breakwater's with breakwater.model.mesh.convert_to_xdmf\(msh, "
                       r"out\) or `python -m breakwater mesh CASE --out meshio.xdmf`$"):
        meshes.convert(source, meshio_xdmf, comm=COMM)
    assert not meshio_xdmf.exists()


def test_a_group_sharing_facets_is_refused_from_the_xdmf_too(folder):
    # dolfinx's facet tags keep one group per facet: the XDMF's record keeps what the
    # .msh reader found, so the group is refused by name as from the .msh.
    out = folder / "shared.xdmf"
    write_xdmf(read_mesh(RUNS / "g_shared_groups.geo", COMM), out)
    data = read_mesh(out, COMM)
    assert group_tag(data, "block_top", 1)
    with pytest.raises(MeshError, match=r"'block_left_and_top' shares 7 of its 11 facets "
                       r"with group 'block_top'"):
        group_tag(data, "block_left_and_top", 1)


def test_an_xdmf_without_names_is_refused_in_one_line(folder):
    # meshio's conversion (integer gmsh:physical only) and dolfinx's own meshtags.
    import meshio
    from breakwater.meshes import export  # type: ignore[import-not-found]

    source = mesh_geo(RUNS / "q_cylinder_on_slope.geo", folder / "cylinder.msh", COMM)
    data = read_mesh(source, COMM)
    bare = folder / "bare.xdmf"
    with dolfinx.io.XDMFFile(COMM, str(bare), "w") as f:
        f.write_mesh(data.mesh)
        data.cell_tags.name = "cell_tags"
        f.write_meshtags(data.cell_tags, data.mesh.geometry)
    foreign = folder / "meshio.xdmf"

    def write() -> None:
        with export._h5py_not_required():  # (no h5py here: inline XML needs none)
            meshio.write(foreign, export.read(source), data_format="XML")

    on_rank_zero(COMM, write)
    for path in (bare, foreign):
        with pytest.raises(MeshError, match=FOREIGN) as info:
            read_mesh(path, COMM)
        assert "\n" not in str(info.value)


def test_an_xdmf_without_its_whole_h5_is_refused_naming_it(folder):
    # dolfinx reads the arrays from the .h5 of the .xdmf's name: a pair renamed together
    # reads; a missing or cut-short .h5 is refused before HDF5 prints its error stack.
    out = folder / "alone.xdmf"
    write_xdmf(read_mesh(RUNS / "g_shared_groups.geo", COMM), out)
    renamed = folder / "renamed.xdmf"

    def rename() -> None:
        renamed.write_bytes(out.read_bytes())
        out.with_suffix(".h5").rename(renamed.with_suffix(".h5"))

    on_rank_zero(COMM, rename)
    assert read_mesh(renamed, COMM).physical_groups["block_top"].dim == 1
    COMM.barrier()  # every rank has read the .h5 before rank 0 cuts it
    with pytest.raises(MeshError, match=r"alone.xdmf: its data file alone.h5 is missing .*"
                       r"copy alone.h5 with alone.xdmf"):
        read_mesh(out, COMM)
    h5 = renamed.with_suffix(".h5")
    size = on_rank_zero(COMM, lambda: h5.stat().st_size)
    on_rank_zero(COMM, lambda: h5.write_bytes(h5.read_bytes()[:size // 2]))
    with pytest.raises(MeshError, match=rf"renamed.h5 is cut short: {size // 2} of its "
                       rf"{size} bytes"):
        read_mesh(renamed, COMM)
    on_rank_zero(COMM, lambda: h5.write_bytes(b"not HDF5\n" * 100))
    with pytest.raises(MeshError, match=r"renamed.h5 is not an HDF5 file"):
        read_mesh(renamed, COMM)


def test_an_h5_damaged_within_its_length_is_refused_in_one_line(folder, capfd):
    """An ``.h5`` of the right length with bytes overwritten (a bad copy, a disk's
    damage): refused in one line naming it, on every rank, nothing on stderr. Before,
    HDF5 read the garbled arrays without a word, or dolfinx aborted every rank
    (``MPI_Issend ... Invalid rank``), or HDF5 printed its error stack (40-50 lines)
    before the line. A file of breakwater's before its ``.h5``'s digest was recorded:
    an error of HDF5's turned into one line naming the ``.h5``, with no stack."""
    out = folder / "damaged.xdmf"
    write_xdmf(read_mesh(RUNS / "g_shared_groups.geo", COMM), out)
    h5 = out.with_suffix(".h5")
    size = on_rank_zero(COMM, lambda: h5.stat().st_size)
    whole = on_rank_zero(COMM, h5.read_bytes)

    def damage(at: int, count: int, value: bytes) -> None:
        data = bytearray(whole)
        data[at:at + count] = value * count
        h5.write_bytes(bytes(data))

    again = (r" \(copy it again with damaged.xdmf, or write both again with `python -m "
             r"breakwater mesh CASE --out damaged.xdmf`\)$")
    for at, value in ((size // 2, b"\xff"), (size // 4, b"\x00"), (100, b"\x5a")):
        on_rank_zero(COMM, lambda at=at, value=value: damage(at, 2000, value))
        capfd.readouterr()
        with pytest.raises(MeshError, match=r"damaged.xdmf: its data file damaged.h5 is "
                           r"damaged, its bytes not the ones written with it \(a bad copy, "
                           r"a disk's damage\)" + again):
            read_mesh(out, COMM)
        assert capfd.readouterr().err == ""
    # Without the digest (a file written before it was recorded): HDF5's error, one line.
    text = on_rank_zero(COMM, out.read_text)
    on_rank_zero(COMM, lambda: out.write_text(
        "".join(line for line in text.splitlines(keepends=True) if "breakwater_h5" not in line)))
    on_rank_zero(COMM, lambda: damage(100, 2000, b"\x5a"))  # its root group's header
    capfd.readouterr()
    with pytest.raises(MeshError, match=r"damaged.xdmf: cannot read the mesh from its data "
                       r"file damaged.h5 \(.*\): copy it again with damaged.xdmf, or write "):
        read_mesh(out, COMM)
    assert capfd.readouterr().err == ""


def history(path: pathlib.Path) -> tuple[list[str], np.ndarray]:
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    return rows[0], np.array(rows[1:], dtype=float)


@pytest.mark.timeout(900)
def test_the_goda_case_runs_the_same_from_its_xdmf(shared_dir, capsys):
    # `breakwater mesh --out` as .msh and as .xdmf, then 2 ms of the Goda case from each
    # (20 steps: the static state, the impact's rise, the contact's friction).
    small = ["--set", "mesh.refinement=0.7"]
    msh, xdmf = shared_dir / "goda.msh", shared_dir / "goda.xdmf"
    assert cli.main(["mesh", "--out", str(msh), *small]) == 0
    assert cli.main(["mesh", "--out", str(xdmf), *small]) == 0
    out = capsys.readouterr().out
    if COMM.rank == 0:
        assert out.count("\n") == 2 and 'reads it as mesh.source = "goda.xdmf"' in out
    for path in (msh, xdmf):
        assert cli.main(["run", "--out", str(shared_dir / path.suffix[1:]), "--quiet",
                         "--no-progress", "--set", f"mesh.source={path}", "--set",
                         "time.end_time=0.002"]) == 0
    # Another format from the XDMF: refused (meshio would read it as gmsh's).
    capsys.readouterr()  # the runs' warnings
    assert cli.main(["mesh", "--out", str(shared_dir / "goda.vtu"), "--set",
                     f"mesh.source={xdmf}"]) == 2
    err = capsys.readouterr().err
    if COMM.rank == 0:
        assert err.count("\n") == 1 and "the case's mesh is an XDMF" in err
    names, a = history(shared_dir / "msh" / "history.csv")
    names_x, b = history(shared_dir / "xdmf" / "history.csv")
    assert names == names_x and a.shape == b.shape and len(a) == 21
    # dolfinx numbers the cells and dofs of the two readings apart: Newton (relative
    # tolerance 1e-9) then stops at other round-off; measured 2.5e-8 of the column's
    # largest value at most (the friction force, serial; 2.1e-8 on 2 ranks), 1e-9 for
    # the displacements. A lost group (a load, a point, a contact facet) changes them by
    # O(1).
    for k, name in enumerate(names):
        if name in ("newton_iterations", "balance_error"):  # an integer; round-off itself
            continue
        scale = np.abs(a[:, k]).max()
        assert np.abs(a[:, k] - b[:, k]).max() <= 1e-7 * scale, name
    assert np.abs(a[:, names.index("balance_error")]).max() < 1e-9 * a[:, names.index(
        "external_work")].max()


def test_a_rewritten_h5_is_another_case_for_resume(shared_dir):
    # The .xdmf's XML is the same for a mesh written again with other coordinates (its
    # arrays are in the .h5): the checkpoint's fingerprint counts the .h5's contents.
    from breakwater.outputs.checkpoint import case_fingerprint

    xdmf, h5 = shared_dir / "m.xdmf", shared_dir / "m.h5"
    on_rank_zero(COMM, lambda: (xdmf.write_text("<Xdmf/>\n"), h5.write_bytes(b"one")))
    case = {"mesh": {"source": str(xdmf)}}
    before = case_fingerprint(case)
    COMM.barrier()  # every rank has read the first .h5 before rank 0 writes the second
    on_rank_zero(COMM, lambda: h5.write_bytes(b"other"))  # another size (digests cached)
    assert case_fingerprint(case) != before
