"""Bodies meshed separately in one gmsh file (disconnected components), for general pairs.

Each body is its own surface with its own element size, so the meshes of two bodies in
contact need not match (:mod:`breakwater.contact.general`); each side of a body is an
exterior facet group. Rectangles are structured (transfinite) triangles; boxes (3-D)
unstructured tetrahedra of a given size.
"""

from __future__ import annotations

import pathlib
from collections.abc import Sequence
from dataclasses import dataclass

import gmsh
from mpi4py import MPI

from breakwater.common.gmshtools import gmsh_session
from breakwater.common.parallel import on_rank_zero

__all__ = ["Box", "Rectangle", "boxes", "rectangles"]


@dataclass(frozen=True)
class Rectangle:
    """A rectangular body ``[x0, x0 + width] × [y0, y0 + height]``.

    Its physical groups: ``name`` (cells) and ``name_bottom``, ``name_right``,
    ``name_top``, ``name_left`` (facets); with :func:`rectangles`' ``corners``, its
    corners ``name_bottom_left``, ``name_bottom_right``, ``name_top_right``,
    ``name_top_left`` (points).

    Attributes:
        name: Body name.
        x0: Left edge (m).
        y0: Bottom edge (m).
        width: Width (m).
        height: Height (m).
        nx: Elements along the width.
        ny: Elements along the height.
    """

    name: str
    x0: float
    y0: float
    width: float
    height: float
    nx: int
    ny: int


def rectangles(path: str | pathlib.Path, comm: MPI.Comm, bodies: Sequence[Rectangle],
               order: int = 1, corners: bool = False) -> pathlib.Path:
    """Write a mesh of separate rectangles (rank 0 writes; collective).

    Args:
        path: Output ``.msh`` (the same on all ranks).
        comm: Communicator.
        bodies: The rectangles.
        order: Geometric order of the elements.
        corners: Also name each rectangle's corners (point groups; the mesh is the
            same).

    Returns:
        The path.
    """
    path = pathlib.Path(path)
    def write() -> str:
        with gmsh_session(model="apart"):
            geo = gmsh.model.geo
            groups = []
            for b in bodies:
                corners = ((b.x0, b.y0), (b.x0 + b.width, b.y0),
                           (b.x0 + b.width, b.y0 + b.height), (b.x0, b.y0 + b.height))
                p = [geo.addPoint(x, y, 0) for x, y in corners]
                lines = [geo.addLine(p[k], p[(k + 1) % 4]) for k in range(4)]
                surface = geo.addPlaneSurface([geo.addCurveLoop(lines)])
                groups.append((b, p, lines, surface))
            geo.synchronize()
            for b, p, lines, surface in groups:
                for line, n in zip(lines, (b.nx, b.ny, b.nx, b.ny), strict=True):
                    gmsh.model.mesh.setTransfiniteCurve(line, n + 1)
                gmsh.model.mesh.setTransfiniteSurface(surface)
                gmsh.model.addPhysicalGroup(2, [surface], name=b.name)
                for line, side in zip(lines, ("bottom", "right", "top", "left"), strict=True):
                    gmsh.model.addPhysicalGroup(1, [line], name=f"{b.name}_{side}")
                if corners:
                    for point, corner in zip(p, ("bottom_left", "bottom_right", "top_right",
                                                 "top_left"), strict=True):
                        gmsh.model.addPhysicalGroup(0, [point], name=f"{b.name}_{corner}")
            gmsh.model.mesh.generate(2)
            gmsh.model.mesh.setOrder(order)
            gmsh.write(str(path))
        return str(path)

    return pathlib.Path(on_rank_zero(comm, write))  # rank 0's path, or its error


@dataclass(frozen=True)
class Box:
    """A box body ``[x0, x0 + size_x] × [y0, y0 + size_y] × [z0, z0 + size_z]`` (3-D, y up).

    Its physical groups: ``name`` (cells) and ``name_bottom`` (y min), ``name_top``,
    ``name_left`` (x min), ``name_right``, ``name_back`` (z min), ``name_front`` (faces).

    Attributes:
        name: Body name.
        corner: ``(x0, y0, z0)`` (m).
        size: ``(size_x, size_y, size_z)`` (m).
        h: Element size (m).
    """

    name: str
    corner: tuple[float, float, float]
    size: tuple[float, float, float]
    h: float


def boxes(path: str | pathlib.Path, comm: MPI.Comm, bodies: Sequence[Box], order: int = 2
          ) -> pathlib.Path:
    """Write a mesh of separate boxes of tetrahedra (rank 0 writes; collective).

    Args:
        path: Output ``.msh`` (the same on all ranks).
        comm: Communicator.
        bodies: The boxes (each meshed on its own, at its own size).
        order: Geometric order of the elements.

    Returns:
        The path.
    """
    path = pathlib.Path(path)
    sides = (("left", 0, 0), ("right", 0, 1), ("bottom", 1, 0), ("top", 1, 1),
             ("back", 2, 0), ("front", 2, 1))

    def write() -> str:
        with gmsh_session(model="apart"):
            occ = gmsh.model.occ
            made = [(b, occ.addBox(*b.corner, *b.size)) for b in bodies]
            occ.synchronize()
            for b, v in made:
                gmsh.model.addPhysicalGroup(3, [v], name=b.name)
                faces = [f for _, f in gmsh.model.getBoundary([(3, v)], oriented=False)]
                for side, axis, end in sides:
                    at = b.corner[axis] + end * b.size[axis]
                    tags = [f for f in faces
                            if abs(occ.getCenterOfMass(2, f)[axis] - at) < 1e-9]
                    gmsh.model.addPhysicalGroup(2, tags, name=f"{b.name}_{side}")
                points = gmsh.model.getBoundary([(3, v)], recursive=True)
                gmsh.model.mesh.setSize(points, b.h)
            gmsh.model.mesh.generate(3)
            gmsh.model.mesh.setOrder(order)
            gmsh.write(str(path))
        return str(path)

    return pathlib.Path(on_rank_zero(comm, write))  # rank 0's path, or its error
