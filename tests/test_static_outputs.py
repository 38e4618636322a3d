"""Point groups in ``[fixed]``, the static summary of general pairs, the static stress tensor
(issue 23, item 5).

- A frictionless block (W × H, ρ) on a base meshed apart (:mod:`meshes.apart`; a general
  pair): nothing holds it horizontally but the point group ``block_bottom_left`` fixed in
  x (``[fixed.block_bottom_left] components = [0]``). Its static state and a short run
  work, the pinned node's u_x is exactly 0 (a Dirichlet DOF), and the summary's static
  entry has the conforming pairs' keys: the normal resultant ∫ p dS equals the block's
  weight ρ g W H (vertical equilibrium of the block, exact for the FE solution: the
  virtual displacement (0, 1) is in the P2 space, and the pin carries no vertical
  force; tests/test_relaxation.py), the mean pressure is it over the contact length,
  and edge and centre pressures are the snapshot's at the ends and the middle of the
  slave surface.
- A block on rollers (``block_bottom`` fixed in y, its corner ``block_bottom_left`` in x)
  under a uniform pressure p on its top, no gravity: the uniform plane-strain state
  σ_yy = −p, σ_xx = σ_xy = 0, σ_zz = ν(σ_xx + σ_yy) (Timoshenko & Goodier, *Theory of
  Elasticity*, §16: plane strain), which P2 elements hold exactly (a linear
  displacement): every node of ``static.npz`` to 1e-9 of p (the round-off of a
  direct solve on E/p = 1e6), with the fast and the reference solver.
- A point group lying on two bodies (the corner of a block on a conforming interface)
  is refused in one line.
"""

from __future__ import annotations

import json
import pathlib

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from blocks import two_rectangles
from breakwater.meshes.apart import Rectangle, rectangles

from breakwater import cli
from breakwater.casefile.case import load_case
from breakwater.common.errors import MeshError
from breakwater.common.files import read_history
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Fixed, Material
from breakwater.statics.initial import initial_state
from breakwater.stepping.gn22 import GN22

COMM = MPI.COMM_WORLD
W, H = 0.2, 0.05            # the block (m)
ρ, ν, E, G = 2000.0, 0.25, 1e9, 9.81
WEIGHT = ρ * G * W * H      # N/m
P = 1e3                     # Pa: the uniform pressure


SHORT_RUN = """[time]
dt = 1e-3
end_time = 2e-3
[output]
figures = false
field_interval = 0
"""
"""Two steps after the static state, no figures or fields: the runs that check it."""


def _bodies(*names: str) -> str:
    """The case file's [bodies.<name>] tables, each of the tests' material."""
    return "".join(f"[bodies.{b}]\ndensity = {ρ}\npoisson = {ν}\nyoung_modulus = {E}\n"
                   for b in names)


def _run(case: pathlib.Path, out: pathlib.Path) -> dict:
    assert cli.main(["run", str(case), "--out", str(out), "--quiet", "--no-progress"]) == 0
    with open(out / "summary.json", encoding="utf-8") as f:
        return json.load(f)


@pytest.fixture(scope="module")
def pinned(folder: pathlib.Path) -> pathlib.Path:
    """The frictionless block on the base, pinned in x at its lower-left corner: a run of
    five steps of 1e-4 s from its static state."""
    mesh = rectangles(folder / "pinned.msh", COMM,
                      [Rectangle("base", -0.2, -0.05, 0.4, 0.05, 8, 2),
                       Rectangle("block", -W / 2, 0.0, W, H, 7, 2)], corners=True)
    case = folder / "pinned.toml"
    if COMM.rank == 0:
        case.write_text(f'''name = "pinned"
mesh.source = "{mesh}"
{_bodies("base", "block")}[contact.c]
slave = "block"
master = "base"
slave_surface = "block_bottom"
master_surface = "base_top"
penalty = 1e12
[fixed.base_bottom]
[fixed.block_bottom_left]
components = [0]
[time]
dt = 1e-4
end_time = 5e-4
[output]
figures = false
[output.probes.corner]
body = "block"
group = "block_bottom_left"
''', encoding="utf-8")
    COMM.barrier()
    out = folder / "pinned"
    summary = _run(case, out)
    assert summary["finished"] is True
    return out


def test_pinned_point_holds_a_frictionless_block(pinned: pathlib.Path) -> None:
    """The run of the case file: the point probe at the pin reads u_x = 0 to the
    round-off of the other shape functions, as do the snapshots' P1 values there (1e-12
    of u_y; measured 1e-17); the block settles (u_y < 0) and spreads (Poisson) away
    from the pin (u_x > 0 at its right corner)."""
    h = read_history(pinned / "history.csv")
    assert len(h["t"]) == 6
    assert np.all(h["corner_uy"] < 0)
    assert np.all(np.abs(h["corner_ux"]) < 1e-12 * np.abs(h["corner_uy"]))
    for name in ("static.npz", "snapshot_max_ux.npz"):
        with np.load(pinned / name) as data:
            x, ux, uy = data["block_x"], data["block_ux"], data["block_uy"]
        pin = np.flatnonzero(np.hypot(x[:, 0] + W / 2, x[:, 1]) < 1e-12)
        right = np.flatnonzero(np.hypot(x[:, 0] - W / 2, x[:, 1]) < 1e-12)
        assert len(pin) == 1 and len(right) == 1
        assert abs(ux[pin[0]]) < 1e-12 * abs(uy[pin[0]]), name
        assert ux[right[0]] > 0.0, name


def test_pinned_dof_is_exactly_zero(pinned: pathlib.Path) -> None:
    """The model of the same case file: the block's x DOF at the pin (on every rank that
    holds it, owned or ghost) is exactly 0 in the static state and after five steps,
    while its y DOF moves."""
    built = load_case(pinned.with_suffix(".toml")).build(COMM)
    model = built.model
    model.set_time(0.0)
    state = initial_state(model)
    assert state.kind == "frictionless"
    block = model.body("block").index
    x = state.u[block].function_space.tabulate_dof_coordinates()[:, :2]
    pin = np.flatnonzero(np.hypot(x[:, 0] + W / 2, x[:, 1]) < 1e-12)
    assert COMM.allreduce(len(pin)) >= 1
    stepper = GN22(model, 1e-4)
    stepper.initialise(state.u, state.v)
    for k in range(6):
        u = stepper.u[block].x.array.reshape(-1, 2)
        assert np.all(u[pin, 0] == 0.0), k
        assert np.all(u[pin, 1] < 0.0), k
        stepper.step()
    stepper.destroy()


def test_static_summary_of_a_general_pair(pinned: pathlib.Path) -> None:
    """Resultant = weight ρgWH (1e-6: the relaxation's residual, 1e-8 of the load norm,
    as tests/test_relaxation.py); the weight itself to round-off; mean = resultant over
    the contact length W (every integration point closed); edge and centre pressures
    the snapshot's end and middle nodes; the printed report has no n/a."""
    with open(pinned / "summary.json", encoding="utf-8") as f:
        s = json.load(f)["static"]
    assert s["slave"] == "block"
    assert s["weight"] == pytest.approx(WEIGHT, rel=1e-12)
    assert s["contact_resultant"] == pytest.approx(WEIGHT, rel=1e-6)
    assert s["resultant_over_weight"] == pytest.approx(1.0, rel=1e-6)
    assert s["contact_length"] == pytest.approx(W, rel=1e-12)
    assert s["mean_contact_pressure"] == pytest.approx(s["contact_resultant"] / W, rel=1e-12)
    assert s["mean_contact_pressure"] == pytest.approx(ρ * G * H, rel=1e-6)
    with np.load(pinned / "static.npz") as data:
        x, p = data["contact_c_x"], data["contact_c_pressure"]
    assert len(x) == 15 and np.all(np.diff(x[:, 0]) > 0)  # 7 P2 facets, sorted
    middle = int(np.argmin(np.abs(x[:, 0])))
    assert x[middle, 0] == pytest.approx(0.0, abs=1e-12)
    assert s["edge_pressures"] == [p[0], p[-1]]
    assert s["edge_pressure"] == 0.5 * (p[0] + p[-1])
    assert s["center_pressure"] == p[middle]
    assert s["max_pressure"] == p.max()
    # The pressure is near its mean in the middle (a flat block on a stiff base).
    assert s["center_pressure"] == pytest.approx(ρ * G * H, rel=0.2)
    report = _report(pinned)
    # The resultant is ∫p dS, the normal one (W cos θ on an inclined interface: the
    # line says so, read beside the weight it carries as a 4 % error before).
    line = next(li for li in report.splitlines()
                if "static: normal contact resultant ∫p dS" in li)
    assert "n/a" not in line, line


def _report(out: pathlib.Path) -> str:
    """The report printed at the end of a run, from its summary."""
    from breakwater.outputs.summary import format_report

    with open(out / "summary.json", encoding="utf-8") as f:
        return format_report(json.load(f), out)


@pytest.mark.parametrize("solver", ["fast", "reference"])
def test_static_stress_tensor_of_a_uniformly_loaded_block(folder: pathlib.Path,
                                                          solver: str) -> None:
    """σ_yy = −p, σ_xx = σ_xy = 0, σ_zz = ν(σ_xx + σ_yy) at every node of static.npz
    (to 1e-9 p); ``stress_yy`` is the tensor's σ_yy; von Mises is that of the tensor."""
    mesh = rectangles(folder / "press.msh", COMM, [Rectangle("block", 0.0, 0.0, W, H, 4, 2)],
                      corners=True)
    case = folder / f"press_{solver}.toml"
    if COMM.rank == 0:
        case.write_text(f'''name = "press"
gravity = [0.0, 0.0]
mesh.source = "{mesh}"
[bodies.block]
density = {ρ}
poisson = {ν}
young_modulus = {E}
[fixed.block_bottom]
components = [1]
[fixed.block_bottom_left]
components = [0]
[loads.press]
group = "block_top"
pressure = {P}
[time]
dt = 1e-4
end_time = 2e-4
solver = "{solver}"
[output]
figures = false
''', encoding="utf-8")
    COMM.barrier()
    out = folder / f"press_{solver}"
    _run(case, out)
    with np.load(out / "static.npz") as data:
        σ = {k: data[f"block_stress_{k}"] for k in ("xx", "yy", "xy", "zz")}
        vm = data["block_von_mises"]
        ux = data["block_ux"]
        x = data["block_x"]
    tol = 1e-9 * P
    np.testing.assert_allclose(σ["yy"], -P, atol=tol)
    np.testing.assert_allclose(σ["xx"], 0.0, atol=tol)
    np.testing.assert_allclose(σ["xy"], 0.0, atol=tol)
    np.testing.assert_allclose(σ["zz"], ν * (σ["xx"] + σ["yy"]), atol=tol)
    np.testing.assert_allclose(σ["zz"], -ν * P, atol=tol)
    # Von Mises of (0, −p, −νp): p sqrt(1 − ν + ν²).
    np.testing.assert_allclose(vm, P * np.sqrt(1 - ν + ν**2), atol=tol)
    # The pin holds the corner: u_x = (1 + ν) ν p x / E (plane strain: ε_xx = ((1 − ν²)
    # σ_xx − ν(1 + ν) σ_yy)/E), 0 at x = 0 (to the P1 values' round-off, 1e-20 m).
    assert (np.hypot(x[:, 0], x[:, 1]) < 1e-12).sum() == 1
    np.testing.assert_allclose(ux, (1 + ν) * ν * P * x[:, 0] / E, rtol=1e-8, atol=1e-20)


def test_point_group_on_two_bodies_is_refused(shared_dir: pathlib.Path) -> None:
    """``a_corner`` (tests/blocks.py) lies on the conforming interface: a vertex of both
    blocks."""
    mesh = two_rectangles(shared_dir / "two.msh", COMM, (0.5, 0.5), (1.0, 0.5), 0.25)
    mat = Material(ρ, ν, young_modulus=E)
    with pytest.raises(MeshError, match=r"^fixed 'a_corner': point group 'a_corner' lies "
                       r"on several bodies \(a, b\)"):
        ContactModel(read_mesh(mesh, COMM), [Body("a", mat), Body("b", mat)],
                     fixed=[Fixed("a_corner", (0,))])


@pytest.mark.parametrize("slave", ["a", "b"])
def test_weight_is_the_upper_body_whichever_is_the_slave(shared_dir: pathlib.Path,
                                                          slave: str) -> None:
    # The static summary's weight is what the pair carries: the upper block's (a on b),
    # with a as the slave or as the master (a foundation as the slave gave the
    # foundation's own weight: 8x, found by a user-path test).
    from breakwater.model.model import ContactPair
    from breakwater.outputs.staticsummary import _upper_body, resting_on

    path = two_rectangles(shared_dir / "stack.msh", COMM, (0.2, 0.1), (0.4, 0.1), 0.05)
    mat = Material(2000.0, 0.25, young_modulus=1e9)
    master = "b" if slave == "a" else "a"
    model = ContactModel(read_mesh(path, COMM), [Body("a", mat), Body("b", mat)],
                         [ContactPair("interface", slave, master, penalty=1e12)],
                         [Fixed("b_bottom")], [], gravity=(0.0, -9.81))
    a, b = model.body("a").index, model.body("b").index
    p = model.pairs[0]
    assert _upper_body(model, p.slave, p.master) == a
    assert resting_on(model, a) == {a} and resting_on(model, b) == {a, b}


INCLINE_GEO = """// a block on a long slope tilted by 30 degrees, meshed apart
Point(1) = {0, -0.1, 0, 0.03}; Point(2) = {1, -0.1, 0, 0.03};
Point(3) = {1, 0, 0, 0.03}; Point(4) = {0, 0, 0, 0.03};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Point(11) = {0.2, 0, 0, 0.02}; Point(12) = {0.3, 0, 0, 0.02};
Point(13) = {0.3, 0.05, 0, 0.02}; Point(14) = {0.2, 0.05, 0, 0.02};
Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 11};
Curve Loop(2) = {11, 12, 13, 14}; Plane Surface(2) = {2};
Rotate {{0, 0, 1}, {0, 0, 0}, Pi / 6} { Surface{1, 2}; }
Physical Surface("slope") = {1}; Physical Surface("block") = {2};
Physical Curve("slope_top") = {3}; Physical Curve("slope_bottom") = {1};
Physical Curve("block_bottom") = {11};
"""


@pytest.mark.parametrize("friction", [0.3, 0.0])
def test_weight_on_a_slope_is_the_blocks(shared_dir: pathlib.Path, friction: float) -> None:
    """A 0.1 x 0.05 m block on a 1 m slope tilted by 30 degrees (a general pair; the
    slope's centroid lies above the block's): the static summary's weight is the block's,
    ρ g a b, and the pair carries its normal component, resultant / weight = cos 30°
    (the block's equilibrium normal to the slope, exact for the FE solution: the
    virtual rigid translation along the normal is in the P2 space; held tangentially
    where μ = 0.3 < tan 30°; 1e-6 covers the relaxation's tolerance). Comparing the
    bodies' centroids took the slope as resting on the block: weight 20x the block's.
    Frictionless too (μ = 0: its pair had no slip guard, which the held stage's μ = 100
    needs: its first pseudo step diverged, and the run was refused)."""
    if COMM.rank == 0:
        (shared_dir / "incline.geo").write_text(INCLINE_GEO, encoding="utf-8")
        (shared_dir / "incline.toml").write_text(f'''name = "incline"
gravity = [0.0, -9.81]
mesh.source = "incline.geo"
{_bodies("block", "slope")}[calibration]
enabled = false
[fixed.slope_bottom]
[contact.sliding]
slave = "block"
master = "slope"
slave_surface = "block_bottom"
master_surface = "slope_top"
penalty = 5e10
friction = {friction}
{SHORT_RUN}''', encoding="utf-8")
    COMM.barrier()
    static = _run(shared_dir / "incline.toml", shared_dir / "out")["static"]
    weight = ρ * G * 0.1 * 0.05
    assert static["weight"] == pytest.approx(weight, rel=1e-12)
    assert static["resultant_over_weight"] == pytest.approx(np.cos(np.pi / 6), rel=1e-6)


def test_a_stack_of_three_bodies_meshed_apart(shared_dir: pathlib.Path) -> None:
    """A block on a block on a base, each meshed apart (two general pairs, element
    sizes 26, 20 and 14 mm, the upper block off-centre): the static state exists, and
    the lower pair carries both blocks, resultant = ρ g (A_lower + A_upper) (their
    vertical equilibrium, exact for the FE solution; 1e-6 covers the relaxation's
    tolerance). The pseudo steps' Newton stalled at 6.6e-9 of the load, its round-off
    with a body held by contact between two others, above the 1e-9 it was asked for:
    "no static equilibrium" (now a stall below 1e-7 is its round-off, and the static
    residual, 1e-9, decides)."""
    mesh = rectangles(shared_dir / "stack.msh", COMM,
                      [Rectangle("base", -0.3, -0.1, 0.6, 0.1, 23, 4),
                       Rectangle("lower", -0.1, 0.0, 0.2, 0.08, 10, 4),
                       Rectangle("upper", -0.05, 0.08, 0.14, 0.06, 10, 4)], order=2)
    if COMM.rank == 0:
        (shared_dir / "stack.toml").write_text(f'''name = "stack"
gravity = [0.0, -9.81]
mesh.source = "{mesh}"
{_bodies("base", "lower", "upper")}[calibration]
enabled = false
[fixed.base_bottom]
[contact.c1]
slave = "lower"
master = "base"
slave_surface = "lower_bottom"
master_surface = "base_top"
penalty = 1e12
friction = 0.5
[contact.c2]
slave = "upper"
master = "lower"
slave_surface = "upper_bottom"
master_surface = "lower_top"
penalty = 1e12
friction = 0.3
{SHORT_RUN}''', encoding="utf-8")
    COMM.barrier()
    static = _run(shared_dir / "stack.toml", shared_dir / "out")["static"]
    weight = ρ * G * (0.2 * 0.08 + 0.14 * 0.06)
    assert static["weight"] == pytest.approx(weight, rel=1e-12)
    assert static["contact_resultant"] == pytest.approx(weight, rel=1e-6)


def test_centre_of_a_curved_interface() -> None:
    # The centre node of a half-cylinder's lower arc (R = 0.1, nodes sorted by x then y)
    # is its bottom, halfway along the arc; the middle of its ends is the circle's
    # centre, as far from every node (the pick was arbitrary: a node at 39° of 90°).
    # A straight, unevenly spaced interface keeps the node nearest its middle.
    from breakwater.outputs.staticsummary import edge_centre

    θ = np.linspace(np.pi, 2 * np.pi, 25)
    arc = 0.1 * np.column_stack([np.cos(θ), np.sin(θ)])
    first, last, centre = edge_centre(arc[np.lexsort(arc.T[::-1])])
    assert np.allclose(arc[np.lexsort(arc.T[::-1])][[first, last, centre]],
                       [[-0.1, 0.0], [0.1, 0.0], [0.0, -0.1]], atol=1e-15)
    line = np.column_stack([[0.0, 0.1, 0.15, 0.47, 0.56, 1.0], np.zeros(6)])
    assert edge_centre(line) == (0, 5, 3)
    # A slave surface longer than the contact (a slope under a block): the ends and the
    # middle of the nodes under pressure, 0.1 to 0.56 (its middle 0.33: the node 0.47
    # is at 0.14, 0.15 at 0.18), not the surface's own, where the pressure was 0.
    pressure = np.array([0.0, 1.0, 0.0, 2.0, 1.0, 0.0])
    assert edge_centre(line, pressure) == (1, 4, 3)
    # The nodal pressure leaks past the contact's end: the Goda mound crest as the slave
    # read 0.04 Pa (6e-6 of the largest, 6533 Pa at the caisson's corner) at its node
    # 10 mm past the corner, which the summary took as the edge (edge pressure 0.04 Pa).
    pressure = np.array([0.0, 0.04, 6533.0, 4200.0, 6533.0, 0.04])
    assert edge_centre(line, pressure) == (2, 4, 3)


def test_an_unresolved_static_contact_is_warned() -> None:
    """A static contact shorter than 3 interface facets is warned about in one line (a
    block on a cylinder of R = 0.5 m: 5.6 mm of contact on 10 mm facets, measured); the
    Goda caisson's base (205 mm on 29 mm facets, 7 of them) is not; in 3D the contact's
    size is the square root of its area."""
    from breakwater.outputs.quality import PairInputs
    from breakwater.outputs.staticsummary import resolution_warnings

    def inputs(h: float) -> list[PairInputs]:
        return [PairInputs("sliding", 5e10, h, (4.8e9, 4.8e9), 1.6e-6, 2.2e-6)]

    lines = resolution_warnings({"sliding_contact_length": 0.00556}, inputs(0.01), 2)
    assert len(lines) == 1 and "\n" not in lines[0]
    assert lines[0].startswith("contact 'sliding': the static contact is 0.00556 m long, "
                               "0.56 of its mean interface facet (h = 0.01 m)")
    assert resolution_warnings({"sliding_contact_length": 0.205}, inputs(0.029), 2) == []
    assert resolution_warnings({"sliding_contact_length": 0.0}, inputs(0.029), 2) == []
    assert resolution_warnings({"sliding_contact_length": 0.041}, inputs(0.01), 3) == []
    assert len(resolution_warnings({"sliding_contact_length": 4e-4}, inputs(0.01), 3)) == 1


def test_a_contact_is_judged_by_its_own_facets() -> None:
    """A surface refined at its contact and coarse elsewhere is judged by the facets
    across the contact, counted from its pressed nodes ((n − 1)/degree in 2D,
    (√n − 1)/degree across in 3D), not by the surface's mean facet: issue 23's Hertz
    cylinder (benchmarks/hertz_static.py), 0.4 mm P2 facets within its 3.43 mm contact
    and 4 mm beyond (mean 1.31 mm), has 17 pressed slave nodes (8 facets across) and was
    told to refine (2.6 mean facets)."""
    from breakwater.outputs.quality import PairInputs
    from breakwater.outputs.staticsummary import resolution_warnings

    inputs = [PairInputs("hertz", 1e14, 1.31e-3, (1e9, 1e9), 1e-7, 1e-5)]
    row = {"hertz_contact_length": 3.43e-3}
    pressure = np.zeros(60)
    pressure[:17] = 1e6
    assert len(resolution_warnings(row, inputs, 2)) == 1  # by the mean facet: 2.6
    assert resolution_warnings(row, inputs, 2, {"contact_hertz_pressure": pressure}) == []
    pressure[3:] = 0.0  # three nodes: one P2 facet across, as on the motivating block
    lines = resolution_warnings(row, inputs, 2, {"contact_hertz_pressure": pressure})
    assert len(lines) == 1 and "1 interface facets across it (3 nodes pressed" in lines[0]
    # 3D: a patch of 7 × 7 P2 nodes is 3 facets across; of 5 × 5, 2 (warned); P1 5 × 5, 4.
    square = {"hertz_contact_length": 1e-4}
    assert resolution_warnings(square, inputs, 3, {"contact_hertz_pressure": np.ones(49)}) \
        == []
    assert len(resolution_warnings(square, inputs, 3,
                                   {"contact_hertz_pressure": np.ones(25)})) == 1
    # Touching, nothing pressed (a 3D block on its slab with gravity = [0, 0, 0], the
    # contact measured 0.075 m² at zero pressure): no pressure to resolve. It was told
    # "0 interface facets across it (0 nodes pressed ...): refine the surfaces there".
    touching = {"hertz_contact_length": 0.075}
    assert resolution_warnings(touching, inputs, 3, {"contact_hertz_pressure": np.zeros(49)}) \
        == []
    assert resolution_warnings(row, inputs, 2, {"contact_hertz_pressure": np.zeros(60)}) == []
    assert resolution_warnings(square, inputs, 3, {"contact_hertz_pressure": np.ones(25)},
                               degree=1) == []
