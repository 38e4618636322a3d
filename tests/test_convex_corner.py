"""A general pair in a master surface's corners: a retaining wall's shear key in its notch.

An L-shaped concrete wall (base 3 m × 0.5 m, stem 0.5 m × 3 m at its heel, a shear key
0.4 m × 0.4 m under the middle; E = 30 GPa) on a soil layer (12 m × 5 m, E = 50 MPa)
whose top has a notch of the key's size, meshed apart (the key's sides touching the
notch's sides), gravity only. Found walking the user path (`python -m breakwater run`
on the wall's case): the static state failed, "no static equilibrium, not even with the
bodies held", with or without friction:

- the notch's top edges are convex corners of the master surface: a point on the key's
  side pressed into both the notch's side and the crest beside it lies nearer the
  crest, by the penetration, and the nearest projection alone took the crest or the
  notch's bottom (master normals at 90° to the point's), alternating from one iterate to
  the next (a Newton cycle of 2 iterates). A point now projects only onto master facets
  that face it (:func:`breakwater.contact.searchkernels.slave_normals`);
- the notch's bottom corners are concave: a point of the key's bottom pressed past
  both the notch's bottom and side has no projection on either, and the nearest facing
  facet was the crest, 0.4 m above it: a "penetration" of 0.4 m, a force of 4e9 N/m
  (the held stage's Newton residual 3e12). A point now projects only within the depth
  the pair sees (:func:`breakwater.contact.penetration.allowed_depth`), and the step's
  penetration check leaves out a node that starts the step beyond it (it refused the
  pseudo step: "slave node at (-0.1999, -0.4045) m ends the step 0.4 m inside the master").

Serially and under ``mpiexec -n 2``.

Serially and under ``mpiexec -n 2``.
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater.contact import searchkernels
from breakwater.contact.general import SurfaceContact
from breakwater.contact.surfaces import SurfacePair
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Fixed, Material
from breakwater.statics.initial import initial_state
from breakwater.stepping.gn22 import GN22

COMM = MPI.COMM_WORLD
SOIL = Material(1800.0, 0.3, young_modulus=5e7)
CONCRETE = Material(2400.0, 0.2, young_modulus=3e10)

GEO = """
Mesh.Algorithm = 6;
hw = 0.3; hs = 1.0; hi = 0.4;
// wall
Point(1) = {-1.5, 0, 0, hw}; Point(2) = {-0.2, 0, 0, hw}; Point(3) = {-0.2, -0.4, 0, hw};
Point(4) = {0.2, -0.4, 0, hw}; Point(5) = {0.2, 0, 0, hw}; Point(6) = {1.5, 0, 0, hw};
Point(7) = {1.5, 0.5, 0, hw}; Point(8) = {-1.0, 0.5, 0, hw}; Point(9) = {-1.0, 3.5, 0, hw};
Point(10) = {-1.5, 3.5, 0, hw};
For i In {1:9}
  Line(i) = {i, i+1};
EndFor
Line(10) = {10, 1};
Curve Loop(1) = {1:10}; Plane Surface(1) = {1};
// soil
Point(21) = {-6, -5, 0, 1.0}; Point(22) = {6, -5, 0, 1.0}; Point(23) = {6, 0, 0, hs};
Point(24) = {1.5, 0, 0, hi}; Point(25) = {0.2, 0, 0, hi}; Point(26) = {0.2, -0.4, 0, hi};
Point(27) = {-0.2, -0.4, 0, hi}; Point(28) = {-0.2, 0, 0, hi}; Point(29) = {-1.5, 0, 0, hi};
Point(30) = {-6, 0, 0, hs};
For i In {21:29}
  Line(i) = {i, i+1};
EndFor
Line(30) = {30, 21};
Curve Loop(2) = {21:30}; Plane Surface(2) = {2};
Physical Surface("wall") = {1};
Physical Surface("soil") = {2};
Physical Curve("wall_base") = {1, 2, 3, 4, 5};
Physical Curve("wall_back") = {10};
Physical Curve("soil_top") = {23:29};
Physical Curve("soil_top_far") = {29};
Physical Curve("soil_bottom") = {21};
Physical Curve("soil_sides") = {22, 30};
Physical Point("heel") = {1};
Physical Point("toe") = {6};
Physical Point("stem_top") = {10};
"""


def test_a_corner_point_projects_onto_the_facet_facing_it() -> None:
    """The search alone: the master's convex corner at the origin (a crest y = 0 for
    x < 0 and a side x = 0 for y < 0; the master body in x < 0, y < 0), a slave facet
    pressing leftwards (outward normal −x) into the side by 1e-4 m, 5e-5 m below the
    crest. The nearest projection is the crest (5e-5 m) and pushed the point up; the
    side (1e-4 m) faces it and pushes it back right."""
    crest = [[0.0, 0.0], [-0.1, 0.0]]  # (t_y, −t_x) = (0, 0.1): up, out of the master
    side = [[0.0, -0.1], [0.0, 0.0]]  # (t_y, −t_x) = (0.1, 0): +x
    mX = np.array([crest, side])
    sX = np.array([[[-1e-4, -0.1], [-1e-4, 0.1]]])  # (t_y, −t_x) = (0.2, 0): +x, inward
    pos_s = np.full((1, 2, 2), -1, np.int64)
    pos_m = np.full((2, 2, 2), -1, np.int64)
    u1 = np.zeros(1)
    xi = np.array([-5e-4])  # the point (−1e-4, −5e-5)
    fixed = (np.zeros(1, np.int64), xi, np.ones(1), searchkernels.shape_values(xi, 2))
    g, w = np.polynomial.legendre.leggauss(2)
    every = np.ones(2, bool)

    def facet(outward: float) -> int:
        out = searchkernels.search(sX, mX, pos_s, pos_m, u1, False, *fixed, 0.2, 1e-9, g, w,
                                   every, np.array([outward]), np.full(2, 0.1))
        np.testing.assert_allclose(out[1][0], [-1e-4, -5e-5], atol=1e-15)
        return int(out[5][0]) if len(out[3]) else -1

    assert facet(-1.0) == 1  # outward −x: the side
    # Its normal reversed (+x, turned away from the side): the crest is at 90°, no
    # facet faces it.
    assert facet(1.0) == -1


@pytest.mark.parametrize("friction", [0.0, 0.6])
def test_wall_with_a_shear_key_finds_its_static_state(folder: pathlib.Path,
                                                       friction: float) -> None:
    """The static state exists (frictionless: the key holds the wall sideways) and the
    contact carries the weight, with no net horizontal force."""
    geo = folder / "wall.geo"
    if COMM.rank == 0:
        geo.write_text(GEO)
    COMM.barrier()
    pair = SurfacePair("c", "wall", "soil", "wall_base", "soil_top", 1e10, friction=friction)
    model = ContactModel(read_mesh(geo, COMM), [Body("soil", SOIL), Body("wall", CONCRETE)],
                         fixed=[Fixed("soil_bottom"), Fixed("soil_sides", (0,))],
                         gravity=(0.0, -9.81), surface_pairs=[pair])
    model.set_time(0.0)
    state = initial_state(model)  # before: ConvergenceError, a cycle of 2 iterates
    s = GN22(model, 1e-4)
    s.initialise(state.u, state.v)
    contact = s.surfaces[-1]
    assert isinstance(contact, SurfaceContact)
    normal, friction = contact.resultants()
    s.destroy()
    weight = model.weight()[1]
    total = normal + friction
    # Measured 1e-12 (frictionless) and 1.4e-6 (μ = 0.6: the static tolerance, 1e-9 of
    # the load norm, which the soil's weight dominates, 14 times the wall's, and the
    # stick tangent μλ/χ) of the weight; 1e-5 allows 7x. The x resultant is the balance
    # of the key's two sides and of the base's friction (measured 4e-7).
    assert abs(total[1] - weight) < 1e-5 * weight, (normal, friction, weight)
    assert abs(total[0]) < 1e-5 * weight, (normal, friction)
