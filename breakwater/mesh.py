"""Reading gmsh meshes with named physical groups, ready for interface integrals."""

from __future__ import annotations

import pathlib

import dolfinx
import gmsh
import numpy as np
from dolfinx.io import gmsh as gmshio
from mpi4py import MPI

from .errors import MeshError


def read_mesh(path: str | pathlib.Path, comm: MPI.Comm = MPI.COMM_WORLD,
              gdim: int = 2) -> gmshio.MeshData:
    """Read a gmsh ``.msh`` (or mesh a ``.geo``) with its physical groups.

    Cells are ghosted across shared facets, which interior-facet (interface)
    integrals need in parallel.

    Args:
        path: A ``.msh`` file, or a ``.geo`` script that gmsh meshes first.
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
        path = _mesh_geo(path, comm, gdim)
    elif path.suffix != ".msh":
        raise MeshError(f"{path}: expected a gmsh .msh or .geo file")
    partitioner = dolfinx.mesh.create_cell_partitioner(dolfinx.mesh.GhostMode.shared_facet, 2)
    # dolfinx's read_from_msh, but with gmsh quiet: rank 0 reads, all ranks distribute.
    error, started = None, False
    if comm.rank == 0:
        started = not gmsh.isInitialized()
        if started:
            gmsh.initialize(readConfigFiles=False)
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("breakwater-read")
        try:
            gmsh.merge(str(path))
        except Exception as e:  # gmsh raises bare Exceptions on unreadable files
            error = f"{path}: cannot read the mesh ({e})"
    error = comm.bcast(error, root=0)
    try:
        if error:
            raise MeshError(error)
        data = gmshio.model_to_mesh(gmsh.model, comm, 0,
                                    gdim=gdim, partitioner=partitioner)
    finally:
        if comm.rank == 0:
            gmsh.model.remove()
            if started:
                gmsh.finalize()
    if not data.physical_groups:
        raise MeshError(f"{path}: the mesh has no named physical groups")
    return data


def _mesh_geo(path: pathlib.Path, comm: MPI.Comm, dim: int) -> pathlib.Path:
    """Mesh a ``.geo`` script with gmsh on rank 0 and return the ``.msh`` written."""
    out = path.with_suffix(".msh")
    import gmsh

    error, started = None, False
    if comm.rank == 0:
        started = not gmsh.isInitialized()
        if started:
            gmsh.initialize()
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            gmsh.open(str(path))
            gmsh.model.mesh.generate(dim)
            gmsh.write(str(out))
        except Exception as e:
            error = f"{path}: gmsh cannot mesh the script ({e})"
        finally:
            if started:
                gmsh.finalize()
    error = comm.bcast(error, root=0)
    if error:
        raise MeshError(error)
    return out


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
