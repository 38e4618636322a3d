"""The XDMF mesh file of ``breakwater mesh --out x.xdmf``: what it holds, read without dolfinx.

dolfinx's ``XDMFFile`` writes the mesh (grid ``mesh``) and its meshtags (grids
``cell_tags``, ``facet_tags``, ``ridge_tags``, ``peak_tags``), whose values are gmsh's
integer physical tags: the names breakwater finds bodies and boundaries by are not
among them. breakwater's writer (:func:`breakwater.model.xdmfmesh.write_xdmf`) keeps
them in an ``<Information Name="breakwater_groups">`` element of the file's domain
(``XDMFFile.write_information``), a JSON object:

- ``groups``: name -> [dimension, tag], gmsh's physical groups;
- ``tags``: the meshtags grids written;
- ``gdim``: the model's dimension (2 plane strain, 3);
- ``shared``, ``empty``, ``ungrouped``: what the ``.msh`` reader found
  (:class:`breakwater.model.mesh.GroupedMeshData`), refused or reported again when the
  XDMF is read.

A second element, ``<Information Name="breakwater_h5">``, holds the SHA-256 of the
``.h5`` as written (added once dolfinx has closed the file): an ``.h5`` of the right
length whose bytes were overwritten (a bad copy, a disk's damage) is refused before
dolfinx reads it (HDF5 read garbled arrays without a word, or dolfinx aborted every
rank). A file written before 2026-11-28 has none: its ``.h5`` is checked for its length
only.

An XDMF without it (meshio's, one written by dolfinx elsewhere, breakwater's before it
wrote names) is refused: :func:`read_info`. This module reads the XML only (rank 0 or
every rank), so that a case is checked against its mesh's names before any solver
library is imported.
"""

from __future__ import annotations

import json
import os
import pathlib
import xml.etree.ElementTree as ET
from typing import Any

from breakwater.common.errors import MeshError
from breakwater.common.files import sha256_of

__all__ = ["DIGEST", "GROUPS", "MESH_GRID", "SUFFIXES", "TAG_GRIDS", "add_digest", "digest_problem",
           "hdf5_problem", "heavy_files", "is_xdmf", "read_info", "xdmf_groups"]

SUFFIXES = (".xdmf", ".xmf")
"""Suffixes of XDMF files."""
GROUPS = "breakwater_groups"
"""Name of the ``<Information>`` element holding the physical groups' names."""
DIGEST = "breakwater_h5"
"""Name of the ``<Information>`` element holding the SHA-256 of the ``.h5``."""
MESH_GRID = "mesh"
"""Name of the mesh's grid."""
TAG_GRIDS = ("cell_tags", "facet_tags", "ridge_tags", "peak_tags")
"""Names of the meshtags grids, codimension 0 to 3 (dolfinx's ``MeshData`` order)."""
VERSION = 1
"""Version of the ``breakwater_groups`` record."""

FOREIGN = ("an XDMF without breakwater's physical group names (meshio's, or dolfinx's "
           "meshtags: integer tags only), and breakwater finds bodies and boundaries by "
           "name: write it with `python -m breakwater mesh CASE --out {name}` (from the "
           "gmsh .msh or .geo), or give the .msh")
"""The refusal of an XDMF that breakwater did not write (``{name}``: the file's name)."""


def is_xdmf(path: pathlib.Path) -> bool:
    """Whether ``path`` names an XDMF file (by its suffix)."""
    return path.suffix.lower() in SUFFIXES


def _root(path: pathlib.Path) -> ET.Element:
    try:
        return ET.parse(path).getroot()
    except ET.ParseError as e:
        raise MeshError(f"{path}: cannot read the mesh (not XDMF: the XML is broken: "
                        f"{e})") from None
    except OSError as e:
        raise MeshError(f"{path}: cannot read the mesh ({e.strerror or e})") from None


def read_info(path: pathlib.Path) -> dict[str, Any]:
    """The ``breakwater_groups`` record of an XDMF mesh file, checked.

    Raises:
        MeshError: One line: the file is not XML, has no such record (an XDMF that
            breakwater did not write: :data:`FOREIGN`), a record of another version or
            broken, or lacks a grid the record names.
    """
    root = _root(path)
    domain = root.find("Domain")
    info = None if domain is None else domain.find(f"Information[@Name='{GROUPS}']")
    if domain is None or info is None:
        raise MeshError(f"{path}: {FOREIGN.format(name=path.name)}")
    try:
        record = json.loads(info.get("Value") or info.text or "")
        groups = {str(n): (int(d), int(t)) for n, (d, t) in record["groups"].items()}
        tags = [str(t) for t in record["tags"]]
        version = int(record.get("version", 0))
        if not set(tags) <= set(TAG_GRIDS):
            raise ValueError(tags)
    except (ValueError, KeyError, TypeError, AttributeError):
        raise MeshError(f"{path}: its {GROUPS} record is broken (edited?): write the file "
                        "again with `python -m breakwater mesh CASE --out "
                        f"{path.name}`") from None
    if version != VERSION:
        raise MeshError(f"{path}: its {GROUPS} record is of version {version}, this "
                        f"breakwater reads version {VERSION}: write the file again with "
                        f"`python -m breakwater mesh CASE --out {path.name}`")
    grids = {g.get("Name") for g in domain.findall("Grid")}
    missing = [g for g in (MESH_GRID, *tags) if g not in grids]
    if missing:
        raise MeshError(f"{path}: no grid {', '.join(repr(g) for g in missing)} in the file "
                        "(edited or cut short?): write it again with `python -m breakwater "
                        f"mesh CASE --out {path.name}`")
    record["groups"], record["tags"] = groups, tags
    return dict(record)


def heavy_files(path: pathlib.Path) -> pathlib.Path | None:
    """The HDF5 file holding the arrays of an XDMF file, or None when they are inline XML.

    dolfinx writes the arrays to ``x.h5`` beside ``x.xdmf`` (``Format="HDF"``) or, with
    ASCII encoding, into the XML; it reads them from the ``.h5`` of the ``.xdmf``'s name,
    whatever file the items name (a pair renamed together reads).
    """
    if any(item.get("Format", "XML") == "HDF" for item in _root(path).iter("DataItem")):
        return path.with_suffix(".h5")
    return None


_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def hdf5_problem(h5: pathlib.Path) -> str | None:
    """What makes an HDF5 file unreadable at a glance: not HDF5, or cut short.

    The superblock (at byte 0, or 512, 1024, ... after a user block) stores the file's
    end address: a copy cut short (an interrupted transfer) ends before it. Checked
    before HDF5 opens the file, which prints its error stack (30 lines) to stderr.

    Returns:
        None, or the problem ("not an HDF5 file", "cut short: ...").
    """
    size = h5.stat().st_size
    with open(h5, "rb") as f:
        at = 0
        while True:
            f.seek(at)
            head = f.read(64)
            if head.startswith(_SIGNATURE):
                break
            at = 512 if at == 0 else 2 * at
            if at >= size:
                return "not an HDF5 file"
    version, offsets = head[8], head[13] if head[8] < 2 else head[9]
    if offsets not in (2, 4, 8):
        return "not an HDF5 file (its superblock is broken)"
    start = {0: 24, 1: 28}.get(version, 12)  # the base address, then EOF two on
    base = int.from_bytes(head[start:start + offsets], "little")
    end = int.from_bytes(head[start + 2 * offsets:start + 3 * offsets], "little")
    if at + base + end > size:
        return f"cut short: {size} of its {at + base + end} bytes"
    return None


def add_digest(path: pathlib.Path, h5: pathlib.Path) -> None:
    """Record the SHA-256 of ``h5`` in ``path`` (rank 0, once dolfinx closed both).

    The element goes on a line of its own after the ``breakwater_groups`` record (the
    rest of dolfinx's XML is kept as written); the file is replaced atomically.
    """
    lines = path.read_text().splitlines(keepends=True)
    at = next(i for i, line in enumerate(lines) if f'Name="{GROUPS}"' in line)
    indent = lines[at][:len(lines[at]) - len(lines[at].lstrip())]
    lines.insert(at + 1, f'{indent}<Information Name="{DIGEST}" Value="sha256:'
                         f'{sha256_of(h5)}" />\n')
    temporary = path.with_name(f".{path.name}.tmp")
    temporary.write_text("".join(lines))
    os.replace(temporary, path)


def digest_problem(path: pathlib.Path, h5: pathlib.Path) -> str | None:
    """What is wrong with ``h5`` if it holds other bytes than those recorded in ``path``.

    Returns:
        None (the same bytes, or no digest recorded), or the problem ("damaged, ...").
    """
    domain = _root(path).find("Domain")
    info = None if domain is None else domain.find(f"Information[@Name='{DIGEST}']")
    value = None if info is None else info.get("Value", "")
    if value is None or not value.startswith("sha256:"):
        return None
    if sha256_of(h5) != value.removeprefix("sha256:"):
        return "damaged, its bytes not the ones written with it (a bad copy, a disk's damage)"
    return None


def xdmf_groups(path: pathlib.Path) -> dict[str, int]:
    """The named physical groups (name -> dimension) of breakwater's XDMF mesh file.

    Raises:
        MeshError: As :func:`read_info`.
    """
    return {name: dim for name, (dim, _) in read_info(path)["groups"].items()}
