"""Checks of a ``.msh`` file as written elsewhere (rank 0, in gmsh's session, after merge).

Meshes made by other tools or on clusters reach breakwater in forms that gmsh reads
without error but that dolfinx read wrongly or the checks of :mod:`.mesh` misjudged:

- a mesh partitioned by gmsh with ghost cells (``Mesh.PartitionCreateGhostCells``):
  each ghost cell is a copy of a neighbour partition's cell, outside every physical
  group; the overlap check called them folded cells ("cells 366 and 366 overlap").
  They are dropped (:func:`drop_ghost_cells`), breakwater partitions the mesh itself;
- one file of a partitioned mesh split into one file per partition
  (``Mesh.PartitionSplitMeshFiles``): it ran on that piece of the bodies, a block of a
  quarter of its weight, silently (:func:`check_partitions`);
- a format 2.2 file written with ``Mesh.SaveAll = 1``: gmsh then writes every element
  with physical tag 0, so the file names groups that hold nothing ("no physical
  groups: truncated?", :func:`no_groups`);
- group names in ``$PhysicalNames`` that no element carries (a converter that kept the
  cells' tags only): "the mesh needs cell and facet physical groups" (:func:`empty_names`);
- cells in no physical group (``Mesh.SaveAll = 1``, a surface left out of the groups):
  dolfinx's reader raised "All cells are expected to be tagged once" (a traceback). They
  are left out with a warning (:func:`drop_ungrouped_cells`), as gmsh leaves them out of
  a file written without ``Mesh.SaveAll``;
- nodes on no cell (of elements outside the cells' groups, or of none) numbered among
  the cells' nodes: dolfinx's reader called ``MPI_Abort`` ("Invalid rank", even
  serially); node tags with gaps (two meshes merged with distinct first tags): it
  failed an assertion. The cells' nodes are numbered 1..n first
  (:func:`number_cell_nodes_first`);
- cells of several physical groups in elementary entity 0 (meshio, given
  ``gmsh:physical`` only, writes ``gmsh:geometrical`` 0): gmsh keeps the groups per
  entity, so each cell would be in every group (:func:`meshio_entities`);
- a mesh far from the origin for its size (survey coordinates, UTM: x ~ 5e5 m,
  y ~ 4e6 m, on a 0.6 m model): coordinates then carry round-off above breakwater's
  relative tolerances (the cells' areas, the coincidence of a conforming interface's
  nodes: a 2 cm cell was "degenerate", the interface "not conforming")
  (:func:`check_offset`);
- a 2D mesh that is not flat (z varying, a plane tilted about an axis): dolfinx keeps x
  and y only, so the bodies were their projection on the x-y plane
  (:func:`check_plane`).
"""

from __future__ import annotations

import pathlib

import gmsh
import numpy as np

from breakwater.common.errors import MeshError
from breakwater.common.gmshtools import UNNAMED, GroupNameError, named_groups, physical_groups

__all__ = [
    "FLAT",
    "check_names",
    "check_offset",
    "check_partitions",
    "check_plane",
    "check_unnamed_cells",
    "drop_ghost_cells",
    "drop_ungrouped_cells",
    "empty_names",
    "no_groups",
    "number_cell_nodes_first",
]

FAR = 1e4
"""A mesh whose coordinates reach this many times its extent is refused as too far from
the origin: their round-off (2.2e-16 of them) would approach 1e-11 of the extent, and of
a contact interface 10 times smaller, within 100 of breakwater's 1e-9 tolerances."""

FLAT = 1e-6
"""A 2D mesh whose z coordinates span more than this fraction of its extent in x and y is
refused as not flat (a tilt of 1e-6 changes lengths by 5e-13)."""


def drop_ghost_cells() -> int:
    """Remove gmsh's ghost entities (partitioned with ghost cells) from the current model.

    Returns:
        The number of ghost entities removed.
    """
    ghosts = [(d, t) for d, t in gmsh.model.getEntities()
              if gmsh.model.getType(d, t).startswith("Ghost")]
    if ghosts:
        gmsh.model.removeEntities(ghosts)
    return len(ghosts)


def drop_ungrouped_cells(path: pathlib.Path, gdim: int) -> tuple[int, str]:
    """Remove the cells in no physical group from the current model.

    Returns:
        How many, and the warning to give once the mesh is accepted ("": none).
    """
    kind = "Surface" if gdim == 2 else "Volume"
    drop, count = [], 0
    for d, t in gmsh.model.getEntities(gdim):
        n = sum(len(e) for e in gmsh.model.mesh.getElements(d, t)[1])
        if n and not len(gmsh.model.getPhysicalGroupsForEntity(d, t)):
            drop.append((d, t))
            count += n
    if not drop:
        return 0, ""
    gmsh.model.removeEntities(drop)
    return count, (f"{path}: {count} cells in no physical group (gmsh {kind} "
                   f"{', '.join(str(t) for _, t in drop)}) are left out: name them in a "
                   "physical group to model them")


def number_cell_nodes_first(gdim: int) -> None:
    """Number the nodes of the cells of dimension ``gdim`` 1..n, the other nodes after.

    dolfinx's reader needs the tags 1..N and, for a node on no cell, a tag above every
    cell node's (one among them made it call ``MPI_Abort``).
    """
    tags = gmsh.model.mesh.getNodes()[0].astype(np.int64)
    used = np.unique(np.concatenate([np.asarray(n, dtype=np.int64) for n in
                                     gmsh.model.mesh.getElements(gdim)[2]]))
    if len(used) == len(tags) and tags.min() == 1 and tags.max() == len(tags):
        return
    old = np.concatenate([used, np.setdiff1d(tags, used)])
    gmsh.model.mesh.renumberNodes(old, np.arange(1, len(old) + 1))


def check_partitions(path: pathlib.Path, gdim: int) -> None:
    """Refuse one part of a partitioned mesh written as one file per partition.

    Format 4.1 gives the number of partitions: some have no cells in the file. Format 2.2
    gives each element's partition only: its first file (``name_1.msh``) reads as a whole
    mesh partitioned in one, told apart by its sibling ``name_2.msh``.

    Raises:
        MeshError: Naming the partitions the file holds.
    """
    total = gmsh.model.getNumberOfPartitions()
    if total < 1:
        return
    present: set[int] = set()
    for d, t in gmsh.model.getEntities(gdim):
        if any(len(e) for e in gmsh.model.mesh.getElements(d, t)[1]):
            present.update(int(p) for p in gmsh.model.getPartitions(d, t))
    stem = path.stem.rsplit("_", 1)
    sibling = len(stem) == 2 and stem[1] == "1" and path.with_name(f"{stem[0]}_2.msh").is_file()
    if present and (len(present) < total or sibling):
        held = ", ".join(map(str, sorted(present)))
        raise MeshError(f"{path}: holds only partition {held} of a partitioned mesh (one file "
                        "per partition: Mesh.PartitionSplitMeshFiles): give the whole mesh in "
                        "one file; breakwater partitions it over the MPI ranks itself")


def no_groups(path: pathlib.Path) -> MeshError:
    """The error of a ``.msh`` whose elements carry no physical group.

    A format 2.2 file written with ``Mesh.SaveAll = 1`` names its groups in
    ``$PhysicalNames`` but tags every element with physical group 0; a file cut short
    names its groups but has no elements.
    """
    try:
        named = physical_groups(path)
    except (ValueError, OSError):
        named = {}
    if named and len(gmsh.model.mesh.getElements()[0]):  # elements, none in a group
        return MeshError(f"{path}: no element carries a physical group, though the file names "
                         f"{len(named)} (as gmsh writes format 2.2 with Mesh.SaveAll = 1): "
                         "write it without Mesh.SaveAll, or in format 4.1")
    return MeshError(f"{path}: cannot read the mesh (no physical groups: truncated?)")


def empty_names(path: pathlib.Path) -> dict[str, int]:
    """Groups named in the file's ``$PhysicalNames`` that no element carries.

    Returns:
        Name -> dimension.
    """
    try:
        named = physical_groups(path)
    except (ValueError, OSError):
        return {}
    held = {gmsh.model.getPhysicalName(d, t) for d, t in gmsh.model.getPhysicalGroups()}
    return {n: d for n, d in named.items() if n not in held}


def check_names(path: pathlib.Path) -> None:
    """Refuse a name given to physical groups of two dimensions, or groups without names.

    dolfinx keeps one group per name (the highest dimension's): a load on the curve
    "block" of a body "block" was refused as "a cell group".

    Raises:
        MeshError: Naming the name and its dimensions.
    """
    names = [(gmsh.model.getPhysicalName(d, t), d) for d, t in gmsh.model.getPhysicalGroups()]
    if not any(n for n, _ in names):  # dolfinx read them all as one group named ""
        raise MeshError(f"{path}: {UNNAMED}")
    try:
        named_groups([(n, d) for n, d in names if n])
    except GroupNameError as e:
        raise MeshError(f"{path}: {e}") from None


def check_unnamed_cells(path: pathlib.Path, gdim: int) -> None:
    """Refuse a cell group without a name (no body can name it: its cells left out).

    Raises:
        MeshError: Naming the groups' tags.
    """
    tags = [str(t) for d, t in gmsh.model.getPhysicalGroups(gdim)
            if not gmsh.model.getPhysicalName(d, t)]
    if tags:
        kind = "Surface" if gdim == 2 else "Volume"
        raise MeshError(f"{path}: the {gdim}D physical group(s) {', '.join(tags)} have no "
                        "name, so no body can be given their cells: name them in gmsh "
                        f"(Physical {kind}(\"rock\", {tags[0]}) = {{...}};)")


def meshio_entities(path: pathlib.Path, first: str, second: str) -> str:
    """The message refusing cell groups that share gmsh's elementary entity 0."""
    return (f"{path}: the cells of '{first}' and '{second}' are all in elementary entity 0 "
            "(meshio writes it without gmsh:geometrical), so gmsh cannot tell them apart: "
            "give meshio cell_data[\"gmsh:geometrical\"] = the gmsh:physical tags")


def check_offset(path: pathlib.Path) -> None:
    """Refuse a mesh whose distance from the origin exceeds :data:`FAR` times its extent.

    Raises:
        MeshError: Naming the distance, the extent and how to move it.
    """
    coords = gmsh.model.mesh.getNodes()[1].reshape(-1, 3)
    if not len(coords):
        return
    far = float(np.abs(coords).max())
    extent = float(np.ptp(coords, axis=0).max())
    if far > FAR * extent:
        raise MeshError(f"{path}: the mesh lies {far:.3g} m from the origin, {far / extent:.2g} "
                        f"times its size ({extent:.3g} m; survey coordinates?): its "
                        "coordinates' round-off would exceed breakwater's tolerances; "
                        "translate it near the origin (gmsh: Translate{...}), with the case's "
                        "coordinates")


def check_plane(path: pathlib.Path) -> None:
    """Refuse a 2D mesh not in a plane z = constant (rank 0, the current gmsh model).

    Raises:
        MeshError: The mesh lies in the x-z or y-z plane (say how to rotate it), or its
            z coordinates vary (tilted or warped).
    """
    coords = gmsh.model.mesh.getNodes()[1].reshape(-1, 3)
    if not len(coords):
        return
    span = np.ptp(coords, axis=0)
    if span[2] > 0 and min(span[0], span[1]) <= 1e-12 * span.max():
        plane = "y-z" if span[0] <= span[1] else "x-z"
        raise MeshError(f"{path}: the 2D mesh lies in the {plane} plane; a plane-strain "
                        "model lies in the x-y plane (y up): rotate it in gmsh")
    if span[2] > FLAT * max(span[0], span[1]):
        raise MeshError(f"{path}: the 2D mesh is not flat: its z coordinates span "
                        f"{span[2]:.6g} over {max(span[0], span[1]):.6g} in x-y (breakwater "
                        "would use its projection on the x-y plane): draw it at z = constant")
