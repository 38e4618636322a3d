"""A block on a conforming pair held up to t = 0 between rollers, released (issue list).

Block ``a`` (0.2 × 0.05 × 0.2 m) on block ``b`` of :func:`blocks3d.block_pair` (one
conforming interface, μ = 0.3, the paper's χ = 1e-10 m/s), its faces z = 0 and
z = 0.2 (``a_sides``) on rollers (held along z), ``b_bottom`` fixed, pushed on its face
x = −0.1 by a uniform traction along (1, 0, 1) whose x component is F = 1.5 μN: no
frictional static state, the block is held up to t = 0 and released
(:func:`breakwater.statics.initial._release`). The push's z component goes into the
rollers and the held interface's shear has a component along z.
"""

from __future__ import annotations

import pathlib
import sys

import numpy as np
import pytest
import ufl
from dolfinx import fem
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, ContactPair, Fixed, Material, SurfaceLoad
from breakwater.statics.initial import initial_state
from breakwater.stepping.gn22 import GN22

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from blocks3d import block_pair

COMM = MPI.COMM_WORLD

L, H = 0.2, 0.05           # block width and depth (x, z), height (y) (m)
ρ, g, μ = 2000.0, 9.81, 0.3
MASS = ρ * L * H * L
PUSH = 1.5 * μ * MASS * g  # the push's x component (N)


def test_conforming_block_on_rollers_released_along_its_free_directions(
        folder: pathlib.Path) -> None:
    """Released, the block slides along x with a = (F − μN)/m = ½ μ g = 1.4715 m/s²
    (Meriam & Kraige, *Engineering Mechanics: Dynamics*, §3/4, block on a rough plane;
    the rollers carry the push along z), and its velocity has no z component.

    The sliding direction d is the held shear less its component along z, which the
    rollers hold (:func:`breakwater.statics.release.free_part`, as the general pairs'
    test_pair3d_friction.test_held_block_on_rollers_released_sliding). Before, d was the
    held shear itself: the release velocities had a z component (RELEASE χ d_z at
    every slave node, the rollers' nodes included) and the state of incipient sliding
    accelerated the block along d, z included, with α from the resultant along d,
    the push's z component in it (the rollers' reaction is not): measured a₀ =
    (1.524, 0, 0.674) m/s² (+3.6 % along x) and |v_z| up to 1.9e-9 m/s at t = 0.

    Asked: the block's velocity at t = 0 nil along z (exactly: d_z = 0 gives a tangent
    with no z component on the plane y = const), and its acceleration at t = 0 (GN22's
    a₀, the mass-weighted mean) (F − μN)/m along x to 1 % (the elastic block's
    response to the release, as the general pairs' test; measured 1.0e-4), nil along z
    to 1e-3 of it (measured 1.5e-11). 8 s alone on this machine once compiled."""
    path = block_pair(folder / "rollers_conforming.msh", COMM, L, (H, H), 0.05, thickness=L,
                      layers=4)
    mat = Material(ρ, 0.25, young_modulus=1e9)
    traction = PUSH / (H * L)
    model = ContactModel(
        read_mesh(path, COMM), [Body("a", mat), Body("b", mat)],
        [ContactPair("interface", "a", "b", penalty=1e12, friction=μ)],
        [Fixed("b_bottom"), Fixed("a_sides", (2,))],
        [SurfaceLoad("a_left", (traction, 0.0, traction), lambda t: 1.0)],
        gravity=(0.0, -g, 0.0))
    model.set_time(0.0)
    state = initial_state(model)
    s = GN22(model, 1e-3)
    s.initialise(state.u, state.v)
    block = model.bodies[0].submesh

    def centre(f: fem.Function) -> np.ndarray:
        return np.array([COMM.allreduce(fem.assemble_scalar(fem.form(
            ρ * f[k] * ufl.dx(domain=block))), op=MPI.SUM) for k in range(3)]) / MASS

    a0, v0 = centre(s.a[0]), centre(state.v[0])
    vz = COMM.allreduce(float(np.abs(state.v[0].x.array.reshape(-1, 3)[:, 2]).max(initial=0.0)),
                        op=MPI.MAX)
    expected = (PUSH - μ * MASS * g) / MASS
    if COMM.rank == 0:
        print(f"\nconforming rollers: a0 = {a0} (expected {expected:.6g} along x), "
              f"v0 = {v0}, largest |v_z| {vz:.3g}")
    s.destroy()
    assert state.kind == "held" and state.held == ["a"]
    assert v0[0] > 0
    assert vz == 0.0
    assert a0[0] == pytest.approx(expected, rel=0.01)
    assert abs(a0[2]) < 1e-3 * expected
