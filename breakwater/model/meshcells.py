"""Checks of a gmsh model's elements before dolfinx reads them (rank 0, in gmsh's session).

dolfinx reads prisms and pyramids but cannot tag their facets (a load's measure then
failed with "Multiple entity types in mesh", a traceback), and a physical group whose
nodes are on no cell (a gmsh ``Point`` not embedded in the body, a surface meshed apart
from its volume) made its reader call ``MPI_Abort`` ("Invalid rank", even serially).
"""

from __future__ import annotations

import pathlib

import gmsh
import numpy as np

from breakwater.common.errors import MeshError

__all__ = ["DEGENERATE", "THIN", "check_cell_type", "check_group_nodes", "check_meshed"]

DEGENERATE = 1e-6
"""A cell whose height (a tetrahedron's smallest: :mod:`.tetcells`) is below this fraction
of its longest edge is refused as degenerate (zero area or volume). The stiffness of such
a cell exceeds its neighbours' by 1/DEGENERATE or more, so the solution would carry
errors of the order of its condition number times the round-off (1e6 × 1e-16 × the
neighbours' own ~1e6); a collapsed cell (three collinear vertices) makes the matrix
singular (a MUMPS error; a flat tetrahedron's stiffness is NaN)."""
THIN = 1e-2
"""A cell whose height is below this fraction of its longest edge (an angle below about
0.6°, an aspect ratio above 100) is accepted with a warning."""

CELL_FAMILIES = {2: ("Triangle", "Quadrilateral"), 3: ("Tetrahedron", "Hexahedron")}
"""The cells breakwater reads, by the mesh's dimension (gmsh's family names)."""
_PLURAL = {2: "triangles or quadrilaterals", 3: "tetrahedra or hexahedra"}
SERENDIPITY = {16, 17, 18, 19}
"""gmsh's incomplete second-order cells (8-node quadrilateral, 20-node hexahedron, 15-node
prism, 13-node pyramid), which dolfinx does not read."""


def check_cell_type(path: pathlib.Path, gdim: int, kind: int) -> None:
    """Refuse a cell type other than triangles, quadrilaterals, tetrahedra, hexahedra.

    Args:
        path: The mesh file (for the message).
        gdim: The mesh's dimension.
        kind: gmsh's element type of its cells (the one type of the mesh).

    Raises:
        MeshError: Prisms, pyramids or serendipity cells, saying how to mesh instead.
    """
    name = gmsh.model.mesh.getElementProperties(kind)[0]
    if kind in SERENDIPITY:
        raise MeshError(f"{path}: the {gdim}D cells are {name} (incomplete second order), "
                        "which breakwater does not read: drop Mesh.SecondOrderIncomplete "
                        "(or mesh first order)")
    if name.split()[0] not in CELL_FAMILIES[gdim]:
        raise MeshError(f"{path}: the {gdim}D cells are {name}, which breakwater does not "
                        f"read: mesh with {_PLURAL[gdim]} (an extruded mesh is hexahedral when "
                        "the extruded surfaces are recombined into quadrilaterals: "
                        "Recombine Surface{...} or Mesh.RecombineAll = 1, and Layers{...}; "
                        "Recombine; in the Extrude)")


def check_group_nodes(path: pathlib.Path, gdim: int) -> None:
    """Refuse a physical group of a lower dimension with nodes on no cell.

    Args:
        path: The mesh file (for the message).
        gdim: The mesh's dimension (its cells').

    Raises:
        MeshError: Naming the group and how many of its elements are off the cells
            (facet groups first: a surface meshed apart from its volume takes its points
            off the cells too).
    """
    cells = np.unique(np.concatenate([np.asarray(n) for n in
                                      gmsh.model.mesh.getElements(gdim)[2]]))
    kind = "Surface" if gdim == 2 else "Volume"
    for dim, tag in sorted(gmsh.model.getPhysicalGroups(), reverse=True):  # facets first
        if dim >= gdim:
            continue
        off = total = 0
        for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
            for etype, _, nodes in zip(*gmsh.model.mesh.getElements(dim, entity),
                                       strict=True):
                per = gmsh.model.mesh.getElementProperties(etype)[3]
                inside = np.isin(np.asarray(nodes), cells).reshape(-1, per)
                off += int(np.count_nonzero(~inside.all(axis=1)))
                total += len(inside)
        if off == 0:
            continue
        name = gmsh.model.getPhysicalName(dim, tag) or str(tag)
        if dim == 0:
            raise MeshError(f"{path}: physical group '{name}': {off} of its {total} points "
                            "are not nodes of the mesh's cells: embed the gmsh Point in its "
                            f"body (Point{{...}} In {kind}{{...}};), or give a probe "
                            "coordinates (point = [...]) instead of a point group")
        what = "segments" if dim == 1 else "facets"
        raise MeshError(f"{path}: physical group '{name}': {off} of its {total} {what} have "
                        "nodes on no cell: its mesh is not the cells' boundary (meshed "
                        "apart from the cells, or a curve or surface not on a body)")


def check_meshed(dim: int) -> None:
    """Refuse a script that gmsh meshed leaving a surface (2D) or volume (3D) empty.

    gmsh's 3D Delaunay and Frontal algorithms log a failed volume (a point embedded in
    a surface between two volumes: "No elements in volume 1 2") and return; the file
    then read as "no 3D cells: truncated?".

    Args:
        dim: The dimension meshed.

    Raises:
        RuntimeError: Naming the empty entities and gmsh's last error, if any.
    """
    empty = [t for d, t in gmsh.model.getEntities(dim)
             if not any(len(e) for e in gmsh.model.mesh.getElements(d, t)[1])]
    if empty:
        kind = "Surface" if dim == 2 else "Volume"
        last = gmsh.logger.getLastError()
        raise RuntimeError(f"gmsh left {kind} {', '.join(map(str, empty))} without cells"
                           + (f": {last.strip()}" if last else "")
                           + "; open the script in gmsh (a point embedded on a surface's "
                           "edge leaves it unmeshed) or try another Mesh.Algorithm"
                           + ("3D" if dim == 3 else ""))
