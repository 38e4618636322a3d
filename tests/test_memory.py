"""The fast solver within the node's memory: X in chunks, the cache freed, MUMPS's failures.

And ``time.solver = "auto"`` (:mod:`breakwater.stepping.solverchoice`): the fast solver
where its dense interface matrices fit, else the full-system Newton (general pairs:
refused in one line).

:mod:`breakwater.common.memory` reads what the node has left; the factorisations
(:mod:`breakwater.stepping.factorisations`) build X = A⁻¹E whole only where it fits,
otherwise in chunks of columns keeping X_II (a second back-solve per step), free kept
factorisations before a new one that would not fit, and refuse a factorisation that
MUMPS could not complete. Here the available memory is set (``available``) so that a
small model takes the paths a large one takes on a real machine.
"""

from __future__ import annotations

import pathlib
import sys

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from petsc4py import PETSc

from breakwater.casefile.case import load_case
from breakwater.common.errors import BreakwaterError
from breakwater.common.files import read_history
from breakwater.common.memory import available_bytes, fits
from breakwater.contact.surfaces import SurfacePair
from breakwater.model.layout import MonolithicLayout
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, ContactPair, Damping, Fixed, Material
from breakwater.run import simulation
from breakwater.stepping import solverchoice
from breakwater.stepping.bulk import interface_dofs
from breakwater.stepping.factorisations import check_factorisation
from breakwater.stepping.gn22 import GN22, solve_static
from breakwater.stepping.solverchoice import DENSE_COPIES, DENSE_MEMORY, choose, dense_bytes

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from blocks import two_rectangles

COMM = MPI.COMM_WORLD
DT = 1e-3


def _two_blocks(path: pathlib.Path) -> ContactModel:
    """Block ``a`` on block ``b`` under gravity, frictional contact (μ = 0.5), damped."""
    return ContactModel(read_mesh(path, COMM),
                        [Body("a", Material(2000.0, 0.25, young_modulus=1e8)),
                         Body("b", Material(1800.0, 0.3, young_modulus=5e7))],
                        [ContactPair("interface", "a", "b", 1e10, friction=0.5)],
                        [Fixed("b_bottom")], gravity=(0.0, -9.81),
                        damping=Damping(alpha=2.0, beta=1e-4))


def test_available_memory_is_read_from_meminfo(tmp_path: pathlib.Path) -> None:
    meminfo = tmp_path / "meminfo"
    meminfo.write_text("MemTotal:       24000000 kB\nMemFree:         1000 kB\n"
                       "MemAvailable:   12345678 kB\nBuffers:  1 kB\n")
    assert available_bytes(meminfo) == 12345678 * 1024.0
    meminfo.write_text("MemTotal:       24000000 kB\n")  # an old kernel: unknown
    assert available_bytes(meminfo) is None
    assert available_bytes(tmp_path / "absent") is None
    if pathlib.Path("/proc/meminfo").exists():  # this machine's: some, not more than all
        have = available_bytes()
        assert have is not None and 0 < have


def test_fits_counts_every_rank_of_a_node() -> None:
    # The ranks on a node add their needs: 100 bytes each against half of 1000 bytes.
    node = COMM.Split_type(MPI.COMM_TYPE_SHARED)  # the ranks sharing this rank's node
    ranks = node.size
    node.Free()
    assert 1 <= ranks <= COMM.size
    assert fits(COMM, 100.0, 0.5, available=1000.0) == (100 * ranks <= 500)
    assert fits(COMM, 300.0, 0.5, available=1000.0) == (300 * ranks <= 500)
    assert not fits(COMM, 600.0, 0.5, available=1000.0)
    # One rank that needs too much refuses it for all (the same answer on every rank).
    need = 600.0 if COMM.rank == COMM.size - 1 else 0.0
    assert not fits(COMM, need, 0.5, available=1000.0)


def _run(path: pathlib.Path, available: float | None, chunk_bytes: float | None = None
         ) -> tuple[list[int], list[np.ndarray], np.ndarray, int]:
    """8 frictional steps from rest: Newton counts, u, v, a, X_II, X's chunks."""
    s = GN22(_two_blocks(path), DT)
    assert s.fast is not None
    f = s.fast.factorisations
    f.available = available
    if chunk_bytes is not None:
        f.elimination.CHUNK_BYTES = chunk_bytes
    s.initialise()
    its = [s.step() for _ in range(8)]
    fact = f.factorisation(DT)
    state = [np.concatenate([g.x.array for g in x]) for x in (s.u, s.v, s.a)]
    X_II, chunks = fact.X_II.copy(), fact.chunks
    assert (fact.X_blocks is None) == (chunks > 0)
    # What the summary reports (solver.elimination): the cost rule keeps X here.
    described = f.describe()
    assert described["X"] == ("interface rows only" if chunks else "kept")
    assert described["chunks"] == chunks and described["memory_gb"] > 0
    s.destroy()
    return its, state, X_II, chunks


def test_x_in_chunks_equals_x_whole(folder: pathlib.Path) -> None:
    # A node with 1 kB available: X (2 × 8 N n_I bytes per chunk at least one column)
    # is built a few columns at a time and only X_II is kept. X_II is the same numbers
    # (MUMPS solves each column alike; bound 1e-13 of its scale, round-off of a
    # cond ~ 1e6 solve being ~1e-10 absolute at most, measured 0), and the steps are
    # those of a second back-solve instead of the product with X: the bounds of
    # tests/test_fastpath.py::test_second_back_solve_equals_product_with_X (1e-8 on u,
    # 1e-7 on v and a, Newton counts within one).
    path = two_rectangles(folder / "chunks.msh", COMM, (0.2, 0.1), (0.3, 0.1), h=0.05)
    its_w, state_w, X_w, chunks_w = _run(path, None)
    n = COMM.allreduce(len(state_w[0]), op=MPI.SUM)
    chunk_bytes = 2 * 8.0 * n * 3  # about three columns per chunk
    its_c, state_c, X_c, chunks_c = _run(path, 1024.0, chunk_bytes)
    assert chunks_w == 0 and chunks_c >= len(X_c) // 6 > 1
    np.testing.assert_allclose(X_c, X_w, rtol=0, atol=1e-13 * np.abs(X_w).max())
    assert np.all(np.abs(np.array(its_c) - np.array(its_w)) <= 1) and sum(its_w) > 8
    for whole, chunked, rtol in zip(state_w, state_c, (1e-8, 1e-7, 1e-7), strict=True):
        scale = COMM.allreduce(np.abs(whole).max(), op=MPI.MAX)
        error = COMM.allreduce(np.abs(chunked - whole).max(), op=MPI.MAX)
        assert scale > 0 and error <= rtol * scale


def test_kept_factorisations_are_freed_when_memory_is_short(folder: pathlib.Path) -> None:
    # Three step sizes: with memory to spare all three stay (cache of 4); with 1 kB
    # available each new one first frees those kept, and the steps still run.
    path = two_rectangles(folder / "cache.msh", COMM, (0.2, 0.1), (0.3, 0.1), h=0.05)
    for available, kept in ((None, 3), (1024.0, 1)):
        s = GN22(_two_blocks(path), DT)
        assert s.fast is not None
        f = s.fast.factorisations
        f.available = available
        for dt in (DT, DT / 2, DT / 4):
            assert f.factorisation(dt).bytes > 0
        assert list(f._cache) == [DT, DT / 2, DT / 4][-kept:]
        s.initialise()
        assert s.step() >= 1
        s.destroy()


def test_a_factorisation_mumps_cannot_complete_is_refused(
        folder: pathlib.Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # MUMPS told it may use 1 MB per rank (ICNTL(23); it estimates 7 MB) fails with
    # INFOG(1) = -19; its back-solves would return infinities. The run stops with one
    # line naming it.
    path = two_rectangles(folder / "fail.msh", COMM, (0.2, 0.1), (0.3, 0.1), h=0.01)
    model = _two_blocks(path)
    monkeypatch.setattr(model, "options_prefix", lambda name: f"memory_test_{name}_")
    option = "memory_test_bulk_mat_mumps_icntl_23"
    package = "memory_test_bulk_pc_factor_mat_solver_type"  # MUMPS on one rank too
    options = PETSc.Options()
    options[option] = 1
    options[package] = "mumps"
    try:
        s = GN22(model, DT)
        with pytest.raises(BreakwaterError, match=r"the factorisation of the step matrix .* "
                           r"failed \(MUMPS INFOG\(1\) = -19: it needs more memory than "
                           r"allowed\): the model is too large"):
            s.initialise()
            s.step()
        s.destroy()
    finally:
        options.delValue(option)
        options.delValue(package)


def test_a_zero_pivot_of_petsc_lu_is_refused() -> None:
    # PETSc's own LU (the step matrix's on one rank in 2D, lu_package) does not pivot:
    # a zero pivot leaves factors whose back-solves give infinities. Refused in one
    # line naming it (a singular 3 × 3 matrix of ones, on each rank alone).
    A = PETSc.Mat().createAIJ((3, 3), nnz=3, comm=MPI.COMM_SELF)
    A.setUp()
    for i in range(3):
        A.setValues(i, [0, 1, 2], [1.0, 1.0, 1.0])
    A.assemble()
    ksp = PETSc.KSP().create(MPI.COMM_SELF)
    ksp.setOperators(A)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("petsc")
    ksp.setUp()
    with pytest.raises(BreakwaterError, match=r"^the factorisation of A failed \(PETSc's "
                       r"LU, reason 2: a zero pivot\)$"):
        check_factorisation(ksp, "A")
    ksp.destroy()
    A.destroy()


def test_a_newton_matrix_mumps_cannot_factorise_is_refused(
        folder: pathlib.Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # The static state's and the reference solver's Newton (a PETSc SNES with MUMPS):
    # the failed factorisation raised PETSc's "error code 76" under a page of PETSc's
    # traceback; now one line naming MUMPS's error (the first solve of every run is
    # the static state's: a model too large for the machine fails there).
    path = two_rectangles(folder / "snesfail.msh", COMM, (0.2, 0.1), (0.3, 0.1), h=0.01)
    model = _two_blocks(path)
    monkeypatch.setattr(model, "options_prefix", lambda name: f"memory_snes_{name}_")
    options = PETSc.Options()
    names = [f"memory_snes_{name}_mat_mumps_icntl_23" for name in ("static", "gn22")]
    for name in names:
        options[name] = 1
    try:
        with pytest.raises(BreakwaterError, match=r"the factorisation of the Newton matrix "
                           r"of static failed \(MUMPS INFOG\(1\) = -19"):
            solve_static(model)
        s = GN22(model, DT, solver="reference")
        with pytest.raises(BreakwaterError, match=r"Newton matrix of gn22 failed \(MUMPS "
                           r"INFOG\(1\) = -19"):
            s.initialise()
            s.step()
        s.destroy()
    finally:
        for name in names:
            options.delValue(name)


# --- time.solver = "auto": the fast solver where its dense interface fits ---------------

def test_auto_takes_the_fast_solver_where_its_dense_interface_fits(folder: pathlib.Path) -> None:
    """:func:`solverchoice.choose`: ``"auto"`` is ``"fast"`` while DENSE_COPIES × 8 n_I²
    bytes per rank fit in half the node's memory, else the full-system Newton
    (``"reference"``) with one line saying why; ``"fast"`` and ``"reference"`` are
    taken as asked. The boundary is the formula's: n_I of this two-block model (its
    interface's unknowns), the memory set just above and just below twice the need of
    the node's ranks."""
    path = two_rectangles(folder / "auto.msh", COMM, (0.2, 0.1), (0.3, 0.1), h=0.05)
    model = _two_blocks(path)
    n = len(interface_dofs(model, MonolithicLayout(model)))
    assert n > 0
    node = COMM.Split_type(MPI.COMM_TYPE_SHARED)
    need = node.size * dense_bytes(n)  # the node's ranks each hold them
    node.Free()
    assert dense_bytes(n) == DENSE_COPIES * 8.0 * n**2
    assert choose(model, "auto", available=2.01 * need / (2 * DENSE_MEMORY)) == ("fast", None)
    solver, line = choose(model, "auto", available=0.99 * need / DENSE_MEMORY)
    assert solver == "reference" and line is not None
    assert f"({n} interface unknowns" in line and "full-system Newton" in line
    assert choose(model, "fast", available=1.0) == ("fast", None)
    assert choose(model, "reference", available=1e15) == ("reference", None)


def test_auto_refuses_general_pairs_whose_dense_interface_does_not_fit(
        folder: pathlib.Path) -> None:
    """General pairs have no full-system solver: ``"auto"`` refuses them in one line
    where their fast solver would not fit, and takes it where it does."""
    path = two_rectangles(folder / "auto_general.msh", COMM, (0.2, 0.1), (0.3, 0.1), h=0.05)
    model = ContactModel(read_mesh(path, COMM),
                         [Body("a", Material(2000.0, 0.25, young_modulus=1e8)),
                          Body("b", Material(1800.0, 0.3, young_modulus=5e7))],
                         fixed=[Fixed("b_bottom")], gravity=(0.0, -9.81),
                         surface_pairs=[SurfacePair("c", "a", "b", "interface", "interface",
                                                    1e10, 0.5)])
    assert choose(model, "auto", available=1e15) == ("fast", None)
    with pytest.raises(BreakwaterError, match="general contact pairs have no other solver"):
        choose(model, "auto", available=1.0)


def test_auto_runs_the_reference_solver_where_the_interface_does_not_fit(
        shared_dir: pathlib.Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Through a run: the Goda case with ``time.solver = "auto"`` and no memory for the
    dense interface (DENSE_MEMORY = 0) runs the full-system Newton, says so in the
    summary (``solver.kind``), and its history is the ``"reference"`` run's: bit for bit
    on one rank (the same solver on the same inputs); on several, MUMPS's distributed
    factorisation is not reproducible to the bit from run to run (two ``"reference"``
    runs of this case on 2 ranks differ in the last bits, and stick-sensitive force
    columns by more), so there the displacements agree to 1e-8 of each column's scale
    (test_fastpath's tolerance between the two solvers)."""
    monkeypatch.setattr(solverchoice, "DENSE_MEMORY", 0.0)
    summaries = {}
    for solver in ("auto", "reference"):
        case = load_case(None, ["mesh.refinement=0.5", "time.end_time=0.0015",
                                f"time.solver={solver}", "output.figures=false",
                                "output.field_interval=0", "output.checkpoint_interval=0",
                                f"output.directory={(shared_dir / solver).as_posix()}"])
        model, spec, output, extra = case.build(COMM)
        summaries[solver] = simulation.run(model, spec, output, extra_summary=extra,
                                           report=False)
    assert summaries["auto"]["solver"]["kind"] == "reference"
    assert summaries["auto"]["finished"]
    a, b = (read_history(shared_dir / s / "history.csv") for s in ("auto", "reference"))
    assert list(a) == list(b)
    for name in a:
        if COMM.size == 1:
            np.testing.assert_array_equal(a[name], b[name], err_msg=name)
        elif name.endswith(("_ux", "_uy")):
            np.testing.assert_allclose(a[name], b[name], rtol=0,
                                       atol=1e-8 * np.abs(b[name]).max(), err_msg=name)
