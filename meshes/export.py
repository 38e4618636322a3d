"""Conversion of gmsh ``.msh`` files to other mesh formats with meshio.

The physical groups travel as cell data ``gmsh:physical`` (and
``gmsh:geometrical``), one value per cell of every block; the output has one
block per cell type (triangles, lines, vertices). Formats other than ``.msh``
drop the group names: decode the tags with
:data:`breakwater.meshes.goda.PHYSICAL_GROUPS` (``SEPARATE_PHYSICAL_GROUPS`` for the
separately meshed model).

Format notes:
    * ``.msh`` output is a verbatim copy (meshio's gmsh 4.1 writer loses the
      entity-to-group links of its own input).
    * XDMF (``.xdmf``, ``.xmf``) is refused, naming the way to breakwater's own:
      :func:`breakwater.model.mesh.convert_to_xdmf` or ``breakwater mesh --out
      x.xdmf`` write it with the physical groups' names, which a case reads it by
      (its ``mesh.source``). Until 2026-11-28 this function wrote meshio's XDMF,
      without the names: a case refused the file it wrote.
"""

from __future__ import annotations

import importlib.util
import pathlib
import shutil
import sys
import types
from collections.abc import Iterator
from contextlib import contextmanager

import meshio  # type: ignore[import-untyped]
import numpy as np
from mpi4py import MPI

from breakwater.common.parallel import on_rank_zero

_XDMF_SUFFIXES = (".xdmf", ".xmf")
_TAGS = ("gmsh:physical", "gmsh:geometrical")


@contextmanager
def _h5py_not_required() -> Iterator[None]:
    """Let meshio handle inline-XML XDMF without h5py installed.

    meshio's XDMF reader and writer ``import h5py`` unconditionally although
    inline XML data never uses it; a placeholder module satisfies that import.
    """
    if "h5py" in sys.modules or importlib.util.find_spec("h5py") is not None:
        yield
        return
    sys.modules["h5py"] = types.ModuleType("h5py")
    try:
        yield
    finally:
        del sys.modules["h5py"]


def _file_format(path: pathlib.Path) -> str:
    suffix = path.suffix.lower()
    formats = meshio.extension_to_filetypes.get(suffix)
    if not formats:
        known = ", ".join(sorted(meshio.extension_to_filetypes))
        raise ValueError(
            f"unknown mesh file suffix {suffix!r} of {path}; known: {known}"
        )
    return "gmsh" if "gmsh" in formats else str(formats[0])  # .msh is also ANSYS's


def _by_cell_type(mesh: meshio.Mesh, skip: tuple[str, ...] = ()) -> meshio.Mesh:
    """One block per cell type (except `skip`) with its gmsh tags, without cell sets."""
    groups: dict[str, list[int]] = {}
    for i, block in enumerate(mesh.cells):
        if block.type not in skip:
            groups.setdefault(block.type, []).append(i)
    cells = [
        (t, np.concatenate([mesh.cells[i].data for i in idx]))
        for t, idx in groups.items()
    ]
    cell_data = {
        key: [
            np.concatenate([mesh.cell_data[key][i] for i in idx])
            for idx in groups.values()
        ]
        for key in _TAGS
    }
    return meshio.Mesh(
        mesh.points, cells, cell_data=cell_data, field_data=mesh.field_data
    )


def read(path: str | pathlib.Path) -> meshio.Mesh:
    """Read any meshio-supported file (also inline-XML XDMF without h5py).

    Args:
        path: File to read; the format follows from the suffix.

    Returns:
        The meshio mesh.

    Raises:
        ValueError: For a suffix meshio does not know.

    """
    path = pathlib.Path(path)
    file_format = _file_format(path)
    with _h5py_not_required():
        return meshio.read(path, file_format=file_format)


def convert(
    msh_path: str | pathlib.Path,
    out_path: str | pathlib.Path,
    comm: MPI.Comm | None = None,
) -> pathlib.Path:
    """Convert a gmsh file to the format given by the suffix of ``out_path``.

    Only rank 0 of ``comm`` converts, with its paths (returned on all ranks);
    all ranks return after the file is written.

    Args:
        msh_path: gmsh ``.msh`` file, e.g. from :func:`breakwater.meshes.goda.generate`.
        out_path: Output file: ``.vtu``, ``.msh``, or any meshio suffix but XDMF's
            (the names are lost but in ``.msh``: for viewing).
        comm: MPI communicator; ``MPI.COMM_WORLD`` if None.

    Returns:
        The output path.

    Raises:
        ValueError: For an unknown suffix, or XDMF's (one line naming
            :func:`breakwater.model.mesh.convert_to_xdmf`), on all ranks before any work.
        Exception: What the conversion raised on rank 0, on every rank (see
            :func:`breakwater.common.parallel.on_rank_zero`).

    """
    file_format = _file_format(pathlib.Path(out_path))
    if pathlib.Path(out_path).suffix.lower() in _XDMF_SUFFIXES:
        raise ValueError(
            f"{out_path}: meshio's XDMF holds no physical group names, which a case reads "
            "its mesh by: write breakwater's with breakwater.model.mesh.convert_to_xdmf"
            f"(msh, out) or `python -m breakwater mesh CASE --out {pathlib.Path(out_path).name}`"
        )
    comm = MPI.COMM_WORLD if comm is None else comm
    paths = on_rank_zero(comm, lambda: (str(msh_path), str(out_path)))  # rank 0's paths
    src, out = (pathlib.Path(p) for p in paths)

    def write() -> None:
        out.parent.mkdir(parents=True, exist_ok=True)
        if file_format == "gmsh":
            if not out.exists() or not out.samefile(src):
                shutil.copyfile(src, out)
            return
        mesh = meshio.read(src, file_format="gmsh")
        meshio.write(out, _by_cell_type(mesh), file_format)

    on_rank_zero(comm, write)
    return out
