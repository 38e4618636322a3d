"""A body that friction cannot hold in the initial state, held and released (issue 20).

Block ``a`` (W × H) rests on a base ``b`` of the same width fixed at its bottom,
μ = 0.3, the paper's χ = 1e-10 m/s, run from case files through the command line:

- **incline**: gravity tilted by θ = 25° > atan μ = 16.7°, ``g = (g sinθ, −g cosθ)``;
- **push**: gravity vertical and a side push F = 1.5 μN on the block's left face,
  present in the static state (a constant load).

Both with the conforming pair of tests/blocks.py (:mod:`breakwater.statics.initial`) and with
a general pair on the bodies meshed apart, the block on a wider base (as
tests/test_relaxation.py; :mod:`breakwater.statics.relaxation`). No frictional equilibrium
exists: the block is held up to t = 0 and released.
A rigid block then slides with the constant acceleration a = (F_T − μN)/m, ½ a t²
(incline: a = g (sinθ − μ cosθ); push: a = ½ μ g; Meriam & Kraige, *Engineering
Mechanics: Dynamics*, §3/4, block on a rough plane). The run must start the slide at
t = 0 with the friction of sliding, μN, at every step: from the held state at rest the
regularised law carried no friction at the first step (v = 0), so that a₀ was the
frictionless acceleration and GN22 kept (1 − β₁)Δt μN/m of it as a velocity error, an
error linear in Δt (+1.4 % at Δt = 1e-3), and the elastic block's release of the bonded
shear reversed the slip velocities at the first steps. The block here is soft
(E = 1e9, as tests/blocks.two_block_case): that release is then large. The general
pair's slide is the block centre's displacement (a point probe), its ratio that of
the pair's resultant on the slave.
"""

from __future__ import annotations

import csv
import json
import math
import pathlib

import pytest
from blocks import two_block_case, two_rectangles
from breakwater.meshes.apart import Rectangle, rectangles
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
def meshes(folder: pathlib.Path) -> dict[str, pathlib.Path]:
    """The conforming mesh (tests/blocks.py) and the bodies meshed apart, the block on a
    wider base, element sizes 1.75:1 (as tests/test_relaxation.py)."""
    apart = rectangles(folder / "apart.msh", COMM, [Rectangle("b", -0.2, -H, 0.4, H, 8, 2),
                                                    Rectangle("a", -W / 2, 0.0, W, H, 7, 2)])
    return {"conforming": two_rectangles(folder / "block.msh", COMM, a=(W, H), b=(W, H),
                                         h=0.025), "general": apart}


GENERAL = '''
[contact.c]
slave = "a"
master = "b"
slave_surface = "a_bottom"
master_surface = "b_top"
penalty = 1e12
friction = {μ}
regularisation = 1e-10
[output.probes.centre]
body = "a"
point = [0.0, 0.025]
'''
CONFORMING = '''
[output.pair_probes.corner]
pair = "interface"
group = "a_corner"
'''


def _case_file(folder: pathlib.Path, mesh: pathlib.Path, case: str, pairs: str) -> pathlib.Path:
    gx, gy = GRAVITY[case]
    load = (f'[loads.push]\ngroup = "a_left"\nforce = {PUSH!r}\ndirection = [1.0, 0.0]\n'
            if case == "push" else "")
    tail = load + "[output]\nfield_interval = 0\nfigures = false\n"
    tail += GENERAL.format(μ=μ) if pairs == "general" else CONFORMING
    path = folder / f"{case}_{pairs}.toml"
    if COMM.rank == 0:
        text = two_block_case(mesh, f'name = "{case}"\ngravity = [{gx!r}, {gy!r}]', tail)
        if pairs == "general":  # the general pair instead of the conforming one
            start = text.index("[contact.interface]")
            text = text[:start] + text[text.index("[fixed.b_bottom]"):]
        else:
            text = text.replace('penalty = 1e12', f'penalty = 1e12\nfriction = {μ}\n'
                                'regularisation = 1e-10')
        path.write_text(text)
    COMM.barrier()
    return path


@pytest.mark.parametrize("dt", [1e-3, 1e-4])
@pytest.mark.parametrize("case", ["incline", "push"])
@pytest.mark.parametrize("pairs", ["conforming", "general"])
def test_released_block_slides_as_the_rigid_block(pairs: str, case: str, dt: float,
                                                  meshes: dict[str, pathlib.Path],
                                                  folder: pathlib.Path) -> None:
    out = folder / f"{case}_{pairs}_{dt:g}"
    code = cli.main(["run", str(_case_file(folder, meshes[pairs], case, pairs)), "--out", str(out),
                     "--quiet", "--no-progress", "--set", f"time.dt={dt}",
                     "--set", f"time.end_time={T_END}"])
    assert code == 0
    static = json.loads((out / "summary.json").read_text())["static"]
    assert static["initial_state"] == "held" and static["held_bodies"] == ["a"]
    with (out / "history.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert float(rows[-1]["t"]) == pytest.approx(T_END)
    if pairs == "general":  # the block's centre; the resultant on the slave
        slide = float(rows[-1]["centre_ux"]) - float(rows[0]["centre_ux"])
        ratio = [-float(r["c_force_x"]) / float(r["c_force_y"]) for r in rows]
    else:  # the slip at the block's corner; friction and normal resultants
        slide = float(rows[-1]["corner_slip"]) - float(rows[0]["corner_slip"])
        ratio = [-float(r["interface_tangential_force"]) / float(r["interface_normal_force"])
                 for r in rows]
    reference = 0.5 * acceleration(case) * T_END**2
    if COMM.rank == 0:
        print(f"\n{pairs} {case}, dt = {dt:g} s: slide {slide:.6e} m, rigid block "
              f"{reference:.6e} m ({slide / reference - 1:+.3%}); friction/normal, first steps "
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
    # offset: measured +4e-7 to +1.1e-6 at both Δt, both pairs (before: conforming
    # +1.44 %, +0.39 % incline and +1.81 %, +0.48 % push at Δt = 1e-3, 1e-4; general
    # push +1.27 % at Δt = 1e-3, with friction/normal 0.25 at the third step). 1e-4
    # bounds it with margin.
    assert slide == pytest.approx(reference, rel=1e-4)
