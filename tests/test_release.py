"""A body that friction cannot hold in the initial state, held and released (issue 20).

Block ``a`` (W × H) rests on a base ``b`` of the same width fixed at its bottom,
μ = 0.3, the paper's χ = 1e-10 m/s, run from case files through the command line:

- **incline**: gravity tilted by θ = 25° > atan μ = 16.7°, ``g = (g sinθ, −g cosθ)``;
- **push**: gravity vertical and a side push F = 1.5 μN on the block's left face,
  present in the static state (a constant load).

No frictional equilibrium exists: the block is held (bonded) up to t = 0 and released.
A rigid block then slides with the constant acceleration a = (F_T − μN)/m, ½ a t²
(incline: a = g (sinθ − μ cosθ); push: a = ½ μ g; Meriam & Kraige, *Engineering
Mechanics: Dynamics*, §3/4, block on a rough plane). The run must start the slide at
t = 0 with the friction of sliding, μN, at every step: from the held state at rest the
regularised law carried no friction at the first step (v = 0), so that a₀ was the
frictionless acceleration and GN22 kept (1 − β₁)Δt μN/m of it as a velocity error, an
error linear in Δt (+1.4 % at Δt = 1e-3), and the elastic block's release of the bonded
shear reversed the slip velocities at the first steps. The block here is soft
(E = 1e9, as tests/blocks.two_block_case): that release is then large.
"""

from __future__ import annotations

import csv
import json
import math
import pathlib

import pytest
from blocks import two_block_case, two_rectangles
from mpi4py import MPI

from breakwater import cli

COMM = MPI.COMM_WORLD

W, H = 0.2, 0.05              # block and base (m)
ρ, g, μ = 2000.0, 9.81, 0.3   # the density of two_block_case
θ = math.radians(25.0)
T_END = 0.1                   # s
GRAVITY = {"incline": (g * math.sin(θ), -g * math.cos(θ)), "push": (0.0, -g)}
PUSH = 1.5 * μ * ρ * g * W * H  # N/m on the block's left face (out_of_plane_length 1 m)


def acceleration(case: str) -> float:
    """The rigid block's acceleration along x (m/s²)."""
    gx, gy = GRAVITY[case]
    m = ρ * W * H
    push = PUSH if case == "push" else 0.0
    return (m * gx + push - μ * m * abs(gy)) / m


@pytest.fixture(scope="module")
def mesh_path(folder: pathlib.Path) -> pathlib.Path:
    return two_rectangles(folder / "block.msh", COMM, a=(W, H), b=(W, H), h=0.025)


def _case_file(folder: pathlib.Path, mesh: pathlib.Path, case: str) -> pathlib.Path:
    gx, gy = GRAVITY[case]
    load = (f'[loads.push]\ngroup = "a_left"\nforce = {PUSH!r}\ndirection = [1.0, 0.0]\n'
            if case == "push" else "")
    tail = f'''{load}
[output]
field_interval = 0
figures = false
[output.pair_probes.corner]
pair = "interface"
group = "a_corner"
'''
    path = folder / f"{case}.toml"
    if COMM.rank == 0:
        text = two_block_case(mesh, f'name = "{case}"\ngravity = [{gx!r}, {gy!r}]', tail)
        path.write_text(text.replace('penalty = 1e12', f'penalty = 1e12\nfriction = {μ}\n'
                                     'regularisation = 1e-10'))
    COMM.barrier()
    return path


@pytest.mark.parametrize("dt", [1e-3, 1e-4])
@pytest.mark.parametrize("case", ["incline", "push"])
def test_released_block_slides_as_the_rigid_block(case: str, dt: float, mesh_path: pathlib.Path,
                                                  folder: pathlib.Path) -> None:
    out = folder / f"{case}_{dt:g}"
    code = cli.main(["run", str(_case_file(folder, mesh_path, case)), "--out", str(out),
                     "--quiet", "--no-progress", "--set", f"time.dt={dt}",
                     "--set", f"time.end_time={T_END}"])
    assert code == 0
    static = json.loads((out / "summary.json").read_text())["static"]
    assert static["initial_state"] == "held" and static["held_bodies"] == ["a"]
    with (out / "history.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert float(rows[-1]["t"]) == pytest.approx(T_END)
    slide = float(rows[-1]["corner_slip"]) - float(rows[0]["corner_slip"])
    reference = 0.5 * acceleration(case) * T_END**2
    ratio = [-float(r["tangential_force_0"]) / float(r["normal_force_0"]) for r in rows]
    if COMM.rank == 0:
        print(f"\n{case}, dt = {dt:g} s: slide {slide:.6e} m, rigid block {reference:.6e} m "
              f"({slide / reference - 1:+.3%}); friction/normal at the first steps "
              + " ".join(f"{r:.5f}" for r in ratio[:6]))
    # Sliding from t = 0: the friction is μN at t = 0 and at every step after (the law
    # carries μp/sqrt(1 + 1e-4) at the release speed 100χ, μ(1 − 5e-5), and μp once the
    # block moves, as long as no slip velocity reverses). Measured 0.29999 then 0.30000.
    # Released from the held state at rest it was 0 at t = 0 and fell to 0.12-0.19 in
    # the first steps (incline and push, Δt = 1e-4); with the release velocities but the
    # held state's displacements (its bonded shear), to 0.23-0.26.
    assert ratio == pytest.approx([μ] * len(ratio), rel=1e-4)
    # The issue asks for 0.5 % at both Δt; GN22 is exact for a constant acceleration and
    # the block starts in the motion of sliding, so the slide is the rigid block's but
    # for the release speed's 100χ T = 1e-9 m (1.4e-7 of it) and the corner's elastic
    # offset: measured +4e-7 to +8e-7 at both Δt (before: +1.44 %, +0.39 % incline and
    # +1.81 %, +0.48 % push at Δt = 1e-3, 1e-4). 1e-4 bounds it with margin.
    assert slide == pytest.approx(reference, rel=1e-4)
