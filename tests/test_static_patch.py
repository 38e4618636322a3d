"""The non-matching contact patch test in the static state (issue 23): exact on both bodies.

Two blocks 1 m × 0.5 m of one material meshed separately (:mod:`meshes.apart`), the
upper on the lower, a uniform pressure p on the upper's top, the lower on rollers
(bottom: u_y = 0, left side: u_x = 0), a general pair with ``integration = "segments"``
and ε_n = 1e12 N/m³ (stiff: the static residual's error grows with the penalty). The
exact solution is a uniform uniaxial stress σ_yy = −p, σ_xx = σ_xy = 0 in both blocks
(Taylor & Papadopoulos 1991, the contact patch test); it is in the P2 space and the
segment-to-segment integration reproduces it on non-matching meshes, so the static state
must give it to its residual: 1e-8 p is asked in every stress component of both blocks,
at every node of a DG1 interpolation (measured 1e-11 to 5e-11 p; before the pseudo steps
balanced the bulk with the interface, 6e-6 p in the upper block, 1.7e-5 p with the pair
swapped). Element sizes in the ratios 1.5 (lower 6, upper 4 across) and 1.7 (17 and 10),
the slave the coarser (upper) or the finer (lower) side. 20 undamped time steps from the
state keep it (to the same 1e-8 p): it is the equilibrium of the dynamics too.

With μ = 0.3 and the upper block free along x (no roller on its side), ``[initial]
loading = "frictional"`` (the default) applies the load with friction active: both blocks
expand alike, nothing slips (measured 3e-18 m at the upper block's corner) and the stress
is uniform (measured 2e-11 p); the frictionless loading path lets the upper block expand
about its centre, a slide of ν p H/E-order (1.3e-5 m) at its corner.

Integration ``gauss`` and ``nodes`` do not pass the patch test (their discretisation),
but their static state is found (not the undeformed state). A static state that cannot
be found is an error naming ``[initial] undeformed``, the key that starts undeformed.
Serially and under ``mpiexec -n 2``.
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
import ufl
from breakwater.meshes.apart import Rectangle, rectangles
from dolfinx import fem

from breakwater.common.errors import ConvergenceError
from breakwater.config.runspec import InitialSpec
from breakwater.contact.surfaces import SurfacePair
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Fixed, Material, SurfaceLoad
from breakwater.statics.initial import initial_state
from breakwater.stepping.gn22 import GN22

COMM = MPI.COMM_WORLD
P = 1e5  # Pa
MATERIAL = Material(density=2000.0, poisson=0.25, young_modulus=1e9)
PENALTY = 1e12
ASKED = 1e-8  # of p


def _model(folder: pathlib.Path, lower: int, upper: int, slave: str = "upper",
           integration: str = "segments", friction: float = 0.0,
           upper_roller: bool = True, pressure: float = P) -> ContactModel:
    path = rectangles(folder / f"patch_{lower}_{upper}.msh", COMM,
                      [Rectangle("lower", 0.0, 0.0, 1.0, 0.5, lower, max(2, lower // 2)),
                       Rectangle("upper", 0.0, 0.5, 1.0, 0.5, upper, max(2, upper // 2))])
    sides = {"upper": "upper_bottom", "lower": "lower_top"}
    master = "lower" if slave == "upper" else "upper"
    pair = SurfacePair("c", slave, master, sides[slave], sides[master], PENALTY,
                       friction=friction, integration=integration)  # type: ignore[arg-type]
    fixed = [Fixed("lower_bottom", (1,)), Fixed("lower_left", (0,))]
    if upper_roller:
        fixed.append(Fixed("upper_left", (0,)))
    model = ContactModel(read_mesh(path, COMM), [Body("lower", MATERIAL), Body("upper", MATERIAL)],
                         fixed=fixed,
                         loads=[SurfaceLoad("upper_top", (0.0, -pressure), lambda t: 1.0)],
                         surface_pairs=[pair])
    model.set_time(0.0)
    return model


def _stress_errors(model: ContactModel, u: list[fem.Function]) -> list[float]:
    """Per body: the largest |σ − σ_exact|/p over the components, at the DG1 nodes."""
    out = []
    for i, b in enumerate(model.bodies):
        Q = fem.functionspace(b.submesh, ("DG", 1))
        e = ufl.sym(ufl.grad(u[i]))
        σ = 2 * b.μ * e + b.λ * ufl.tr(e) * ufl.Identity(2)
        error = 0.0
        for (k, m), exact in (((1, 1), -P), ((0, 0), 0.0), ((0, 1), 0.0)):
            q = fem.Function(Q)
            q.interpolate(fem.Expression(σ[k, m], Q.element.interpolation_points))
            error = max(error, float(np.abs(q.x.array - exact).max(initial=0.0)) / P)
        out.append(COMM.allreduce(error, op=MPI.MAX))
    return out


def _say(text: str) -> None:
    if COMM.rank == 0:
        print("\n" + text)


@pytest.mark.parametrize(("lower", "upper", "slave"),
                         [(6, 4, "upper"), (6, 4, "lower"), (17, 10, "upper"),
                          (17, 10, "lower")],
                         ids=["1.5-upper", "1.5-lower", "1.7-upper", "1.7-lower"])
def test_patch_static_state_exact(folder: pathlib.Path, lower: int, upper: int,
                                  slave: str) -> None:
    """σ uniform in both blocks to 1e-8 p in the static state and after 20 steps."""
    model = _model(folder, lower, upper, slave)
    state = initial_state(model)
    assert state.kind == "frictionless" and state.held == []
    static = _stress_errors(model, state.u)
    s = GN22(model, 1e-3)
    s.initialise(state.u, state.v)
    for _ in range(20):
        s.step()
    dynamic = _stress_errors(model, s.u)
    s.destroy()
    _say(f"patch {1.0 / lower:.3g}/{1.0 / upper:.3g} m (ratio {lower / upper:.2f}), slave "
         f"{slave}: {state.iterations} Newton iterations; max |σ − σ_exact|/p static "
         f"{static}, after 20 steps {dynamic}")
    assert max(static) < ASKED, static
    assert max(dynamic) < ASKED, dynamic


def test_patch_friction_loading_path(folder: pathlib.Path) -> None:
    """μ = 0.3, the upper block free along x: the frictional loading path slides nothing."""
    model = _model(folder, 6, 4, friction=0.3, upper_roller=False)
    state = initial_state(model)
    assert state.kind == "frictional"
    errors = _stress_errors(model, state.u)
    slips = []
    for loading in ("frictional", "frictionless"):
        if loading == "frictionless":
            model.initial = InitialSpec(loading="frictionless")
            state = initial_state(model)
            assert state.kind == "frictionless"
        # The upper block's corner (0, 0.5) against the lower's: the slip.
        corner = []
        for i, b in enumerate(model.bodies):
            x = b.V.tabulate_dof_coordinates()[:, :2]
            at = np.flatnonzero(np.hypot(x[:, 0], x[:, 1] - 0.5) < 1e-9)
            held = COMM.allgather(state.u[i].x.array.reshape(-1, 2)[at, 0].tolist())
            corner.append(next(v[0] for v in held if v))  # the ranks that hold the node
        slips.append(abs(corner[1] - corner[0]))
    _say(f"patch, μ = 0.3: σ error {errors}; corner slip frictional {slips[0]:.2e} m, "
         f"frictionless {slips[1]:.2e} m")
    assert max(errors) < ASKED, errors
    # Nothing slides on the frictional path (round-off of a 5e-5 m displacement: 1e-15 m
    # allowed); the frictionless path's slide is the Poisson expansion about the upper
    # block's centre, ν p (W/2)/E' ~ 1e-5 m.
    assert slips[0] < 1e-15
    assert slips[1] > 1e-6


@pytest.mark.parametrize("integration", ["gauss", "nodes"])
def test_patch_other_integrations_find_a_static_state(folder: pathlib.Path,
                                                      integration: str) -> None:
    """``gauss`` and ``nodes``: a static state (not the undeformed state), its vertical
    resultant the load to 1e-8 (the horizontal one is the discretisation's out-of-balance
    on the deformed normals, which the roller carries: 1.4e-6 p with gauss)."""
    model = _model(folder, 6, 4, integration=integration)
    state = initial_state(model)
    assert state.kind == "frictionless"
    s = GN22(model, 1e-3)
    s.initialise(state.u, state.v)
    resultant = s.surfaces[-1].resultant()
    s.destroy()
    assert abs(resultant[1] - P) < ASKED * P


def test_no_static_state_is_an_error(folder: pathlib.Path) -> None:
    """The pressure reversed (a pull on the upper block, no gravity): no static state,
    not even held. An error naming ``[initial] undeformed``, the key that starts the run
    undeformed (before, the run went on from the undeformed state with one warning)."""
    model = _model(folder, 6, 4, pressure=-P)
    with pytest.raises(ConvergenceError, match=r"\[initial\] undeformed = true"):
        initial_state(model)
    model.initial = InitialSpec(undeformed=True)
    state = initial_state(model)
    assert state.kind == "undeformed" and state.iterations == 0
    assert all(not np.any(u.x.array) for u in state.u)


def test_unreachable_tolerance_is_named(folder: pathlib.Path) -> None:
    """A static tolerance below what round-off reaches (1e-20 of the load): the error
    names ``[initial] tolerance`` and gives each stage's failure (the frictionless one's
    first: the case's own law), not only the held stage's and ``undeformed`` (the
    equilibrium exists: 1e-9 finds it, above)."""
    model = _model(folder, 6, 4)
    model.initial = InitialSpec(tolerance=1e-20)
    with pytest.raises(ConvergenceError, match=r"\(frictionless: .*; held: .*\) at "
                       r"\[initial\] tolerance = 1e-20 of the load"):
        initial_state(model)


def test_failed_static_state_exits_1(folder: pathlib.Path,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    """Through the command line: the sliding-block example with gravity reversed (the block
    pulled off its base) exits with status 1 and one line naming ``[initial] undeformed``;
    with ``initial.undeformed = true`` it runs (status 0)."""
    from breakwater import cli

    example = pathlib.Path(__file__).parent.parent / "examples/sliding_block/sliding_block.toml"
    args = ["run", str(example), "--no-progress", "--quiet", "--set", "gravity=[0.0, 9.81]",
            "--set", "time.end_time=0.002"]
    assert cli.main([*args, "--out", str(folder / "pulled")]) == 1
    errors = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    if COMM.rank == 0:
        assert len(errors) == 1 and "[initial] undeformed = true" in errors[0], errors
    assert cli.main([*args, "--out", str(folder / "pulled_undeformed"), "--set",
                     "initial.undeformed=true"]) == 0
