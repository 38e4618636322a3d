"""The ParaView fields read back as pyvista grids (breakwater.outputs.fieldgrids).

VTX files of known fields are written here with dolfinx's VTXWriter, as a run writes
them (discontinuous P2, the mesh written once), on any number of ranks: the grid read
on rank 0 holds each cell once and, at its points, the fields' exact values (quadratics,
held exactly by P2).
"""

from __future__ import annotations

import pathlib
import re

import dolfinx  # before adios2: the other way round, dolfinx's ADIOS2 library fails to load
import numpy as np
import pytest
from dolfinx import fem
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)
from breakwater.outputs.fieldgrids import field_names, field_times, read_fields

pytest.importorskip("adios2")
pytest.importorskip("pyvista")

NX, NY = 4, 3  # 2 × 4 × 3 triangles


def _u(x: np.ndarray, scale: float) -> np.ndarray:
    return scale * np.stack([x[0] * x[1], x[0] ** 2 - x[1]])


def _s(x: np.ndarray, scale: float) -> np.ndarray:
    return scale * (x[0] + 2.0 * x[1] ** 2)


def _square(comm: MPI.Comm) -> dolfinx.mesh.Mesh:
    return dolfinx.mesh.create_unit_square(comm, NX, NY,
                                           ghost_mode=dolfinx.mesh.GhostMode.shared_facet)


def _write(path: pathlib.Path, comm: MPI.Comm, times: list[float], scales: list[float],
           msh: dolfinx.mesh.Mesh | None = None) -> None:
    msh = _square(comm) if msh is None else msh
    u = fem.Function(fem.functionspace(msh, ("Discontinuous Lagrange", 2, (2,))),
                     name="displacement")
    s = fem.Function(fem.functionspace(msh, ("Discontinuous Lagrange", 2)), name="von_mises")
    with dolfinx.io.VTXWriter(comm, path, [u, s],
                              mesh_policy=dolfinx.io.VTXMeshPolicy.reuse) as writer:
        for t, c in zip(times, scales, strict=True):
            u.interpolate(lambda x, c=c: _u(x, c))
            s.interpolate(lambda x, c=c: _s(x, c))
            writer.write(t)


@pytest.fixture
def folder(tmp_path: pathlib.Path) -> pathlib.Path:
    """A run's folder (rank 0's) with ``fields_block.bp`` at t = 0, 0.1, 0.2."""
    comm = MPI.COMM_WORLD
    path = pathlib.Path(comm.bcast(str(tmp_path) if comm.rank == 0 else None))
    _write(path / "fields_block.bp", comm, [0.0, 0.1, 0.2], [1.0, 2.0, 3.0])
    comm.barrier()
    return path


def test_grid_holds_the_fields(folder: pathlib.Path) -> None:
    if MPI.COMM_WORLD.rank != 0:
        return
    assert field_names(folder) == ["fields_block"]
    assert field_times(folder, "block") == pytest.approx([0.0, 0.1, 0.2], abs=0)
    grid = read_fields(folder, "block", time=0.12)  # the nearest time written: 0.1
    assert grid.field_data["time"][0] == 0.1
    # Each cell once (a rank's ghost cells dropped), six nodes each (discontinuous).
    assert grid.n_cells == 2 * NX * NY and grid.n_points == 6 * 2 * NX * NY
    assert set(grid.celltypes) == {69}  # VTK_LAGRANGE_TRIANGLE
    x = grid.points
    u = grid.point_data["displacement"]
    assert u.shape == (grid.n_points, 3)
    assert np.allclose(u[:, :2], _u(x.T, 2.0).T, rtol=0, atol=1e-14)
    assert np.all(u[:, 2] == 0.0)
    assert np.allclose(grid.point_data["von_mises"], _s(x.T, 2.0), rtol=0, atol=1e-14)
    # The cells cover the square: their nodes' mean is a centroid (P2 triangles: the
    # mean of the 3 vertices and 3 mid-edge nodes is the centroid), each once.
    vertices = grid.cell_connectivity.reshape(-1, 6)[:, :3]
    a, b, c = (x[vertices[:, k], :2] for k in range(3))
    area = 0.5 * np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    assert area.sum() == pytest.approx(1.0, rel=1e-14)
    last = read_fields(folder, "fields_block")  # the last time, by the file's stem
    assert last.field_data["time"][0] == 0.2
    assert np.allclose(last.point_data["von_mises"], _s(last.points.T, 3.0), atol=1e-14)


def test_resumed_run_parts(folder: pathlib.Path) -> None:
    """A resumed run's earlier part is read too; where both hold a time, the later file."""
    comm = MPI.COMM_WORLD
    _write(folder / "fields_block.part1.bp", comm, [0.2, 0.3], [7.0, 8.0])
    comm.barrier()
    if comm.rank != 0:
        return
    assert field_times(folder, "block") == pytest.approx([0.0, 0.1, 0.2, 0.3], abs=0)
    # The order by part number: the main file is the latest.
    grid = read_fields(folder, "block", 0.2)
    assert np.allclose(grid.point_data["von_mises"], _s(grid.points.T, 3.0), atol=1e-14)
    grid = read_fields(folder, "block", 0.3)
    assert np.allclose(grid.point_data["von_mises"], _s(grid.points.T, 8.0), atol=1e-14)


def test_refusals(folder: pathlib.Path) -> None:
    comm = MPI.COMM_WORLD
    _write(folder / "contact_block.bp", comm, [0.0], [1.0])
    comm.barrier()
    if comm.rank != 0:
        return
    with pytest.raises(ValueError, match=r"no fields of 'fields_block' at t = 0.5 s: "
                                         r"written from t = 0 s to 0.2 s \(3 times\)"):
        read_fields(folder, "fields_block", 0.5)
    with pytest.raises(ValueError, match=r"'block' is a body and a pair: name the file, "
                                         r"'fields_block' or 'contact_block'"):
        read_fields(folder, "block")
    with pytest.raises(ValueError, match=r"no field file of 'mound' \(the run's: "
                                         r"contact_block, fields_block\)"):
        read_fields(folder, "mound")
    assert read_fields(folder, "contact_block").field_data["time"][0] == 0.0


def test_arguments_of_another_type(folder: pathlib.Path) -> None:
    """A time given as a string failed in numpy (``UFuncTypeError: ufunc 'less_equal' did
    not contain a loop ...``), a name None with ``AttributeError: 'NoneType' object has no
    attribute 'removesuffix'``; now one line naming the argument. A NumPy time is taken."""
    if MPI.COMM_WORLD.rank != 0:
        return
    for time, got in (("0.1", "str '0.1'"), (True, "bool True"), ([0.1], "list [0.1]")):
        with pytest.raises(ValueError, match=r"^time: expected a number \(s\) or None \(the "
                           rf"last\), got {re.escape(got)}$"):
            read_fields(folder, "block", time)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"^name: expected a body's or a contact pair's name "
                       r"\(a str\), got NoneType None$"):
        read_fields(folder, None)  # type: ignore[arg-type]
    assert read_fields(folder, "block", np.float32(0.1)).field_data["time"][0] == 0.1


def test_ranks_without_cells(shared_dir: pathlib.Path) -> None:
    """A body whose cells lie on some ranks only (a run's body is a submesh of the whole
    mesh: the Goda caisson on 3 or 4 ranks, a small block on a long base): the file holds
    an empty block of each other rank, and reading one failed inside ADIOS2
    (``ValueError: cannot convert float NaN to integer``: any run on 3 ranks or more).
    Here the body is rank 0's cells of the square; its grid holds them, each once."""
    comm = MPI.COMM_WORLD
    square = _square(comm)
    owned = square.topology.index_map(2).size_local
    cells = np.arange(owned if comm.rank == 0 else 0, dtype=np.int32)
    body = dolfinx.mesh.create_submesh(square, 2, cells)[0]
    _write(shared_dir / "fields_block.bp", comm, [0.0, 0.1], [1.0, 2.0], msh=body)
    count = comm.bcast(owned, root=0)
    comm.barrier()
    if comm.rank != 0:
        return
    grid = read_fields(shared_dir, "block", time=0.1)
    assert grid.n_cells == count and grid.n_points == 6 * count
    assert np.allclose(grid.point_data["von_mises"], _s(grid.points.T, 2.0), rtol=0,
                       atol=1e-14)


def _run(folder: pathlib.Path, end_time: float) -> pathlib.Path:
    """The outputs of the tests' two-block case (fields every step) run to ``end_time``."""
    from blocks import two_block_case, two_rectangles

    from breakwater import cli

    comm = MPI.COMM_WORLD
    folder.mkdir(exist_ok=True) if comm.rank == 0 else None
    comm.barrier()
    mesh = two_rectangles(folder / "blocks.msh", comm, (1.0, 0.5), (1.0, 0.5), 0.25)
    case = folder / "tiny.toml"
    if comm.rank == 0:
        case.write_text(two_block_case(mesh.name, tail="[output]\nfield_interval = 1\n"
                                       "figures = false\n")
                        .replace("end_time = 1e-3", f"end_time = {end_time:g}"))
    comm.barrier()
    out = folder / "out"
    assert cli.main(["run", str(case), "--out", str(out), "--no-progress", "--quiet"]) == 0
    return out


@pytest.mark.timeout(120)
def test_a_run_cut_short(shared_dir: pathlib.Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A run's folder whose ``data.0`` is shorter than its index lists (a copy of a run
    still running, a run killed, a power loss): a time cut short is refused in one line
    naming the last whole time, the whole times are read as in the whole file, on every
    rank. Before, ADIOS2 retried the read past the file's end for good: the notebook
    hung (measured: still waiting after 60 s). A metadata file cut short is refused too,
    in one line naming it, before ADIOS2 opens it (ADIOS2's open timeout, set to 1 s,
    10 s by default, is the backstop).

    The cut lands a quarter of the way into the fourth time's data (of five): after the
    bytes of a run of the same case to its third time (the same data written in the same
    order), so the fifth time is refused naming the third, the fourth being cut too.
    """
    import shutil
    import time

    comm = MPI.COMM_WORLD
    whole = _run(shared_dir / "whole", 4e-4)  # fields at t = 0, 1e-4, ..., 4e-4
    three = _run(shared_dir / "three", 2e-4)  # at t = 0, 1e-4, 2e-4
    capsys.readouterr()
    cut = shared_dir / "cut"
    data = cut / "fields_a.bp" / "data.0"
    if comm.rank == 0:
        shutil.copytree(whole, cut)
        first, full = (three / "fields_a.bp" / "data.0").stat().st_size, data.stat().st_size
        assert first < full
        with open(data, "r+b") as f:
            f.truncate(first + (full - first) // 4)
        shutil.copytree(whole, shared_dir / "meta")
        md = shared_dir / "meta" / "fields_a.bp" / "md.0"
        with open(md, "r+b") as f:
            f.truncate(md.stat().st_size // 2)
    comm.barrier()
    size = data.stat().st_size
    assert field_times(cut, "a") == pytest.approx([0.0, 1e-4, 2e-4, 3e-4, 4e-4], rel=1e-12)
    for t, shown in ((None, "0.0004"), (3e-4, "0.0003")):
        with pytest.raises(ValueError) as refused:
            read_fields(cut, "a", t)
        assert str(refused.value) == (
            f"{cut / 'fields_a.bp'}: the fields at t = {shown} s are cut short, its data "
            f"files hold {size} bytes, fewer than its index lists (a copy of a run still "
            "running, or a run killed, stopped by a full disk or a power loss); the last "
            "whole time before it is t = 0.0002 s")
    grid, reference = read_fields(cut, "a", 2e-4), read_fields(whole, "a", 2e-4)
    assert grid.field_data["time"][0] == pytest.approx(2e-4, rel=1e-12)
    assert np.array_equal(grid.points, reference.points)
    for n in ("displacement", "velocity", "von_mises"):
        assert np.array_equal(grid.point_data[n], reference.point_data[n]), n
    assert read_fields(cut, "b").field_data["time"][0] == pytest.approx(4e-4, rel=1e-12)
    start = time.perf_counter()
    with pytest.raises(ValueError, match=r"^" + str(shared_dir / "meta" / "fields_a.bp")
                       + r": cannot be read, its md.0 is cut short \(\d+ bytes, md.idx lists "
                       r"\d+\) \(a copy "):
        field_times(shared_dir / "meta", "a")
    assert time.perf_counter() - start < 5.0  # ADIOS2's default: 10 s


_WHY = ("(a copy of a run still running, or a run killed, stopped by a full disk or a power "
        "loss); copy the folder again once the run has ended, or run the case again")


def _damage(path: pathlib.Path, how: str) -> None:
    size = path.stat().st_size
    if how == "missing":
        path.unlink()
    elif how == "empty":
        path.write_bytes(b"")
    elif how == "cut":
        path.write_bytes(path.read_bytes()[: size // 2])
    elif how == "zero-filled":
        path.write_bytes(bytes(size))
    else:  # zeros mid-file, the file's length kept (a power loss's zero-filled block)
        data = bytearray(path.read_bytes())
        data[size // 3: 2 * size // 3] = bytes(2 * size // 3 - size // 3)
        path.write_bytes(bytes(data))


@pytest.mark.parametrize(("name", "how", "problem"), [
    ("mmd.0", "cut", r"is cut short \(\d+ bytes, its records list \d+ or more\)"),
    ("mmd.0", "empty", "is empty"),
    ("mmd.0", "missing", "is missing"),
    ("mmd.0", "zero-filled", r"is zero-filled \(\d+ bytes of zeros\)"),
    ("mmd.0", "zeros", r"is damaged \(a run of zeros in the format at byte 0\)"),
    ("md.idx", "empty", "is empty"),
    ("md.idx", "missing", "is missing"),
    ("md.idx", "zero-filled", r"is zero-filled \(\d+ bytes of zeros\)"),
    ("md.idx", "zeros", r"is damaged \(a record of type b'\\x00' and 0 bytes at byte \d+\)"),
    ("md.0", "cut", r"is cut short \(\d+ bytes, md.idx lists \d+\)"),
    ("md.0", "empty", "is empty"),
    ("md.0", "missing", "is missing"),
    ("md.0", "zero-filled", r"is zero-filled \(\d+ bytes of zeros\)"),
])
def test_a_metadata_file_damaged(folder: pathlib.Path, capfd: pytest.CaptureFixture[str],
                                 name: str, how: str, problem: str) -> None:
    """Each metadata file of a ``.bp`` folder missing, empty, cut short or zero-filled:
    refused in one line naming the file and what to do, nothing on stderr, on
    ``field_times`` and ``read_fields`` alike. Before, an ``mmd.0`` cut short,
    zero-filled or with zeros mid-file and an empty ``md.idx`` crashed the process in
    ADIOS2 (a segmentation fault: PETSc's signal handler's lines, then MPI_Abort), and the
    others were refused without naming the file."""
    comm = MPI.COMM_WORLD
    if comm.rank != 0:
        return
    bp = folder / "fields_block.bp"
    _damage(bp / name, how)
    capfd.readouterr()
    for read in (field_times, read_fields):
        with pytest.raises(ValueError) as refused:
            read(folder, "block")
        assert re.fullmatch(re.escape(f"{bp}: cannot be read, its {name} ") + problem
                            + " " + re.escape(_WHY), str(refused.value)), refused.value
    assert capfd.readouterr().err == ""


def test_a_data_file_zero_filled(folder: pathlib.Path, capfd: pytest.CaptureFixture[str]
                                 ) -> None:
    """A ``data.0`` of the right length holding zeros (a power loss): its times are
    listed (its metadata is whole) and each is refused in one line. Before, pyvista's
    ``Number of cell types (1) must match the number of cells 8)``."""
    comm = MPI.COMM_WORLD
    if comm.rank != 0:
        return
    bp = folder / "fields_block.bp"
    _damage(bp / "data.0", "zero-filled")
    assert field_times(folder, "block") == pytest.approx([0.0, 0.1, 0.2], abs=0.0)
    with pytest.raises(ValueError) as refused:
        read_fields(folder, "block", 0.1)
    assert str(refused.value) == (
        f"{bp}: the fields at t = 0.1 s are damaged, its data files hold no cells where its "
        f"index lists them (zeros: {_WHY.replace('(a copy', 'a copy')}")
    assert capfd.readouterr().err == ""


def test_a_bp4_folder_is_left_to_adios2(tmp_path: pathlib.Path) -> None:
    """A folder of ADIOS2's BP4 format (no ``mmd.0``, an index of another layout) is not
    refused by the BP5 checks: its times and fields read as a BP5 folder's."""
    comm = MPI.COMM_SELF
    msh = dolfinx.mesh.create_unit_square(comm, NX, NY)
    s = fem.Function(fem.functionspace(msh, ("Discontinuous Lagrange", 2)), name="von_mises")
    with dolfinx.io.VTXWriter(comm, tmp_path / "fields_b.bp", [s], engine="BP4") as writer:
        for t, c in ((0.0, 1.0), (0.5, 2.0)):
            s.interpolate(lambda x, c=c: _s(x, c))
            writer.write(t)
    assert not (tmp_path / "fields_b.bp" / "mmd.0").exists()
    assert field_times(tmp_path, "b").tolist() == [0.0, 0.5]
    grid = read_fields(tmp_path, "b")
    assert np.allclose(grid.point_data["von_mises"], _s(grid.points.T, 2.0), atol=1e-14)
