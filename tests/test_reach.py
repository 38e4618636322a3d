"""The interface Newton on the unknowns a step's contact may touch (breakwater.stepping.reach).

A block slides on a block six times as wide, a general pair whose master surface is the
lower block's whole top (the shared group and the free top beyond it): most master
facets are far from the slave, and the Newton runs on the near unknowns alone. Three
runs of the same steps: on the near unknowns (the default), on all of them (the reach
switched off), and with a reach too small (the slave's unknowns only), where every
step's contact touches a far unknown and is solved on all of them.
"""

from __future__ import annotations

import gc
import pathlib

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from blocks import two_rectangles

from breakwater.contact.general import SurfaceForces
from breakwater.contact.surfaces import SurfacePair
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Fixed, Material, SurfaceLoad
from breakwater.stepping.gn22 import GN22
from breakwater.stepping.interface import ContactSum

COMM = MPI.COMM_WORLD
MATERIAL = Material(density=2000.0, poisson=0.25, young_modulus=1e9)
PENALTY, MU = 1e10, 0.3
P = 1e5  # Pa on the upper block's top (0.5 m)
Q = 1.5 * MU * P * 0.5 / 0.25  # Pa on its 0.25 m left side: 1.5 × the friction capacity
DT, STEPS = 5e-4, 30
PAIR = SurfacePair("c", "a", "b", "interface", ("interface", "b_top_free"), PENALTY, MU)


def _run(mesh: pathlib.Path) -> dict[str, np.ndarray | int]:
    """The upper block's mean displacement per step, the resultant and the Newton's counts."""
    model = ContactModel(read_mesh(mesh, COMM), [Body("a", MATERIAL), Body("b", MATERIAL)],
                         [], fixed=[Fixed("b_bottom")],
                         loads=[SurfaceLoad("a_top", (0.0, -P), lambda t: 1.0),
                                SurfaceLoad("a_left", (Q, 0.0),
                                            lambda t: float(np.clip((t - 2e-3) / 5e-3, 0, 1)))],
                         surface_pairs=[PAIR])
    stepper = GN22(model, DT)
    try:
        stepper.initialise()
        solver = stepper.fast
        assert solver is not None
        pair = stepper.surfaces[-1]
        u, force, its, fresh = [], [], [], []
        searches = 0
        for _ in range(STEPS):
            before = pair.searches
            its.append(stepper.step())
            searches += pair.searches - before
            owned = stepper.u[0].x.array.reshape(-1, 2)[
                :stepper.u[0].function_space.dofmap.index_map.size_local]
            u.append(COMM.allreduce(owned.sum(axis=0)) / COMM.allreduce(len(owned)))
            force.append(pair.resultant())
            pair._normal_key = None  # the accepted state's search and forces, anew
            fresh.append(pair.resultant())
        reach = solver.newton.reach
        return {"u": np.array(u), "force": np.array(force), "its": np.array(its),
                "fresh": np.array(fresh), "searches": searches,
                "near_solves": reach.solves, "fallbacks": reach.fallbacks, "n": solver.n,
                "near": -1 if reach.near is None else len(reach.near)}
    finally:
        stepper.destroy()
        gc.collect()
        COMM.barrier()


@pytest.fixture(scope="module")
def runs(folder: pathlib.Path) -> dict[str, dict[str, np.ndarray | int]]:
    mesh = two_rectangles(folder / "wide_reach.msh", COMM, (0.5, 0.25), (3.0, 0.5), 0.125)
    out = {"near": _run(mesh)}
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(ContactSum, "reach", lambda self: None)
        out["all"] = _run(mesh)
    with pytest.MonkeyPatch.context() as mp:
        def slave_only(self: SurfaceForces) -> np.ndarray | None:
            return None if self._step is None else np.unique(self._ps[self._ps >= 0])
        mp.setattr(SurfaceForces, "reach", slave_only)
        out["small"] = _run(mesh)
    return out


def test_the_near_unknowns_solve_the_steps(runs) -> None:  # type: ignore[no-untyped-def]
    """Every step on the near unknowns, fewer than the interface's, and the same history.

    The two Newtons solve the same equations (the far unknowns' rows are in equilibrium
    in both) to the Newton's tolerance, by different iterates and convergence measures
    (‖S_n G_n‖ against ‖S G‖): 1e-7 of each history's scale (measured 8e-14 of the
    displacement and 1.2e-9 of the resultant here; on the Goda caisson meshed apart
    from its mound 1.7e-10 and 4e-8).
    """
    near, whole = runs["near"], runs["all"]
    assert near["near_solves"] == STEPS and near["fallbacks"] == 0
    assert 0 < near["near"] < 0.6 * near["n"]  # measured 60 of 116
    assert whole["near_solves"] == 0
    # The block slides (the push exceeds the friction capacity).
    assert near["u"][-1, 0] > 1e-4
    for key in ("u", "force"):
        scale = np.abs(whole[key]).max()
        np.testing.assert_allclose(near[key], whole[key], rtol=0, atol=1e-7 * scale)
    assert np.abs(near["its"] - whole["its"]).max() <= 1


def test_a_contact_beyond_the_reach_is_solved_on_all_unknowns(runs) -> None:  # type: ignore[no-untyped-def]
    """A reach that misses the master's unknowns: every step falls back, bit for bit."""
    small, whole = runs["small"], runs["all"]
    assert small["fallbacks"] == STEPS and small["near_solves"] == 0
    for key in ("u", "force", "its"):
        np.testing.assert_array_equal(small[key], whole[key])


def test_the_near_solution_keeps_its_last_search(runs) -> None:  # type: ignore[no-untyped-def]
    """A near solve's solution differs from its last iterate at the far unknowns alone,
    which no search reads while the far facets are beyond reach: its evaluation keeps
    the last search (one per step fewer than the iterations and starts), and the
    accepted state's resultant from it is the one searched anew, bit for bit."""
    near, whole = runs["near"], runs["all"]
    np.testing.assert_array_equal(near["force"], near["fresh"])
    np.testing.assert_array_equal(whole["force"], whole["fresh"])
    # Searches per step: a start and one per iteration, and (on all the unknowns, or
    # without the kept search) one more at the solution.
    assert near["searches"] == near["its"].sum() + STEPS
    assert whole["searches"] == whole["its"].sum() + STEPS
