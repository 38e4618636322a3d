"""Partition independence: runs on ``MPI.COMM_WORLD`` equal serial runs of the same model.

Under ``mpiexec -n 2`` each test computes on ``COMM_WORLD``, then rank 0 repeats the
computation on ``COMM_SELF`` (a serial run inside the same process, on its own mesh file)
and the two are compared: probe values, nodal interface arrays (gathered in coordinate
order, so the node order does not depend on the partition) and Newton iteration counts.
Serially the tests are skipped.
"""

from __future__ import annotations

import pathlib
import sys
from collections.abc import Callable
from functools import partial

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
import ufl

from breakwater.contact.conforming import InterfaceNodes
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, ContactPair, Fixed, Material, SurfaceLoad
from breakwater.outputs.probes import PointProbe
from breakwater.stepping.gn22 import GN22, solve_static

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from blocks import two_rectangles

COMM = MPI.COMM_WORLD
pytestmark = pytest.mark.skipif(
    COMM.size < 2, reason="compares serial and parallel runs; run under mpiexec -n 2")

# Materials of tests/test_statics.py: Goda's caisson (the paper's §5) on a softer, wider base
# (here a 0.2 m square block on a 0.5 m × 0.15 m base, coarse mesh).
CAISSON = Material(density=2314.0, poisson=0.2, shear_modulus=2e9)
MOUND = Material(density=2000.0, poisson=0.25, shear_modulus=3e6)
PENALTY = 5e8
G = 9.81
DT, STEPS = 2e-4, 20
PULSE_PEAK, PULSE_TIME = 2e4, 1e-3  # Pa; triangular pulse peaking at PULSE_TIME


def _pulse(t: float) -> float:
    """Triangular pulse on [0, 2 PULSE_TIME], peak 1 at PULSE_TIME."""
    return max(0.0, 1.0 - abs(t - PULSE_TIME) / PULSE_TIME)


Result = dict[str, np.ndarray]


def _say(*args: object) -> None:
    if COMM.rank == 0:
        print(*args)


def _block_on_base(comm: MPI.Comm, path: pathlib.Path, friction: float,
                   pulse: bool) -> ContactModel:
    """A 0.2 m × 0.2 m block centred on a 0.5 m × 0.15 m base fixed at its bottom."""
    path = two_rectangles(path, comm, a=(0.2, 0.2), b=(0.5, 0.15), h=0.04)
    loads = [SurfaceLoad("a_left", (PULSE_PEAK, 0.0), _pulse)] if pulse else []
    return ContactModel(read_mesh(path, comm), [Body("a", CAISSON), Body("b", MOUND)],
                        [ContactPair("interface", "a", "b", PENALTY, friction=friction,
                                     regularisation=1e-10)],
                        [Fixed("b_bottom")], loads, gravity=(0.0, -G))


def _static_run(comm: MPI.Comm, path: pathlib.Path) -> Result:
    """Self weight (test (a)): resultant, nodal pressures, a probe, Newton iterations."""
    model = _block_on_base(comm, path, 0.0, pulse=False)
    u, its = solve_static(model)
    pair = model.pairs[0]
    resultant = model.assemble(model.form(ufl.dot(model.traction(pair, u, None), pair.n)
                                          * pair.dS))
    nodes = InterfaceNodes(model, pair)
    us, um = nodes.gather(u[pair.slave].x.array, u[pair.master].x.array)
    p = PENALTY * np.maximum(0.0, -np.sum((us - um) * nodes.normal, axis=1))
    top = PointProbe(model, "a", (0.05, 0.35)).value(u)
    return {"its": np.array([its]), "resultant": np.array([resultant]), "x": nodes.x,
            "pressure": p, "u_slave": us, "u_master": um, "probe": top}


def _dynamic_run(comm: MPI.Comm, path: pathlib.Path, solver: str = "fast") -> Result:
    """Frictional dynamics: static state, then a horizontal pulse on the block's side."""
    model = _block_on_base(comm, path, 0.5, pulse=True)
    u, its0 = solve_static(model)
    stepper = GN22(model, DT, solver=solver)
    stepper.initialise(u)
    probes = [PointProbe(model, "a", (-0.1, 0.15)), PointProbe(model, "b", (-0.1, 0.15)),
              PointProbe(model, "a", (0.1, 0.35))]
    its, history = [its0], []
    for _ in range(STEPS):
        its.append(stepper.step())
        history.append(np.concatenate([p.value(stepper.u) for p in probes]))
    nodes = stepper.nodes[0]
    us, um = nodes.gather(stepper.u[0].x.array, stepper.u[1].x.array)
    vs, vm = nodes.gather(stepper.v[0].x.array, stepper.v[1].x.array)
    result = {"its": np.array(its), "history": np.array(history), "u_slave": us,
              "u_master": um, "v_slave": vs, "v_master": vm, "flips": np.array([stepper.flips])}
    stepper.destroy()
    return result


def _against_serial(run: Callable[[MPI.Comm, pathlib.Path], Result], folder: pathlib.Path,
                    name: str) -> tuple[Result, Result]:
    """Run on COMM_WORLD, then serially on rank 0; both results on every rank."""
    parallel = run(COMM, folder / f"{name}_world.msh")
    serial: Result | str | None = None
    if COMM.rank == 0:
        try:
            serial = run(MPI.COMM_SELF, folder / f"{name}_serial.msh")
        except Exception as e:  # share the failure instead of leaving rank 1 waiting
            serial = f"serial run failed on rank 0: {e!r}"
    serial = COMM.bcast(serial, root=0)
    if isinstance(serial, str):
        pytest.fail(serial)
    assert serial is not None
    return parallel, serial


def _relative(parallel: np.ndarray, serial: np.ndarray) -> float:
    """max |parallel − serial| / max |serial|."""
    assert parallel.shape == serial.shape
    return float(np.abs(parallel - serial).max() / np.abs(serial).max())


# Tolerance 1e-10 relative (asked for): the partition changes only the order of sums and
# the pivoting of the LU factorisation, i.e. round-off. Measured: ~1e-15 for the pressures
# and the base; 2e-11 for the statically placed block, a uniform x-shift of 2e-15 m (vs
# max|u| ~ 1e-4 m): frictionless contact leaves the block's horizontal position free and
# solve_static settles it through the tangential spring of its Jacobian, a poorly
# conditioned mode; 1.5e-11 in the frictional run, where χ = 1e-10 makes the tangential
# tangent μp/χ ~ 1e13 and magnifies round-off.
RTOL = 1e-10
# The fast solver (time.solver = "fast") eliminates the bulk through the interface
# compliance X_II = (A⁻¹)_II and its inverse S, whose round-off the χ = 1e-10 stick
# tangent μp/χ magnifies about 1e5-1e6 times (the partition changes the order of the
# sums in X and S). Measured with the nodal contact forces (summed in a
# partition-independent order; breakwater.contact.nodal): 5.0e-11 (history), 5.4e-11 on
# both sides' displacements, 4.4e-10 / 2.1e-9 on the slave / master velocities; on the CI
# machine (other BLAS kernels, same inputs) 5.6e-11, 3.7e-11 / 1.4e-10, 1.1e-10 / 5.6e-10,
# i.e. 1.5e-14 m on displacements of 1.1e-4 m. A tighter Newton tolerance does not reduce
# it (it is the conditioning, not the stopping test). Bounds: 1e-9 on the displacements
# and 1e-8 on the velocities, a margin of 7-15 over the largest measured; the reference
# solver keeps the 1e-10 asked for (RTOL).
RTOL_FAST = {"history": 1e-9, "u_slave": 1e-9, "u_master": 1e-9, "v_slave": 1e-8,
             "v_master": 1e-8}


def test_self_weight_parallel_equals_serial(folder: pathlib.Path) -> None:
    parallel, serial = _against_serial(_static_run, folder, "static")
    errors = {k: _relative(parallel[k], serial[k])
              for k in ("x", "resultant", "pressure", "u_slave", "u_master", "probe")}
    _say(f"\nself weight, {COMM.size} ranks vs serial: Newton its {parallel['its'][0]} vs "
         f"{serial['its'][0]}; relative differences "
         + ", ".join(f"{k} {v:.1e}" for k, v in errors.items()))
    for k, e in errors.items():
        assert e <= RTOL, k
    assert parallel["its"][0] == serial["its"][0]


@pytest.mark.parametrize("solver", ["reference", "fast"])
def test_frictional_dynamics_parallel_equals_serial(folder: pathlib.Path, solver: str) -> None:
    parallel, serial = _against_serial(partial(_dynamic_run, solver=solver), folder,
                                       f"dynamic_{solver}")
    keys = ("history", "u_slave", "u_master", "v_slave", "v_master")
    errors = {k: _relative(parallel[k], serial[k]) for k in keys}
    # Per-step relative difference of the probe histories (x of block and base corner,
    # then the block's top corner), each normalised by its largest value over the run.
    steps = np.abs(parallel["history"] - serial["history"]).max(axis=1) \
        / np.abs(serial["history"]).max()
    slip = serial["history"][:, 0] - serial["history"][:, 2]
    _say(f"\nfrictional dynamics ({solver}), {COMM.size} ranks vs serial ({STEPS} steps, μ = 0.5, "
         f"χ = 1e-10): relative differences "
         + ", ".join(f"{k} {v:.1e}" for k, v in errors.items())
         + f"; worst step {steps.max():.1e}\n  Newton its parallel {parallel['its'].tolist()}"
         f"\n  Newton its serial   {serial['its'].tolist()}\n  slip-reversal cuts "
         f"{int(parallel['flips'][0])} vs {int(serial['flips'][0])}; corner slip "
         f"{slip[0] * 1e6:.2f} -> {slip[-1] * 1e6:.2f} µm")
    # The pulse must make the block slide, so that the slip branch of the friction law and
    # the slip-reversal guard are part of the comparison (μW = 454 N/m, peak push 4 kN/m).
    assert slip[-1] - slip[0] > 1e-5
    for k, e in errors.items():
        assert e <= (RTOL if solver == "reference" else RTOL_FAST[k]), k
    # Newton iterations: the static solve is smooth and must match exactly. In the slip
    # steps Newton's intermediate iterates pass through the χ = 1e-10 band, where round-off
    # changes the iterates (residual norms of the second iterate were seen 17% apart) while
    # the converged states agree to ~1e-11: a count may then differ by one. This is
    # round-off, not the partition: two runs under mpiexec -n 2 gave 11 and 12 iterations at
    # step 16 (the serial run 11), both agreeing with the serial states to 1.5e-11. With
    # the conforming Newton step solved on the jumps (stepping.jumpsystem, 2026-11-28) two
    # steps took 9 iterations on 2 ranks and 11 serially (the states to 1.7e-10): that
    # step's error against an extended-precision solve was the same size as the primal
    # system's (1e-15 to 4e-9 of |δ| over this run's 77 systems, condition up to 5e8,
    # against 4e-16 to 3e-9), so the counts of steps through the band may differ by 2.
    its_p, its_s = parallel["its"], serial["its"]
    assert its_p[0] == its_s[0]
    assert np.all(np.abs(its_p - its_s) <= 2), (its_p, its_s)
