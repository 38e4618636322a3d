"""The XDMF mesh of ``breakwater mesh --out x.xdmf``: written and read back with its names.

:func:`write_xdmf` writes a mesh read from gmsh (:func:`breakwater.model.mesh.read_mesh`,
every check passed) with dolfinx's ``XDMFFile``: the mesh (its geometry of degree 1 or
2: six-node triangles keep their mid-edge nodes), its cell, facet and point (in 3D also
edge) meshtags, and the physical groups' names as the ``breakwater_groups`` record
(:mod:`breakwater.common.xdmfinfo`). The arrays go to ``x.h5`` beside ``x.xdmf``.
:func:`read_xdmf` reads it back over any number of ranks: the same mesh, groups and
names, so a case gives the same results from the ``.msh`` and from its XDMF (to
round-off: dolfinx numbers the cells and dofs of the two readings apart).
"""

from __future__ import annotations

import json
import logging
import pathlib
from typing import Any

import dolfinx
from dolfinx.io import XDMFFile
from dolfinx.io import gmsh as gmshio
from mpi4py import MPI

from breakwater.common.errors import MeshError
from breakwater.common.hdf5quiet import hdf5_quiet
from breakwater.common.parallel import on_rank_zero
from breakwater.common.xdmfinfo import (
    GROUPS,
    MESH_GRID,
    TAG_GRIDS,
    VERSION,
    add_digest,
    digest_problem,
    hdf5_problem,
    heavy_files,
    read_info,
)

__all__ = ["read_xdmf", "write_xdmf"]

log = logging.getLogger("breakwater.model.mesh")


def write_xdmf(data: gmshio.MeshData, out: pathlib.Path) -> pathlib.Path:
    """Write a mesh with its meshtags and group names to ``out`` (and ``out.h5``; collective).

    Args:
        data: The mesh as :func:`breakwater.model.mesh.read_mesh` read it (its
            ``shared``, ``empty`` and ``ungrouped`` are kept).
        out: The ``.xdmf`` file; the same path on every rank.

    Returns:
        The HDF5 file written beside it.
    """
    msh = data.mesh
    tdim = msh.topology.dim
    msh.name = MESH_GRID
    written = []
    with XDMFFile(msh.comm, str(out), "w") as f:
        f.write_mesh(msh)
        for name, tags in zip(TAG_GRIDS, data[1:5], strict=True):
            if tags is None:
                continue
            tags.name = name
            msh.topology.create_connectivity(tags.dim, tdim)
            f.write_meshtags(tags, msh.geometry, f"/Xdmf/Domain/Grid[@Name='{MESH_GRID}']"
                             "/Geometry")
            written.append(name)
        record: dict[str, Any] = {
            "version": VERSION, "gdim": msh.geometry.dim, "tags": written,
            "groups": {n: [int(g.dim), int(g.tag)] for n, g in data.physical_groups.items()},
            "shared": getattr(data, "shared", {}), "empty": getattr(data, "empty", {}),
            "ungrouped": int(getattr(data, "ungrouped", 0))}
        f.write_information(GROUPS, json.dumps(record))
    h5 = out.with_suffix(".h5")
    on_rank_zero(msh.comm, lambda: add_digest(out, h5))
    return h5


def _inspect(path: pathlib.Path) -> tuple[dict[str, Any], bool]:
    """The file's record and whether its arrays are inline XML (rank 0; its .h5 checked)."""
    record = read_info(path)
    h5 = heavy_files(path)
    if h5 is not None and not h5.is_file():
        raise MeshError(f"{path}: its data file {h5.name} is missing (an XDMF keeps its "
                        f"arrays in the .h5 written beside it: copy {h5.name} with "
                        f"{path.name})")
    problem = None if h5 is None else hdf5_problem(h5) or digest_problem(path, h5)
    if h5 is not None and problem is not None:
        raise MeshError(f"{path}: its data file {h5.name} is {problem} (copy it again "
                        f"with {path.name}, or write both again with `python -m "
                        f"breakwater mesh CASE --out {path.name}`)")
    return record, h5 is None


def read_xdmf(path: pathlib.Path, comm: MPI.Comm, gdim: int | None
              ) -> tuple[gmshio.MeshData, dict[str, Any]]:
    """Read the XDMF mesh of :func:`write_xdmf`, distributed over ``comm`` (collective).

    Args:
        path: The ``.xdmf`` file.
        comm: Communicator to distribute the mesh over.
        gdim: The model's dimension, or None (the file's).

    Returns:
        The mesh data (mesh, meshtags, groups by name) and the file's record (its
        ``shared``, ``empty``, ``ungrouped``).

    Raises:
        MeshError: One line, on every rank: an XDMF without breakwater's names, a
            missing data file, a dimension other than ``gdim``, or dolfinx cannot read it.
    """
    record, inline = on_rank_zero(comm, lambda: _inspect(path))
    if gdim is not None and int(record["gdim"]) != gdim:
        raise MeshError(f"{path}: a {record['gdim']}D mesh, where the model is {gdim}D")
    encoding = XDMFFile.Encoding.ASCII if inline else XDMFFile.Encoding.HDF5
    try:
        with hdf5_quiet(), XDMFFile(comm, str(path), "r", encoding=encoding) as f:
            # Cells ghosted across shared facets, as the .msh reader's partitioner.
            msh = f.read_mesh(ghost_mode=dolfinx.mesh.GhostMode.shared_facet, name=MESH_GRID)
            tdim = msh.topology.dim
            tags: list[Any] = [None] * 4
            for k, name in enumerate(TAG_GRIDS):
                if name in record["tags"]:
                    msh.topology.create_connectivity(tdim - k, tdim)
                    tags[k] = f.read_meshtags(msh, name)
                    tags[k].name = name
    except RuntimeError as e:  # every rank reads the same file: every rank fails
        h5 = path.with_suffix(".h5")
        if inline:
            raise MeshError(f"{path}: cannot read the mesh ({e})") from e
        raise MeshError(f"{path}: cannot read the mesh from its data file {h5.name} ({e}): "
                        f"copy it again with {path.name}, or write both again with "
                        f"`python -m breakwater mesh CASE --out {path.name}`") from e
    groups = {n: gmshio.PhysicalGroup(d, t) for n, (d, t) in record["groups"].items()}
    if record.get("ungrouped") and comm.rank == 0:
        log.warning("%s: %d cells in no physical group were left out when it was written "
                    "(name them in a physical group to model them)", path, record["ungrouped"])
    return gmshio.MeshData(msh, *tags, groups), record
