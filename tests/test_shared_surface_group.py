"""A general pair whose surfaces are one facet group on both bodies, meshed apart.

`docs/general-contact.md` ("On a conforming interface") gives a general pair the same
group as slave and master surface, each side taking its facets on its own body. On
bodies meshed apart (a user's gmsh file with one group "faces" for the block's bottom
and the base's top) the static state and the pair ran, but the pair's ParaView fields
were built on the whole group's facets, whose master nodes are no slave nodes: the run
failed after its static state, exit 1, "the mesh differs from the checkpoint's: no
stored node at [...] (14 nodes unmatched)" (found on the user path of issue 23). The
fields now take the slave body's facets of the group
(:func:`breakwater.outputs.writers.group_fields`).

Serially and under ``mpiexec -n 2``.
"""

from __future__ import annotations

import json
import pathlib

from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater import cli

COMM = MPI.COMM_WORLD

GEO = """
Point(1) = {-0.2, -0.05, 0, 0.04}; Point(2) = {0.2, -0.05, 0, 0.04};
Point(3) = {0.2, 0, 0, 0.04}; Point(4) = {-0.2, 0, 0, 0.04};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1:4}; Plane Surface(1) = {1};
Point(5) = {-0.1, 0, 0, 0.025}; Point(6) = {0.1, 0, 0, 0.025};
Point(7) = {0.1, 0.05, 0, 0.025}; Point(8) = {-0.1, 0.05, 0, 0.025};
Line(5) = {5, 6}; Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 5};
Curve Loop(2) = {5:8}; Plane Surface(2) = {2};
Physical Surface("base") = {1};
Physical Surface("block") = {2};
Physical Curve("base_bottom") = {1};
Physical Curve("faces") = {3, 5};   // the base's top and the block's bottom: one group
"""

CASE = """name = "shared"
[mesh]
source = "shared.geo"
[bodies.base]
density = 2400.0
poisson = 0.2
young_modulus = 3.0e10
[bodies.block]
density = 2400.0
poisson = 0.2
young_modulus = 3.0e10
[fixed.base_bottom]
[contact.c]
slave = "block"
master = "base"
slave_surface = "faces"
master_surface = "faces"
penalty = 1.0e13
friction = 0.5
[time]
dt = 1.0e-4
end_time = 2.0e-4
[output]
figures = false
field_interval = 1
"""


def test_one_group_on_both_bodies_apart(folder: pathlib.Path) -> None:
    """The run finishes with the pair's fields; the contact carries the block's weight."""
    case = folder / "shared.toml"
    if COMM.rank == 0:
        (folder / "shared.geo").write_text(GEO)
        case.write_text(CASE)
    COMM.barrier()
    out = folder / "out"
    # Before: exit 1 after the static state ("the mesh differs from the checkpoint's").
    assert cli.main(["run", str(case), "--out", str(out), "--quiet", "--no-progress"]) == 0
    assert (out / "contact_c.bp").is_dir()
    with open(out / "summary.json", encoding="utf-8") as f:
        static = json.load(f)["static"]
    # ∫p of a flat interface: the weight to the static tolerance (measured 1e-9); 1e-6
    # allows the penalty's tilt of the deformed normals.
    assert abs(static["resultant_over_weight"] - 1.0) < 1e-6, static
