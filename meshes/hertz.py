"""A quarter cylinder on a block, meshed separately (the plane-strain Hertz problem).

The half-cylinder of radius R (axis and flat top at y = R; here its quarter x ≥ 0, by
symmetry) touches the block's top y = 0 at the origin; the two bodies are separate
surfaces of one gmsh file (disconnected components), refined near the origin, so that
their meshes do not match (:mod:`breakwater.contact.general`). Physical groups:

- ``cylinder`` (cells): ``cylinder_contact`` (the arc within ``contact_angle`` of the
  bottom), ``cylinder_arc`` (the rest of the arc), ``cylinder_top`` (the flat top
  y = R), ``cylinder_axis`` (x = 0);
- ``block`` (cells): ``block_top``, ``block_bottom``, ``block_right``, ``block_axis``.

:func:`hertz3d` is the 3-D point contact: a quarter of the lower hemisphere (x ≥ 0,
z ≥ 0, centre at (0, R, 0)) on a quarter block, tetrahedra. Groups: ``sphere``,
``sphere_contact`` (the curved face below the ``cap`` height), ``sphere_surface`` (the
rest of it), ``sphere_top`` (y = R), ``sphere_x0``,
``sphere_z0``; ``block``, ``block_top``, ``block_bottom``, ``block_x0``, ``block_z0``.
"""

from __future__ import annotations

import math
import pathlib

import gmsh
from mpi4py import MPI

from breakwater.common.gmshtools import gmsh_session
from breakwater.common.parallel import on_rank_zero

__all__ = ["hertz", "hertz3d"]


def hertz(path: str | pathlib.Path, comm: MPI.Comm, radius: float, width: float,
          depth: float, fine: float, coarse: float, fine_zone: float,
          contact_angle: float = 30.0, overlap: float = 0.0,
          order: int = 2) -> pathlib.Path:
    """Write the mesh (rank 0 writes; collective).

    Args:
        path: Output ``.msh`` (the same on all ranks).
        comm: Communicator.
        radius: Cylinder radius R (m); its axis is at (0, R).
        width: Block width (m), ``[0, width] × [−depth, 0]``.
        depth: Block depth (m).
        fine: Element size within ``fine_zone`` of the origin (m).
        coarse: Element size far from it (m).
        fine_zone: Radius of the refined zone (m); the size grows linearly to
            ``coarse`` over the next 4 ``fine_zone``.
        contact_angle: Angle (degrees from the bottom) of the ``cylinder_contact`` arc.
        overlap: The cylinder is moved down by this (m): it starts with a contact zone
            (its vertical position is free, so the loaded equilibrium does not depend
            on it), where a point contact would give Newton no vertical stiffness.
        order: Geometric order (2: the arc's mid-nodes on the circle).

    Returns:
        The path.
    """
    path = pathlib.Path(path)
    def write() -> str:
        with gmsh_session(model="hertz"):
            geo = gmsh.model.geo
            R, θ = radius, math.radians(contact_angle)
            y0 = -overlap
            centre = geo.addPoint(0, y0 + R, 0)
            bottom = geo.addPoint(0, y0, 0)
            a = geo.addPoint(R * math.sin(θ), y0 + R - R * math.cos(θ), 0)
            east = geo.addPoint(R, y0 + R, 0)
            cyl = [geo.addCircleArc(bottom, centre, a), geo.addCircleArc(a, centre, east),
                   geo.addLine(east, centre), geo.addLine(centre, bottom)]
            cyl_surface = geo.addPlaneSurface([geo.addCurveLoop(cyl)])
            corners = [geo.addPoint(x, y, 0) for x, y in
                       ((0, -depth), (width, -depth), (width, 0), (0, 0))]
            blk = [geo.addLine(corners[k], corners[(k + 1) % 4]) for k in range(4)]
            blk_surface = geo.addPlaneSurface([geo.addCurveLoop(blk)])
            geo.synchronize()
            field = gmsh.model.mesh.field
            distance = field.add("Distance")
            field.setNumbers(distance, "PointsList", [bottom, corners[3]])
            threshold = field.add("Threshold")
            field.setNumber(threshold, "InField", distance)
            field.setNumber(threshold, "SizeMin", fine)
            field.setNumber(threshold, "SizeMax", coarse)
            field.setNumber(threshold, "DistMin", fine_zone)
            field.setNumber(threshold, "DistMax", 5 * fine_zone)
            field.setAsBackgroundMesh(threshold)
            for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints",
                           "MeshSizeFromCurvature"):
                gmsh.option.setNumber(f"Mesh.{option}", 0)
            gmsh.model.addPhysicalGroup(2, [cyl_surface], name="cylinder")
            for line, name in zip(cyl, ("contact", "arc", "top", "axis"), strict=True):
                gmsh.model.addPhysicalGroup(1, [line], name=f"cylinder_{name}")
            gmsh.model.addPhysicalGroup(2, [blk_surface], name="block")
            for line, name in zip(blk, ("bottom", "right", "top", "axis"), strict=True):
                gmsh.model.addPhysicalGroup(1, [line], name=f"block_{name}")
            gmsh.model.mesh.generate(2)
            gmsh.model.mesh.setOrder(order)
            gmsh.write(str(path))
        return str(path)

    return pathlib.Path(on_rank_zero(comm, write))  # rank 0's path, or its error


def hertz3d(path: str | pathlib.Path, comm: MPI.Comm, radius: float, width: float,
            depth: float, fine: float, coarse: float, fine_zone: float,
            overlap: float = 0.0, order: int = 2, cap: float = 0.3) -> pathlib.Path:
    """Write the 3-D mesh (rank 0 writes; collective); the arguments as :func:`hertz`'s.

    The sphere is cut at the height ``cap`` × R above its bottom into two volumes (one
    body): ``sphere_contact`` is the curved face below, ``sphere_surface`` the rest (a
    contact pair's slave surface need not be the whole sphere: its unknowns are the
    fast solver's interface).

    The block is ``[0, width] × [−depth, 0] × [0, width]``; the element size is
    ``fine`` within ``fine_zone`` of the origin, growing by a quarter of the distance
    beyond, up to ``coarse``.
    """
    path = pathlib.Path(path)

    def write() -> str:
        with gmsh_session(model="hertz3d"):
            occ = gmsh.model.occ
            R, y0 = radius, -overlap
            ball = occ.addSphere(0, y0 + R, 0, R)
            cut = occ.addBox(0, y0, 0, R, R, R)
            (quarter,), _ = occ.intersect([(3, ball)], [(3, cut)])
            low = occ.addBox(0, y0, 0, R, cap * R, R)
            parts, children = occ.fragment([quarter], [(3, low)])
            sphere = [t for d, t in children[0] if d == 3]  # the quarter's pieces
            occ.remove([(d, t) for d, t in parts if d == 3 and t not in sphere],
                       recursive=True)  # the box beyond the sphere
            block = occ.addBox(0, -depth, 0, width, depth, width)
            occ.synchronize()
            bodies = {"sphere": sphere, "block": [block]}
            planes = {"sphere": (("top", 1, y0 + R), ("x0", 0, 0.0), ("z0", 2, 0.0)),
                      "block": (("top", 1, 0.0), ("bottom", 1, -depth), ("x0", 0, 0.0),
                                ("z0", 2, 0.0))}
            for name, vs in bodies.items():
                gmsh.model.addPhysicalGroup(3, vs, name=name)
                faces = [f for _, f in gmsh.model.getBoundary([(3, v) for v in vs],
                                                               oriented=False)]
                used = set()
                for side, axis, at in planes[name]:
                    tags = [f for f in faces if gmsh.model.getType(2, f) == "Plane"
                            and abs(occ.getCenterOfMass(2, f)[axis] - at) < 1e-9]
                    used.update(tags)
                    gmsh.model.addPhysicalGroup(2, tags, name=f"{name}_{side}")
                if name == "sphere":
                    curved = [f for f in faces if f not in used]
                    below = [f for f in curved if occ.getCenterOfMass(2, f)[1] < y0 + cap * R]
                    gmsh.model.addPhysicalGroup(2, below, name="sphere_contact")
                    gmsh.model.addPhysicalGroup(2, [f for f in curved if f not in below],
                                                name="sphere_surface")
            field = gmsh.model.mesh.field
            size = field.add("MathEval")
            field.setString(size, "F", f"Min({coarse}, {fine} + 0.25 * Max(0, "
                            f"Sqrt(x^2 + y^2 + z^2) - {fine_zone}))")
            field.setAsBackgroundMesh(size)
            for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints",
                           "MeshSizeFromCurvature"):
                gmsh.option.setNumber(f"Mesh.{option}", 0)
            gmsh.model.mesh.generate(3)
            gmsh.model.mesh.setOrder(order)
            gmsh.write(str(path))
        return str(path)

    return pathlib.Path(on_rank_zero(comm, write))  # rank 0's path, or its error
