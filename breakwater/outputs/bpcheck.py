"""The files of an ADIOS2 BP5 folder checked before ADIOS2 opens it.

ADIOS2's reader trusts the lengths its metadata files hold: an ``mmd.0`` (the
meta-metadata, the formats of the steps' metadata) cut short or zero-filled, or an
empty ``md.idx``, crashed the process (a segmentation fault, measured with ADIOS2
2.10: a notebook's kernel died, a script ended without a line). :func:`check_bp`
walks the records of ``md.idx`` and ``mmd.0`` and the spans of ``md.0`` they list,
so that such a folder is refused in one line naming the file.

The layouts read (ADIOS2's BP5 engine, ``source/adios2/toolkit/format/bp5``):

* ``md.idx``: a 64-byte header (``ADIOS-BP v...``, byte 37 the format's version: a
  folder of another than BP5 is left to ADIOS2), then records of a type byte
  (``w``: the writers' map, ``s``: a step), a little-endian ``uint64`` length and that
  many bytes; a step's first two ``uint64`` are its position and size in ``md.0``.
  A trailing record cut short is a step a running writer has not finished listing:
  left to ADIOS2, which reads the whole steps before it.
* ``mmd.0``: records of two ``uint64`` lengths (an ID's and a format's), then the ID
  and the format, each of at least one byte, to the file's end; a format holding a run
  of 64 zeros is taken for zero-filled blocks (the formats of the VTX files of 2-D and
  3-D runs hold runs of at most 20). Zeros in fewer bytes of a format are not told from
  a format's own: ADIOS2 may still crash on them.
"""

from __future__ import annotations

import pathlib
import struct

__all__ = ["BPDamaged", "check_bp"]

_HEADER = 64
_BP_VERSION = 37  # the header's byte of the BP format's version (4: BP4, 5: BP5)
_RECORD_TYPES = (b"w", b"s")
#: A run of zeros no format holds (at most 20 in the VTX files of 2-D and 3-D runs): a
#: power loss's zero-filled blocks.
_ZEROS = bytes(64)


class BPDamaged(Exception):
    """A file of a BP5 folder is missing, empty, cut short or damaged.

    ``args[0]`` is the file's name and what is wrong with it (``mmd.0 is cut short``).
    """


class _NotBP5(Exception):
    """Another BP format (BP4: no mmd.0, records of another layout): left to ADIOS2."""


def _read(folder: pathlib.Path, name: str) -> bytes:
    path = folder / name
    if not path.is_file():
        raise BPDamaged(f"{name} is missing")
    data = path.read_bytes()
    if not data:
        raise BPDamaged(f"{name} is empty")
    if not any(data):
        raise BPDamaged(f"{name} is zero-filled ({len(data)} bytes of zeros)")
    return data


def _steps(index: bytes) -> list[tuple[int, int]]:
    """The (position, size) in ``md.0`` of each step ``md.idx`` lists in whole."""
    if len(index) < _HEADER:
        raise BPDamaged(f"md.idx is cut short ({len(index)} bytes, its header is "
                        f"{_HEADER})")
    if not index.startswith(b"ADIOS-BP v"):
        raise BPDamaged("md.idx is damaged (no ADIOS-BP header)")
    if index[_BP_VERSION] != 5:
        raise _NotBP5
    steps, at = [], _HEADER
    while at + 9 <= len(index):
        kind, (length,) = index[at:at + 1], struct.unpack_from("<Q", index, at + 1)
        if kind not in _RECORD_TYPES or length % 8 or (kind == b"s" and length < 16):
            raise BPDamaged(f"md.idx is damaged (a record of type {kind!r} and "
                            f"{length} bytes at byte {at})")
        if at + 9 + length > len(index):
            break  # a step a running writer has not finished listing
        if kind == b"s":
            steps.append(struct.unpack_from("<QQ", index, at + 9))
        at += 9 + length
    return steps


def _formats(meta: bytes) -> list[bytes]:
    """The IDs of the formats ``mmd.0`` holds, its records checked to the file's end."""
    ids, at = [], 0
    while at < len(meta):
        if at + 16 > len(meta):
            raise BPDamaged(f"mmd.0 is cut short (a record's lengths at byte {at} of "
                            f"{len(meta)})")
        id_len, info_len = struct.unpack_from("<QQ", meta, at)
        if not id_len or not info_len:
            raise BPDamaged(f"mmd.0 is damaged (a record of no length at byte {at})")
        end = at + 16 + id_len + info_len
        if end > len(meta):
            raise BPDamaged(f"mmd.0 is cut short ({len(meta)} bytes, its records list "
                            f"{end} or more)")
        if _ZEROS in meta[at + 16 + id_len:end]:
            raise BPDamaged(f"mmd.0 is damaged (a run of zeros in the format at byte {at})")
        ids.append(meta[at + 16:at + 16 + id_len])
        at = end
    return ids


def check_bp(folder: pathlib.Path) -> None:
    """Check the metadata files of the BP5 folder ``folder`` before ADIOS2 reads them.

    Raises:
        BPDamaged: ``md.idx``, ``md.0`` or ``mmd.0`` missing, empty, zero-filled, cut
            short (shorter than the spans listed in them or in ``md.idx``) or damaged
            (records of no length or of an unknown type, a format's ID that no step's
            metadata names); a folder that is not one.
    """
    if not folder.is_dir():
        raise BPDamaged(f"{folder.name} is not a folder (a .bp output is one)")
    try:
        steps = _steps(_read(folder, "md.idx"))
    except _NotBP5:
        return
    if not steps:
        return  # no step written yet: ADIOS2 reads none
    metadata = _read(folder, "md.0")
    end = max(p + s for p, s in steps)
    if end > len(metadata):
        raise BPDamaged(f"md.0 is cut short ({len(metadata)} bytes, md.idx lists {end})")
    for position, size in steps:
        if not any(metadata[position:position + size]):
            raise BPDamaged(f"md.0 is damaged (zeros where md.idx lists a step at byte "
                            f"{position})")
    listed = metadata[:end]
    for name in _formats(_read(folder, "mmd.0")):
        if name not in listed:
            raise BPDamaged("mmd.0 is damaged (a format that no step's metadata names)")
