"""TOML files of typed settings: read, their paths resolved, merged, and where a key came from.

The file side of :class:`~breakwater.config.schema.Schema`: :func:`read_toml` (UTF-8,
valid TOML, 64-bit integers: :func:`out_of_range`), :func:`resolved` (a path value
against the file's folder), :func:`merge` (``extends``: table by table),
:func:`record` and :func:`origin` (the file, or ``--set``, each key came from, for the
messages), :func:`display` (a path as the messages name it), :func:`toml_literal` (a
value's TOML text, for a ``key=value`` override).
"""

from __future__ import annotations

import codecs
import datetime
import json
import pathlib
import tomllib
from collections.abc import Mapping
from typing import Any

from breakwater.common.errors import CaseError
from breakwater.common.files import path_problem

__all__ = ["INTEGER_RANGE", "OUT_OF_RANGE", "display", "merge", "origin", "out_of_range",
           "read_toml", "record", "resolved", "toml_literal"]


def display(path: pathlib.Path) -> str:
    """A path as the messages name it: relative to the working directory if inside."""
    try:
        return str(path.resolve().relative_to(pathlib.Path.cwd()))
    except ValueError:
        return str(path)


def read_toml(path: pathlib.Path) -> dict[str, Any]:
    """A TOML file's data (UTF-8, a byte-order mark or not), or a one-line CaseError."""
    try:
        raw = path.read_bytes()
        if raw.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
            raise CaseError(f"{display(path)}: UTF-16 text (a spreadsheet's \"Unicode "
                            "text\"?): save the file as UTF-8")
        # A byte-order mark (Notepad's or Excel's "UTF-8"): read, as the tables are.
        data = tomllib.loads(raw.decode("utf-8-sig"))
    except UnicodeDecodeError as e:
        line = raw.count(b"\n", 0, e.start) + 1
        column = e.start - (raw.rfind(b"\n", 0, e.start) + 1) + 1
        raise CaseError(f"{display(path)}: not UTF-8 text: byte 0x{raw[e.start]:02x} at "
                        f"position {e.start} (line {line}, column {column}); save the "
                        "file as UTF-8") from None
    except tomllib.TOMLDecodeError as e:
        raise CaseError(f"{display(path)}: invalid TOML: {e}") from None
    except OSError as e:
        raise CaseError(f"{display(path)}: cannot read the case file "
                        f"({e.strerror or e})") from None
    except ValueError as e:  # tomllib's int() of an integer of more than 4300 digits
        raise CaseError(f"{display(path)}: invalid TOML: {str(e).split(':')[0]}") from None
    key = out_of_range(data)
    if key is not None:
        raise CaseError(f"{display(path)}: {key}: {OUT_OF_RANGE}")
    return data


INTEGER_RANGE = (-(2**63), 2**63 - 1)
"""The integers of TOML (64-bit); :mod:`tomllib` reads any size."""
OUT_OF_RANGE = "integer out of the 64-bit range of TOML"


def out_of_range(data: Any, prefix: str = "") -> str | None:
    """The dotted key of the first integer of ``data`` beyond :data:`INTEGER_RANGE`.

    Refused when read, before any conversion: a bigger integer makes ``float()``
    overflow and cannot even be printed past 4300 digits.
    """
    if isinstance(data, int) and not isinstance(data, bool):
        lo, hi = INTEGER_RANGE
        return None if lo <= data <= hi else prefix
    items = data.items() if isinstance(data, dict) else \
        enumerate(data) if isinstance(data, list) else ()
    for k, v in items:
        where = f"{prefix}[{k}]" if isinstance(k, int) else f"{prefix}.{k}" if prefix else k
        found = out_of_range(v, where)
        if found is not None:
            return found
    return None


def record(data: Any, label: str, prefix: str, origins: dict[str, str]) -> None:
    """Note the file every key (and table) comes from."""
    if isinstance(data, dict):
        for k, v in data.items():
            p = f"{prefix}.{k}" if prefix else k
            origins[p] = label
            record(v, label, p, origins)


def resolved(folder: pathlib.Path, text: str, where: str) -> str:
    """The absolute path of ``text`` (relative to ``folder``), or a CaseError at ``where``."""
    problem = path_problem(text)
    if problem is None:
        try:
            return str((folder / text).resolve())
        except (OSError, ValueError) as e:  # the folder and the path together too long
            problem = e.strerror if isinstance(e, OSError) and e.strerror else str(e)
    raise CaseError(f"{where}: {problem}")


def merge(base: dict[str, Any], top: Mapping[str, Any]) -> dict[str, Any]:
    """``top`` merged over ``base``, table by table."""
    out = dict(base)
    for k, v in top.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = merge(out[k], v)
        else:
            out[k] = v
    return out


def origin(path: str, origins: Mapping[str, str], default: str) -> str:
    """The file (or ``--set``) the dotted key ``path`` (or its closest table) came from."""
    parts = path.replace("[", ".[").split(".")
    for n in range(len(parts), 0, -1):
        p = ".".join(parts[:n]).replace(".[", "[")
        if p in origins:
            return origins[p]
    return default


def toml_literal(value: Any) -> str:
    """The TOML text of a value (for a ``key=value`` override)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value)  # TOML spells inf and nan as Python does
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, datetime.date | datetime.time):
        return value.isoformat()  # TOML's dates and times (the case refuses them)
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{_string(str(k))} = {toml_literal(v)}"
                               for k, v in value.items()) + "}"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(toml_literal(v) for v in value) + "]"
    raise TypeError(f"no TOML literal for {value!r}")


def _string(text: str) -> str:
    """A TOML basic string.

    JSON's, but the characters beyond U+FFFF kept (JSON would write surrogate pairs,
    which TOML refuses) and DEL escaped (TOML refuses it raw).
    """
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")
