"""Reading gmsh meshes with named physical groups, ready for interface integrals."""

from __future__ import annotations

import logging
import pathlib
from contextlib import nullcontext

import dolfinx
import gmsh
import numpy as np
from dolfinx.io import gmsh as gmshio
from mpi4py import MPI

from breakwater.common.errors import MeshError
from breakwater.common.gmshtools import gmsh_session, unsupported_format
from breakwater.common.parallel import on_rank_zero, shared_tempdir
from breakwater.common.xdmfinfo import is_xdmf
from breakwater.model.meshcells import (
    DEGENERATE,
    THIN,
    check_cell_type,
    check_group_nodes,
    check_meshed,
)
from breakwater.model.meshfile import (
    check_names,
    check_offset,
    check_partitions,
    check_plane,
    check_unnamed_cells,
    drop_ghost_cells,
    drop_ungrouped_cells,
    empty_names,
    meshio_entities,
    no_groups,
    number_cell_nodes_first,
)
from breakwater.model.tetcells import check_tetrahedra

log = logging.getLogger("breakwater.model.mesh")


def read_mesh(path: str | pathlib.Path, comm: MPI.Comm = MPI.COMM_WORLD,
              gdim: int | None = None, order: int = 2) -> gmshio.MeshData:
    """Read a gmsh ``.msh`` (or mesh a ``.geo``, or breakwater's XDMF) with its physical groups.

    Cells are ghosted across shared facets, which interior-facet (interface)
    integrals need in parallel. A ``.msh`` of second order (six-node triangles) is
    read as such: the cells are curved, their mid-edge nodes where gmsh put them.

    Args:
        path: A ``.msh`` file, or a ``.geo`` script that gmsh meshes first (into a
            temporary folder: nothing is written beside the script), or the ``.xdmf``
            that ``breakwater mesh --out`` writes (:mod:`.xdmfmesh`; another XDMF,
            without the groups' names, is refused).
        comm: Communicator to distribute the mesh over.
        gdim: Geometric dimension of the model: 2 (plane strain) or 3; None: the
            highest dimension of the file's physical groups.
        order: The displacement's degree: a ``.geo`` whose curves are curved is
            meshed to this geometric order (:func:`mesh_geo`).

    Returns:
        dolfinx's ``MeshData`` (mesh, cell/facet/ridge tags, physical groups by name).

    Raises:
        MeshError: The file is missing, unreadable, or has no named physical groups.

    """
    path = pathlib.Path(path)
    if not on_rank_zero(comm, path.is_file):  # rank 0's answer: rank 0 reads the file
        raise MeshError(f"mesh file not found: {path}")
    if path.suffix == ".geo":
        with shared_tempdir(comm, "breakwater-geo-") as folder:
            return read_mesh(mesh_geo(path, folder / f"{path.stem}.msh", comm, gdim,
                                      order), comm, gdim)
    if is_xdmf(path):  # breakwater's own (`breakwater mesh --out x.xdmf`), with names
        from breakwater.model.xdmfmesh import read_xdmf

        xdmf, record = read_xdmf(path, comm, gdim)
        out = GroupedMeshData(*xdmf)
        out.shared, out.empty = record["shared"], record["empty"]
        out.ungrouped = int(record["ungrouped"])
        return out
    if path.suffix != ".msh":
        raise MeshError(unsupported_format(path))
    partitioner = dolfinx.mesh.create_cell_partitioner(dolfinx.mesh.GhostMode.shared_facet, 2)
    # dolfinx's read_from_msh, but with gmsh quiet: rank 0 reads, all ranks distribute.
    with gmsh_session(model="breakwater-read") if comm.rank == 0 else nullcontext():
        try:
            dim, empty, ungrouped = on_rank_zero(comm, lambda: _merge(path, gdim))
        except MeshError:
            raise
        except Exception as e:  # gmsh raises bare Exceptions on unreadable files
            raise MeshError(f"{path}: cannot read the mesh ({e})") from e
        data = gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=dim, partitioner=partitioner)
        sizes = on_rank_zero(comm, _group_sizes)
    data.physical_groups.pop("", None)  # the groups without a name (of lower dimensions)
    for tags, d in ((data.cell_tags, dim), (data.facet_tags, dim - 1)):
        lost = [n for n, k in empty.items() if k == d]
        if tags is None and lost:  # the model said "the mesh needs cell and facet groups"
            raise MeshError(f"{path}: no {d}D physical group holds elements; "
                            f"{', '.join(lost)} are named in the file with none (a converter "
                            "kept only the cells' groups?): write the mesh from gmsh")
    out = _with_shared(data, sizes, comm)
    out.empty, out.ungrouped = empty, ungrouped
    return out


class GroupedMeshData(gmshio.MeshData):
    """dolfinx's ``MeshData`` with the physical groups that lost entities to others.

    gmsh lets an entity (a surface, a curve, a point) belong to several physical groups
    of its dimension; dolfinx's tags keep one group per mesh entity, so the others
    silently lose those facets, cells or vertices (a load on such a group acted on part
    of its surface). :func:`group_tag` refuses a group in :attr:`shared`.

    Attributes:
        shared: By group name: how many of its gmsh elements dolfinx's tags give to
            another group, its element count, and the groups it shares entities with.
        empty: Groups named in the file that no element carries (name -> dimension).
        ungrouped: Cells in no physical group, left out.
    """

    shared: dict[str, tuple[int, int, list[str]]]
    empty: dict[str, int]
    ungrouped: int


def _group_sizes() -> dict[str, tuple[int, int, list[str]]]:
    """Each physical group of the current gmsh model: dimension, elements, sharers.

    Rank 0, within the model's gmsh session. The sharers are the groups of the same
    dimension holding one of its entities.
    """
    groups = gmsh.model.getPhysicalGroups()
    entities = {(d, t): {int(e) for e in gmsh.model.getEntitiesForPhysicalGroup(d, t)}
                for d, t in groups}
    out = {}
    for d, t in groups:
        count = sum(len(tags) for e in entities[d, t]
                    for tags in gmsh.model.mesh.getElements(d, e)[1])
        sharers = sorted(gmsh.model.getPhysicalName(d, o) for dd, o in groups
                         if dd == d and o != t and entities[d, t] & entities[dd, o])
        out[gmsh.model.getPhysicalName(d, t)] = (d, count, sharers)
    return out


def _with_shared(data: gmshio.MeshData, sizes: dict[str, tuple[int, int, list[str]]],
                 comm: MPI.Comm) -> GroupedMeshData:
    """``data`` with :attr:`GroupedMeshData.shared` (collective).

    A group sharing entities with others lost some where dolfinx's tags hold fewer of
    its (owned) cells, facets or vertices than gmsh's elements.
    """
    msh = data.mesh
    tdim = msh.topology.dim
    tags = {tdim: data.cell_tags, tdim - 1: data.facet_tags, 0: data.ridge_tags
            if tdim == 2 else data.peak_tags}
    out = GroupedMeshData(*data)
    out.shared = {}
    for name, (d, count, sharers) in sizes.items():
        t = tags.get(d)
        if not sharers or t is None or name not in data.physical_groups:
            continue
        found = t.find(data.physical_groups[name][1])
        owned = comm.allreduce(int(np.count_nonzero(
            found < msh.topology.index_map(d).size_local)))
        if owned < count:
            out.shared[name] = (count - owned, count, sharers)
    return out


def _merge(path: pathlib.Path, gdim: int | None) -> tuple[int, dict[str, int], int]:
    """Read a ``.msh`` into the current gmsh model (rank 0) and check it is whole.

    A truncated file may read without error but lack its elements, nodes or physical
    groups (dolfinx would then fail with a RuntimeError or an IndexError).

    A partitioned file's ghost cells are dropped; the checks of :mod:`.meshfile` and
    :mod:`.meshcells` refuse what dolfinx would read wrongly.

    Returns:
        The model's dimension (``gdim``, or the highest dimension of its physical
        groups: 2 or 3), the groups named with no elements
        (:func:`.meshfile.empty_names`) and the number of cells in no group, left out.

    Raises:
        MeshError: No nodes, no cells of dimension ``gdim`` or no physical groups; node
            tags that repeat (two meshes numbered apart and merged into one file).
    """
    gmsh.merge(str(path))
    drop_ghost_cells()
    groups = gmsh.model.getPhysicalGroups()
    if not groups:
        raise no_groups(path)
    check_names(path)
    if gdim is None:
        gdim = max(d for d, _ in groups)
        if gdim not in (2, 3):
            raise MeshError(f"{path}: no surface (2D) or volume (3D) physical group: "
                            "name the bodies' cells in gmsh (Physical Surface/Volume)")
    ungrouped, left_out = drop_ungrouped_cells(path, gdim)
    check_unnamed_cells(path, gdim)
    _single_body_cells(path, gdim)
    check_partitions(path, gdim)
    check_offset(path)
    tags = gmsh.model.mesh.getNodes()[0]
    if len(tags) == 0:
        raise MeshError(f"{path}: cannot read the mesh (no nodes: truncated?)")
    repeated = len(tags) - len(np.unique(tags))
    if repeated:  # cells would join nodes of both meshes: folded or overlapping cells
        raise MeshError(f"{path}: {repeated} node tags appear twice (meshes numbered apart "
                        "and merged?): mesh the bodies in one gmsh model (Merge their .geo "
                        "files, not their .msh), or write the second with "
                        "Mesh.FirstNodeTag and Mesh.FirstElementTag above the first's")
    types, _, _ = gmsh.model.mesh.getElements(gdim)
    if len(types) == 0:
        raise MeshError(f"{path}: cannot read the mesh (no {gdim}D cells: truncated?)")
    number_cell_nodes_first(gdim)
    if len(types) > 1:  # dolfinx raised a RuntimeError ("Multiple cell types")
        names = " and ".join(gmsh.model.mesh.getElementProperties(t)[0] for t in types)
        how = ("recombine every surface or none; gmsh leaves triangles where it cannot pair "
               "them, Mesh.SubdivisionAlgorithm = 1 gives quadrilaterals only" if gdim == 2
               else "all tetrahedra, or all hexahedra: every extruded surface recombined "
               "into quadrilaterals")
        raise MeshError(f"{path}: the {gdim}D cells mix {names}; breakwater reads one cell "
                        f"type per mesh: mesh every body with the same kind ({how})")
    check_cell_type(path, gdim, int(types[0]))
    check_group_nodes(path, gdim)
    if gdim == 2:
        check_plane(path)
        check_cells(path)
    else:
        check_tetrahedra(path)
    if left_out:
        log.warning("%s", left_out)
    return gdim, empty_names(path), ungrouped


def _single_body_cells(path: pathlib.Path, gdim: int) -> None:
    """Refuse cells in two physical groups of dimension ``gdim`` (rank 0).

    A gmsh entity in two cell groups puts its cells in two bodies (dolfinx's reader
    raised "All cells are expected to be tagged once"). Two meshes merged into one file
    do it silently where their entity tags repeat (each file's first surface is
    Surface 1: gmsh joins them into one entity holding both bodies' cells).

    Raises:
        MeshError: Naming the entity and both groups.
    """
    owner: dict[int, str] = {}
    for dim, tag in gmsh.model.getPhysicalGroups(gdim):
        name = gmsh.model.getPhysicalName(dim, tag) or str(tag)
        for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
            other = owner.setdefault(int(entity), name)
            if other != name:
                kind = "Surface" if gdim == 2 else "Volume"
                if entity == 0:  # gmsh numbers entities from 1; meshio's default is 0
                    raise MeshError(meshio_entities(path, other, name))
                raise MeshError(f"{path}: the cells of gmsh {kind} {entity} are in both "
                                f"'{other}' and '{name}' (a cell belongs to one body; "
                                "meshes merged whose entity tags repeat? give each file's "
                                "entities distinct tags, or mesh the bodies in one model)")


def cell_quality(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed area and height over the longest edge (relative) of polygonal cells.

    Args:
        corners: The corner coordinates, shape ``(cells, corners, 2)``, in the cells'
            vertex order.

    Returns:
        ``(area, quality)``: the signed area (shoelace; its sign is the cell's
        orientation) and ``2 |area| / L²`` with ``L`` the longest edge (for a triangle,
        its height over the longest edge divided by that edge: √3/2 equilateral, 0
        collapsed).
    """
    # Relative to each cell's first corner: products of absolute coordinates lose the
    # area to cancellation far from the origin (a mesh in UTM coordinates, x ~ 5e5 m,
    # y ~ 4e6 m: every 2 cm cell was "degenerate", its area 0 to round-off).
    local = corners - corners[:, :1]
    x, y = local[..., 0], local[..., 1]
    xn, yn = np.roll(x, -1, axis=1), np.roll(y, -1, axis=1)
    area = 0.5 * np.sum(x * yn - xn * y, axis=1)
    longest = np.max(np.hypot(xn - x, yn - y), axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        quality = np.where(longest > 0, 2 * np.abs(area) / longest**2, 0.0)
    return area, quality


# The six-node triangle (gmsh type 9: the corners, then the mid-edge nodes of the
# edges 0-1, 1-2, 2-0): its shape functions' derivatives at its nodes, (node, ∂ξ/∂η, N).
_P2_NODES = np.array([[0, 0], [1, 0], [0, 1], [0.5, 0], [0.5, 0.5], [0, 0.5]])


def _p2_derivatives(ξ: np.ndarray, η: np.ndarray) -> np.ndarray:
    """∂N/∂ξ and ∂N/∂η of the six-node triangle at points, ``(points, 2, 6)``."""
    λ = 1 - ξ - η
    z = np.zeros_like(ξ)
    dξ = [1 - 4 * λ, 4 * ξ - 1, z, 4 * (λ - ξ), 4 * η, -4 * η]
    dη = [1 - 4 * λ, z, 4 * η - 1, -4 * ξ, 4 * ξ, 4 * (λ - η)]
    return np.stack([np.stack(dξ, axis=-1), np.stack(dη, axis=-1)], axis=1)


_P2_DN = _p2_derivatives(_P2_NODES[:, 0].astype(float), _P2_NODES[:, 1].astype(float))


def curved_jacobian(x: np.ndarray) -> np.ndarray:
    """The smallest Jacobian of six-node triangles at their nodes over the corners' one.

    Args:
        x: The nodes' coordinates, ``(cells, 6, 2)`` in gmsh's order.

    Returns:
        ``min det J(node) / det J(straight cell)`` per cell: 1 for a straight-sided
        cell, ≤ 0 where a mid-edge node moved far enough to fold the cell.
    """
    J = np.einsum("qan,cnd->cqad", _P2_DN, x)  # (cells, node, ∂, coordinate)
    det = J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]
    c = x[:, :3]
    straight = ((c[:, 1, 0] - c[:, 0, 0]) * (c[:, 2, 1] - c[:, 0, 1])
                - (c[:, 2, 0] - c[:, 0, 0]) * (c[:, 1, 1] - c[:, 0, 1]))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(straight != 0, det.min(axis=1) / straight, 0.0)


def check_cells(path: pathlib.Path) -> None:
    """Refuse degenerate or overlapping 2D cells of the current gmsh model (rank 0).

    Checked on the corners of each cell (the straight-sided cell): a height below
    :data:`DEGENERATE` of the longest edge is refused, below :data:`THIN` warned about
    once (the thinnest cell); two cells on the same side of their shared edge overlap
    (a folded mesh, an inverted cell among its neighbours), whatever the orientation
    of each surface. A curved six-node triangle (a second-order mesh) is refused where
    its Jacobian at one of its nodes falls to :data:`DEGENERATE` of the straight
    cell's or changes sign (:func:`curved_jacobian`: a mid-edge node moved across
    the cell).

    Raises:
        MeshError: One line naming the file, the cell (gmsh element tag) and its
            position.
    """
    tags, coords, _ = gmsh.model.mesh.getNodes()
    xy = np.zeros((int(tags.max()) + 1, 2))
    xy[tags.astype(np.int64)] = coords.reshape(-1, 3)[:, :2]
    cells, elements, sides = [], [], []
    for etype, etags, enodes in zip(*gmsh.model.mesh.getElements(2), strict=True):
        corners = gmsh.model.mesh.getElementProperties(etype)[5]
        all_nodes = enodes.astype(np.int64).reshape(len(etags), -1)
        nodes = all_nodes[:, :corners]
        cells.append(nodes)
        elements.append(etags.astype(np.int64))
        if etype == 9:  # six-node triangles
            ratio = curved_jacobian(xy[all_nodes])
            worst = int(np.argmin(ratio))
            if ratio[worst] < DEGENERATE:
                centre = xy[nodes[worst]].mean(axis=0)
                raise MeshError(f"{path}: curved cell {etags[worst]} at ({centre[0]:.6g}, "
                                f"{centre[1]:.6g}) folds: its Jacobian at a node is "
                                f"{ratio[worst]:.1e} of its corners' (a mid-edge node "
                                "too far off its edge; refine there or remesh)")
    for nodes, etags in zip(cells, elements, strict=True):
        area, quality = cell_quality(xy[nodes])
        worst = int(np.argmin(quality))
        centre = xy[nodes[worst]].mean(axis=0)
        where = f"cell {etags[worst]} at ({centre[0]:.6g}, {centre[1]:.6g})"
        if quality[worst] < DEGENERATE:
            raise MeshError(f"{path}: {where} is degenerate: its height is "
                            f"{quality[worst]:.1e} of its longest edge, below "
                            f"{DEGENERATE:g} (zero area; remesh)")
        thin = int(np.count_nonzero(quality < THIN))
        if thin:
            log.warning("%s: %d thin cell(s), the thinnest %s: height %.1e of its longest "
                        "edge, below %g (poor accuracy and conditioning)", path, thin, where,
                        quality[worst], THIN)
        # Each edge, its vertices sorted, and the side of it the cell lies on.
        k = nodes.shape[1]
        a, b = nodes, np.roll(nodes, -1, axis=1)
        forward = a < b
        side = np.where(forward, 1, -1) * np.sign(area)[:, None]
        edges = np.stack([np.minimum(a, b), np.maximum(a, b)], axis=-1).reshape(-1, 2)
        sides.append((edges, side.reshape(-1), np.repeat(etags, k)))
    edges = np.concatenate([e for e, _, _ in sides])
    side = np.concatenate([s for _, s, _ in sides])
    owner = np.concatenate([o for _, _, o in sides])
    order = np.lexsort((edges[:, 1], edges[:, 0]))
    edges, side, owner = edges[order], side[order], owner[order]
    same = np.all(edges[1:] == edges[:-1], axis=1) & (side[1:] == side[:-1])
    if same.any():
        j = int(np.flatnonzero(same)[0])
        mid = xy[edges[j]].mean(axis=0)
        raise MeshError(f"{path}: cells {owner[j]} and {owner[j + 1]} overlap at "
                        f"({mid[0]:.6g}, {mid[1]:.6g}): both lie on the same side of their "
                        "shared edge (a folded mesh or an inverted cell; remesh)")


CURVED = 1e-9
"""A mid-edge node of a second-order mesh farther than this fraction of its edge's
length from the edge's midpoint makes the edge curved."""


def curved_edges() -> int:
    """The number of curved edges of the current gmsh model's 1-D elements (rank 0).

    Mid-edge nodes of the three-node lines (gmsh type 8) more than :data:`CURVED` of
    the edge's length off the chord's midpoint: gmsh places them on the geometry's
    curves (circle arcs, splines), at the midpoint of straight ones.
    """
    tags, coords, _ = gmsh.model.mesh.getNodes()
    if not len(tags):
        return 0
    xyz = np.zeros((int(tags.max()) + 1, 3))
    xyz[tags.astype(np.int64)] = coords.reshape(-1, 3)
    count = 0
    for etype, _, enodes in zip(*gmsh.model.mesh.getElements(1), strict=True):
        if etype != 8:
            continue
        a, b, m = (xyz[enodes.astype(np.int64).reshape(-1, 3)[:, k]] for k in range(3))
        off = np.linalg.norm(m - 0.5 * (a + b), axis=1)
        count += int(np.count_nonzero(off > CURVED * np.linalg.norm(b - a, axis=1)))
    return count


WRITE = {"Mesh.MshFileVersion": 4.1}
"""gmsh options of the ``.msh`` that :func:`mesh_geo` writes, whatever the script sets: a
script's ``Mesh.MshFileVersion = 2.2`` with ``Mesh.SaveAll = 1`` wrote every element in
physical group 0, its format 1 no names (the run then refused breakwater's own file)."""


def mesh_geo(path: pathlib.Path, target: pathlib.Path, comm: MPI.Comm,
             dim: int | None = None, order: int = 1) -> pathlib.Path:
    """Mesh a gmsh ``.geo`` script on rank 0 and write the ``.msh`` to ``target``.

    With ``order = 2`` (the P2 displacement) the mesh is made second order
    (``setOrder(2)``: the mid-edge nodes on the geometry's curves) where the script
    has a curved curve (:func:`curved_edges`); a geometry of straight lines keeps
    first-order (affine) cells, on which the conforming pairs' compiled path runs
    (:mod:`breakwater.contact.nodal`) and whose P2 nodes are the same points. A
    script that asks for an order of 2 or more (``Mesh.ElementOrder``) keeps it; one that
    asks for 1, gmsh's default, cannot be told from one that does not ask.

    Args:
        path: The script.
        target: The ``.msh`` file written (its folder is created); the same path on
            every rank.
        comm: Communicator (rank 0 meshes, every rank returns once the file exists).
        dim: Dimension of the mesh; None: the script's (3 if it has a volume).
        order: The displacement's degree (1 or 2).

    Returns:
        ``target``.

    Raises:
        MeshError: gmsh cannot mesh the script (on every rank).

    """
    def write() -> None:
        target.parent.mkdir(parents=True, exist_ok=True)
        with gmsh_session(WRITE):
            gmsh.merge(str(path))  # into the session's model
            for name, value in WRITE.items():  # over the script's (format 1 or 2.2: refused)
                gmsh.option.setNumber(name, value)
            mdim = dim if dim is not None else max(2, gmsh.model.getDimension())
            gmsh.model.mesh.generate(mdim)
            check_meshed(mdim)
            if order == 2 and gmsh.option.getNumber("Mesh.ElementOrder") == 1:
                gmsh.model.mesh.setOrder(2)
                if not curved_edges():
                    gmsh.model.mesh.setOrder(1)
            gmsh.write(str(target))

    try:
        on_rank_zero(comm, write)
    except Exception as e:
        raise MeshError(f"{path}: gmsh cannot mesh the script ({e})") from e
    return target


def facet_type(msh: dolfinx.mesh.Mesh) -> dolfinx.mesh.CellType:
    """The cell type of a mesh's facets: interval (2D), triangle or quadrilateral (3D)."""
    return dolfinx.cpp.mesh.cell_entity_type(msh.topology.cell_type, msh.topology.dim - 1, 0)


def group_tag(data: gmshio.MeshData, name: str, dim: int | None = None) -> int:
    """The gmsh tag of a named physical group, checking its dimension.

    Raises:
        MeshError: No such group (the message lists the ones that exist), or it has
            another dimension.

    """
    groups = data.physical_groups
    empty = getattr(data, "empty", {})
    if name not in groups and name in empty:
        raise MeshError(f"physical group '{name}' ({empty[name]}D) is named in the mesh file "
                        "but no element carries its tag (a converter dropped its elements?)")
    if name not in groups:
        known = ", ".join(sorted(groups))
        raise MeshError(f"physical group '{name}' is not in the mesh (it has: {known})")
    gdim, tag = groups[name]
    if dim is not None and gdim != dim:
        raise MeshError(f"physical group '{name}' has dimension {gdim}, expected {dim}")
    shared = getattr(data, "shared", {}).get(name)
    if shared is not None:
        lost, count, sharers = shared
        what = ("vertices" if gdim == 0 else "cells" if gdim == data.mesh.topology.dim
                else "facets")
        raise MeshError(f"physical group '{name}' shares {lost} of its {count} {what} with "
                        f"group {', '.join(repr(s) for s in sharers)}: dolfinx keeps one "
                        f"group per entity, so '{name}' would act on the rest only; make "
                        "the groups disjoint in gmsh (a group may list several entities)")
    return int(tag)


def group_vertices(data: gmshio.MeshData, name: str) -> np.ndarray:
    """The vertices of the parent mesh (this rank's, ghosts included) in a point group.

    Raises:
        MeshError: No such group, not a point (dimension-0) group, or a mesh whose
            point groups dolfinx did not read.

    """
    tag = group_tag(data, name, 0)
    tdim = data.mesh.topology.dim
    tags = {tdim - 2: data.ridge_tags, tdim - 3: data.peak_tags}.get(0)
    if tags is None:
        raise MeshError(f"point group '{name}' cannot be read from this mesh")
    return tags.find(tag)


def group_points(data: gmshio.MeshData, name: str) -> np.ndarray:
    """Coordinates of the vertices in a named point (dimension-0) group, on every rank.

    Returns:
        Array of shape ``(n, 3)``; the same on all ranks.

    """
    msh = data.mesh
    vertices = group_vertices(data, name)
    nloc = msh.topology.index_map(0).size_local
    vertices = vertices[vertices < nloc]
    x = msh.geometry.x[dolfinx.mesh.entities_to_geometry(msh, 0, vertices).ravel()]
    allx = msh.comm.allgather(x.reshape(-1, 3))
    return np.unique(np.vstack(allx), axis=0)


def convert_to_xdmf(source: str | pathlib.Path, out: str | pathlib.Path,
                    comm: MPI.Comm = MPI.COMM_WORLD) -> pathlib.Path:
    """Write breakwater's XDMF of a gmsh mesh, as ``breakwater mesh --out x.xdmf`` does.

    The mesh is read with every check a run makes (:func:`read_mesh`) and written with
    its meshtags and the physical groups' names (:func:`.xdmfmesh.write_xdmf`), the
    arrays in ``x.h5`` beside it: a case reads it by group names as its
    ``mesh.source``, on any number of ranks; ParaView opens it. (meshio's XDMF,
    :func:`breakwater.meshes.export.convert`'s until 2026-11-28, holds no names.)

    Args:
        source: The gmsh ``.msh`` (or ``.geo``, meshed first).
        out: The ``.xdmf`` file; rank 0's path is used on every rank.
        comm: The ranks (collective).

    Returns:
        The ``.xdmf`` written (rank 0's path, on every rank).

    Raises:
        MeshError: The mesh is refused as a run refuses it, on every rank.
    """
    from breakwater.model.xdmfmesh import write_xdmf

    src, path = (pathlib.Path(p) for p in on_rank_zero(comm, lambda: (str(source), str(out))))
    if not is_xdmf(path):
        raise MeshError(f"{path}: not an XDMF file name (.xdmf, .xmf)")
    data = read_mesh(src, comm)
    on_rank_zero(comm, lambda: path.parent.mkdir(parents=True, exist_ok=True))
    write_xdmf(data, path)
    return path
