"""A user's own 3D mesh: a .geo written by hand, not breakwater's builders.

``tests/bad_cases/run/h_tet_slab.geo``: a 0.3 x 0.2 x 0.25 m block on a 0.8 x 0.1 x
0.5 m slab, linear tetrahedra of gmsh's default 3D algorithm (a few hundred cells), the
slab's faces z = 0 and 0.5 one group (side walls), the block's top corner a point group.
"""

from __future__ import annotations

import json
import pathlib

import pytest
from mpi4py import MPI

from breakwater import cli
from breakwater.outputs.summary import format_report

COMM = MPI.COMM_WORLD
GEO = pathlib.Path(__file__).parent / "bad_cases" / "run" / "h_tet_slab.geo"

CASE = f'''name = "user3d"
gravity = [0.0, -9.81, 0.0]
mesh.source = "{GEO}"
mesh.degree = 1
[bodies.block]
density = 2314.0
poisson = 0.2
shear_modulus = 2.0e9
[bodies.slab]
density = 2314.0
poisson = 0.2
shear_modulus = 2.0e9
[calibration]
enabled = false
[contact.interface]
slave = "block"
master = "slab"
penalty = 1.0e11
friction = 0.6
[fixed.slab_bottom]
[fixed.slab_sides]      # the side walls: rollers
components = [2]
[fixed.top_corner]      # a point group
components = [2]
[time]
dt = 1.0e-3
end_time = 2.0e-3
[output]
figures = false
field_interval = 0
'''


def test_fixed_groups_are_reported(shared_dir: pathlib.Path,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    # What holds the bodies is in summary.json and the report: each fixed group's
    # components and, per body, its area (the boxes' faces: exact to round-off) or its
    # points. Before, neither said which groups were fixed, nor that the side walls
    # were rollers (only case.toml, the input, did).
    path = shared_dir / "user3d.toml"
    if COMM.rank == 0:
        path.write_text(CASE)
    COMM.barrier()
    out = shared_dir / "out"
    code = cli.main(["run", str(path), "--out", str(out), "--quiet", "--no-progress"])
    assert code == 0, capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    fixed = summary["fixed"]
    assert list(fixed) == ["slab_bottom", "slab_sides", "top_corner"]
    assert fixed["slab_bottom"]["components"] == ["x", "y", "z"]
    assert fixed["slab_bottom"]["bodies"]["slab"]["area"] == pytest.approx(0.8 * 0.5, rel=1e-12)
    assert fixed["slab_sides"]["components"] == ["z"]
    assert list(fixed["slab_sides"]["bodies"]) == ["slab"]
    assert fixed["slab_sides"]["bodies"]["slab"]["area"] == pytest.approx(2 * 0.8 * 0.1,
                                                                          rel=1e-12)
    assert fixed["top_corner"] == {"components": ["z"], "bodies": {"block": {"points": 1}}}
    line = next(x for x in format_report(summary, out).splitlines() if "fixed:" in x)
    assert line == ("  fixed: slab_bottom xyz (slab 0.4 m²); slab_sides z (slab 0.16 m²); "
                    "top_corner z (block 1 point)")


def test_a_block_friction_cannot_hold_is_told_in_newtons(
        shared_dir: pathlib.Path, capsys: pytest.CaptureFixture[str]) -> None:
    # Gravity tilted past the friction angle (tan = 6/7.76 = 0.77 > μ = 0.6): the block
    # is held in the static state and released at t = 0, and the warning gives the 3D
    # block's forces in N, T = ρ V g_x, μN = μ ρ V g_y (the message's four digits); it
    # said N/m, the plane-strain unit.
    path = shared_dir / "tilted.toml"
    if COMM.rank == 0:
        path.write_text(CASE.replace("gravity = [0.0, -9.81, 0.0]", "gravity = [6.0, -7.76, 0.0]"))
    COMM.barrier()
    code = cli.main(["run", str(path), "--out", str(shared_dir / "out"), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 0, err
    if COMM.rank == 0:
        mass = 2314.0 * 0.3 * 0.2 * 0.25
        assert (f"cannot be held by friction on 'interface' (tangential force "
                f"{mass * 6.0:.4g} N, μN = {0.6 * mass * 7.76:.4g} N)") in err, err


def test_gravity_and_initial_velocity_are_reported(
        shared_dir: pathlib.Path, capsys: pytest.CaptureFixture[str]) -> None:
    # summary.json says what the run applied: the gravity vector, and each moving body's
    # initial velocity and momentum m v beside its mass (neither was in it: only the
    # input case.toml said them). The kinetic energy at t = 0 is ½ m |v|² of the block
    # (the slab at rest), m = ρ × 0.3 × 0.2 × 0.25 m³: to round-off.
    path = shared_dir / "moving.toml"
    if COMM.rank == 0:
        path.write_text(CASE)
    COMM.barrier()
    out = shared_dir / "out"
    v = [0.1, 0.0, 0.0]  # (the block's top corner is held in z)
    code = cli.main(["run", str(path), "--out", str(out), "--quiet", "--no-progress",
                     "--set", f"bodies.block.initial_velocity={v}"])
    assert code == 0, capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["gravity"] == [0.0, -9.81, 0.0]
    block = summary["mesh"]["bodies"]["block"]
    mass = 2314.0 * 0.3 * 0.2 * 0.25
    assert block["mass"] == pytest.approx(mass, rel=1e-12)
    assert block["initial_velocity"] == v
    assert block["initial_momentum"] == pytest.approx([mass * c for c in v], rel=1e-12)
    assert "initial_velocity" not in summary["mesh"]["bodies"]["slab"]  # at rest
    history = (out / "history.csv").read_text().splitlines()
    names, first = history[0].split(","), history[1].split(",")
    kinetic = float(first[names.index("kinetic")])
    assert kinetic == pytest.approx(0.5 * mass * v[0] ** 2, rel=1e-12)
