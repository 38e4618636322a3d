"""Benchmark of the 3-D search in passes against its single pass: a graded master.

Run on purpose, never in CI (one rank)::

    .venv/bin/python benchmarks/search_passes.py

``searchkernels3d.project`` searches in passes of a growing radius (from the shortest
master face, ×4 a pass, the pair's radius last), each on the points still without a
projection; before, one pass at the pair's radius (the longest master face edge, the
default) ran Newton on every (point, face) pair within the largest face's reach. The
results are the same bit for bit (``tests/test_projection3d.py``); this measures what
the passes save where the master is graded.

The case is ``tests/test_pair3d.py``'s Hertz point contact (a quarter hemisphere,
R = 1 m, on a quarter block 3 × 3 × 3 m, E = 1 GPa, ν = 0.25, frictionless, elements
a/2 at the contact, a = R/10): its static state (``initial_state``) twice in this process,
first with the single pass put back in place of the passes (the reference), then with
the passes, each timed (wall and CPU seconds, Newton iterations, searches) with the
displacements of the two compared; and the largest search of the static state (its
integration points), both ways, the median of five. The record is written to
``benchmarks/records/<date>-search-passes.md``.
"""

from __future__ import annotations

import argparse
import datetime
import os
import pathlib
import platform
import tempfile
import time
from typing import Any

import numpy as np
from mpi4py import MPI

import breakwater  # noqa: F401  (loads the PETSc of the dolfinx wheel first)

# isort: split
from breakwater.meshes.hertz import hertz3d

from breakwater.contact import searchkernels3d
from breakwater.contact.projection import INSIDE
from breakwater.contact.surfaces import SurfacePair
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Fixed, Material, SurfaceLoad
from breakwater.statics.initial import initial_state

HERE = pathlib.Path(__file__).resolve().parent
R, E, NU = 1.0, 1e9, 0.25
A_REF = 0.1 * R
LOAD = 4 * E / (2 * (1 - NU**2)) * A_REF**3 / (3 * R)  # the whole sphere's: a = R/10


def single_pass(points: np.ndarray, nodes: np.ndarray, radius: float,
                tol: float) -> tuple[np.ndarray, np.ndarray]:
    """The search before the passes: one pass at the pair's radius."""
    return searchkernels3d._project_within(points, nodes, radius, radius, tol)


def model_of(folder: pathlib.Path) -> ContactModel:
    """test_pair3d's coarse Hertz point contact, as a built model (one rank)."""
    path = hertz3d(folder / "hertz3d.msh", MPI.COMM_SELF, R, 3.0, 3.0, A_REF / 2, 0.6,
                   2 * A_REF, overlap=A_REF**2 / (20 * R), cap=0.05)
    material = Material(1000.0, NU, young_modulus=E)
    return ContactModel(
        read_mesh(path, MPI.COMM_SELF), [Body("sphere", material), Body("block", material)],
        fixed=[Fixed("block_bottom"), Fixed("block_x0", (0,)), Fixed("block_z0", (2,)),
               Fixed("sphere_x0", (0,)), Fixed("sphere_z0", (2,))],
        loads=[SurfaceLoad("sphere_top", (0.0, -LOAD / (np.pi * R**2), 0.0), lambda t: 1.0)],
        surface_pairs=[SurfacePair("c", "sphere", "block", "sphere_contact", "block_top",
                                   1e12)])


def static(folder: pathlib.Path, search: Any) -> dict[str, Any]:
    """The static state with ``search`` as the 3-D projection, timed.

    Returns:
        Wall and CPU seconds, Newton iterations, searches and their seconds, the
        displacements, and the arguments of the largest search.
    """
    last: list[Any] = [None]
    seconds, count = [0.0], [0]

    def recorded(*args: Any) -> tuple[np.ndarray, np.ndarray]:
        if last[0] is None or len(args[0]) >= len(last[0][0]):
            last[0] = args  # the largest search (integration points, not nodes)
        count[0] += 1
        t = time.perf_counter()
        out = search(*args)
        seconds[0] += time.perf_counter() - t
        return out

    saved = searchkernels3d.project
    searchkernels3d.project = recorded
    try:
        model = model_of(folder)
        model.set_time(0.0)
        t0, c0 = time.perf_counter(), time.process_time()
        state = initial_state(model)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    finally:
        searchkernels3d.project = saved
    return {"wall": wall, "cpu": cpu, "iterations": state.iterations, "searches": count[0],
            "search_seconds": seconds[0],
            "u": np.concatenate([u.x.array for u in state.u]), "largest": last[0]}


def one_search(args: tuple[Any, ...], search: Any, repeat: int = 5) -> float:
    """The median seconds of ``search`` on ``args`` (after a first call)."""
    search(*args)
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        search(*args)
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def main() -> None:
    """Run the benchmark and write its record."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=pathlib.Path, default=HERE / "records")
    args = parser.parse_args()
    if MPI.COMM_WORLD.size > 1:
        raise SystemExit("one rank: the search is replicated on every rank")
    load_start = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        folder = pathlib.Path(tmp)
        print("static state, single pass (the reference) ...", flush=True)
        ref = static(folder, single_pass)
        print(f"  {ref['wall']:.1f} s ({ref['cpu']:.1f} s CPU), {ref['iterations']} Newton "
              f"iterations, {ref['searches']} searches {ref['search_seconds']:.1f} s", flush=True)
        print("static state, passes ...", flush=True)
        new = static(folder, searchkernels3d.project)
        print(f"  {new['wall']:.1f} s ({new['cpu']:.1f} s CPU), {new['iterations']} Newton "
              f"iterations, {new['searches']} searches {new['search_seconds']:.1f} s", flush=True)
    same = bool(np.array_equal(ref["u"], new["u"]))
    points, nodes, radius, _ = new["largest"]
    t_ref = one_search(new["largest"], single_pass)
    t_new = one_search(new["largest"], searchkernels3d.project)
    f_ref, xi_ref = single_pass(points, nodes, radius, INSIDE)
    f_new, xi_new = searchkernels3d.project(points, nodes, radius, INSIDE)
    equal = bool(np.array_equal(f_ref, f_new) and np.array_equal(xi_ref, xi_new))
    print(f"  displacements equal: {same}; one search of {len(points)} points on "
          f"{len(nodes)} faces: {1e3 * t_ref:.0f} ms single pass, {1e3 * t_new:.0f} ms in "
          f"passes ({t_ref / t_new:.1f}×), results equal: {equal}")
    date = datetime.date.today().isoformat()
    edges = np.linalg.norm(nodes[:, [1, 2, 0], :] - nodes[:, :3, :], axis=2).max(axis=1)
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / f"{date}-search-passes.md"
    path.write_text(
        f"# The 3-D search in passes against its single pass, {date}\n\n"
        "`benchmarks/search_passes.py`: tests/test_pair3d.py's Hertz point contact "
        f"(master faces {edges.min():.3g}–{edges.max():.3g} m, radius {radius:.3g} m). "
        f"Machine: {platform.machine()}, {os.cpu_count()} cores, one rank; load average "
        f"(1 min) {load_start[0]:.2f} at the start, {os.getloadavg()[0]:.2f} at the end.\n\n"
        "| | single pass | passes | ratio |\n|---|---|---|---|\n"
        f"| static state wall (s) | {ref['wall']:.1f} | {new['wall']:.1f} | "
        f"{ref['wall'] / new['wall']:.1f}× |\n"
        f"| static state CPU (s) | {ref['cpu']:.1f} | {new['cpu']:.1f} | "
        f"{ref['cpu'] / new['cpu']:.1f}× |\n"
        f"| searches (s) | {ref['search_seconds']:.1f} | {new['search_seconds']:.1f} | "
        f"{ref['search_seconds'] / new['search_seconds']:.1f}× |\n"
        f"| one search, median of 5 (ms) | {1e3 * t_ref:.0f} | {1e3 * t_new:.0f} | "
        f"{t_ref / t_new:.1f}× |\n\n"
        f"Newton iterations {ref['iterations']} and {new['iterations']}, searches "
        f"{ref['searches']} and {new['searches']}; the static displacements equal bit for "
        f"bit: {same}; one search's faces and (ξ, η) equal: {equal} ({len(points)} "
        f"integration points, {len(nodes)} master faces).\n")
    print(f"written {path}")


if __name__ == "__main__":
    main()
