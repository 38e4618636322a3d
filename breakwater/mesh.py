"""Reading gmsh meshes with named physical groups, ready for interface integrals."""

from __future__ import annotations

import pathlib
from contextlib import nullcontext

import dolfinx
import gmsh
import numpy as np
from dolfinx.io import gmsh as gmshio
from mpi4py import MPI

from .errors import MeshError
from .gmshtools import gmsh_session
from .parallel import on_rank_zero, shared_tempdir


def read_mesh(path: str | pathlib.Path, comm: MPI.Comm = MPI.COMM_WORLD,
              gdim: int = 2) -> gmshio.MeshData:
    """Read a gmsh ``.msh`` (or mesh a ``.geo``) with its physical groups.

    Cells are ghosted across shared facets, which interior-facet (interface)
    integrals need in parallel.

    Args:
        path: A ``.msh`` file, or a ``.geo`` script that gmsh meshes first (into a
            temporary folder: nothing is written beside the script).
        comm: Communicator to distribute the mesh over.
        gdim: Geometric dimension of the model (2 for plane strain).

    Returns:
        dolfinx's ``MeshData`` (mesh, cell/facet/ridge tags, physical groups by name).

    Raises:
        MeshError: The file is missing, unreadable, or has no named physical groups.

    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise MeshError(f"mesh file not found: {path}")
    if path.suffix == ".geo":
        with shared_tempdir(comm, "breakwater-geo-") as folder:
            return read_mesh(mesh_geo(path, folder / f"{path.stem}.msh", comm, gdim),
                             comm, gdim)
    if path.suffix != ".msh":
        raise MeshError(f"{path}: expected a gmsh .msh or .geo file")
    partitioner = dolfinx.mesh.create_cell_partitioner(dolfinx.mesh.GhostMode.shared_facet, 2)
    # dolfinx's read_from_msh, but with gmsh quiet: rank 0 reads, all ranks distribute.
    with gmsh_session(model="breakwater-read") if comm.rank == 0 else nullcontext():
        try:
            on_rank_zero(comm, lambda: _merge(path, gdim))
        except MeshError:
            raise
        except Exception as e:  # gmsh raises bare Exceptions on unreadable files
            raise MeshError(f"{path}: cannot read the mesh ({e})") from e
        data = gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=gdim, partitioner=partitioner)
    if not data.physical_groups:
        raise MeshError(f"{path}: the mesh has no named physical groups")
    return data


def _merge(path: pathlib.Path, gdim: int) -> None:
    """Read a ``.msh`` into the current gmsh model (rank 0) and check it is whole.

    A truncated file may read without error but lack its elements, nodes or physical
    groups (dolfinx would then fail with a RuntimeError or an IndexError).

    Raises:
        MeshError: No nodes, no cells of dimension ``gdim`` or no physical groups.
    """
    gmsh.merge(str(path))
    if not gmsh.model.getPhysicalGroups():
        raise MeshError(f"{path}: cannot read the mesh (no physical groups: truncated?)")
    if len(gmsh.model.mesh.getNodes()[0]) == 0:
        raise MeshError(f"{path}: cannot read the mesh (no nodes: truncated?)")
    types, _, _ = gmsh.model.mesh.getElements(gdim)
    if len(types) == 0:
        raise MeshError(f"{path}: cannot read the mesh (no {gdim}D cells: truncated?)")


def mesh_geo(path: pathlib.Path, target: pathlib.Path, comm: MPI.Comm, dim: int = 2
             ) -> pathlib.Path:
    """Mesh a gmsh ``.geo`` script on rank 0 and write the ``.msh`` to ``target``.

    Args:
        path: The script.
        target: The ``.msh`` file written (its folder is created); the same path on
            every rank.
        comm: Communicator (rank 0 meshes, every rank returns once the file exists).
        dim: Dimension of the mesh.

    Returns:
        ``target``.

    Raises:
        MeshError: gmsh cannot mesh the script (on every rank).

    """
    def write() -> None:
        target.parent.mkdir(parents=True, exist_ok=True)
        with gmsh_session():
            gmsh.merge(str(path))  # into the session's model
            gmsh.model.mesh.generate(dim)
            gmsh.write(str(target))

    try:
        on_rank_zero(comm, write)
    except Exception as e:
        raise MeshError(f"{path}: gmsh cannot mesh the script ({e})") from e
    return target


def group_tag(data: gmshio.MeshData, name: str, dim: int | None = None) -> int:
    """The gmsh tag of a named physical group, checking its dimension.

    Raises:
        MeshError: No such group (the message lists the ones that exist), or it has
            another dimension.

    """
    groups = data.physical_groups
    if name not in groups:
        known = ", ".join(sorted(groups))
        raise MeshError(f"physical group '{name}' is not in the mesh (it has: {known})")
    gdim, tag = groups[name]
    if dim is not None and gdim != dim:
        raise MeshError(f"physical group '{name}' has dimension {gdim}, expected {dim}")
    return int(tag)


def group_points(data: gmshio.MeshData, name: str) -> np.ndarray:
    """Coordinates of the vertices in a named point (dimension-0) group, on every rank.

    Returns:
        Array of shape ``(n, 3)``; the same on all ranks.

    """
    msh = data.mesh
    tag = group_tag(data, name, 0)
    tdim = msh.topology.dim
    tags = {tdim - 2: data.ridge_tags, tdim - 3: data.peak_tags}.get(0)
    if tags is None:
        raise MeshError(f"point group '{name}' cannot be read from this mesh")
    vertices = tags.find(tag)
    nloc = msh.topology.index_map(0).size_local
    vertices = vertices[vertices < nloc]
    x = msh.geometry.x[dolfinx.mesh.entities_to_geometry(msh, 0, vertices).ravel()]
    allx = msh.comm.allgather(x.reshape(-1, 3))
    return np.unique(np.vstack(allx), axis=0)
