"""``--set key=value`` overrides: a dotted key path checked against the schema, a TOML value.

:func:`apply_override` changes the raw data of a file before it is built: the key is
checked table by table (unknown keys refused with the closest valid one), an entry of
a named collection is given by its name or its index, a whole entry may be given (or
created) as an inline table, a path value is resolved against the working directory;
the value is a TOML value, a bare word a string (:func:`parse_value`).
"""

from __future__ import annotations

import dataclasses
import pathlib
import tomllib
from collections.abc import Collection, Mapping
from dataclasses import fields
from typing import Any

from breakwater.common.errors import CaseError
from breakwater.config.fields import (
    key_field,
    keyed_item,
    optional,
    suggest,
    suggest_key,
    type_hints,
)
from breakwater.config.tomlfiles import OUT_OF_RANGE, out_of_range, record, resolved

__all__ = ["OVERRIDE", "apply_override", "parse_value", "path_key"]

OVERRIDE = "--set"
"""Origin of a value given as a ``key=value`` override."""


def parse_value(text: str) -> Any:
    """A TOML value, or the bare text as a string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text.strip()


def path_key(paths: Mapping[str, Collection[str]], here: str) -> Collection[str] | None:
    """The names that are not paths, if the dotted key ``here`` is a path key of ``paths``.

    A ``*`` in a path key stands for any entry of a table (``loads.*.table.file``).
    """
    parts = here.split(".")
    for key, names in paths.items():
        pattern = key.split(".")
        if len(pattern) == len(parts) and all(p in ("*", q)
                                              for p, q in zip(pattern, parts, strict=True)):
            return names
    return None


def apply_override(root: type, paths: Mapping[str, Collection[str]], raw: dict[str, Any],
                   spec: str, origins: dict[str, str]) -> None:
    """Apply one ``key=value`` override to the raw data, checking the key path.

    Args:
        root: The dataclass of a whole file.
        paths: The path keys (:attr:`Schema.paths <breakwater.config.schema.Schema.paths>`):
            a path value is resolved against the working directory.
        raw: The data of the file(s), changed in place.
        spec: The override, ``key=value``.
        origins: Where each key came from; the key's entries become ``--set``.

    Raises:
        CaseError: A malformed override, or a key path the schema does not have.
    """
    if "=" not in spec:
        raise CaseError(f"{OVERRIDE} {spec}: expected key=value")
    key, text = (s.strip() for s in spec.split("=", 1))
    parts = key.split(".")
    if not key or not all(parts):
        raise CaseError(f"{OVERRIDE} {spec}: empty key")
    value = parse_value(text)
    if out_of_range(value) is not None:
        raise CaseError(f"{OVERRIDE} {key}: {OUT_OF_RANGE}")
    cls: Any = root
    node = raw
    done: list[str] = []
    i = 0
    while i < len(parts):
        part = parts[i]
        here = ".".join([*done, part])
        if not (dataclasses.is_dataclass(cls)):
            raise CaseError(f"{OVERRIDE} {key}: '{'.'.join(done)}' is not a table")
        key_name = key_field(cls)
        valid = [f.name for f in fields(cls) if f.init and f.name != key_name]
        if part not in valid:
            raise CaseError(f"{OVERRIDE} {key}: unknown key '{here}'"
                            f"{suggest_key(root, part, valid)} "
                            f"(valid keys: {', '.join(valid)})")
        tp = type_hints(cls)[part]
        item = keyed_item(tp)
        last = i == len(parts) - 1
        if part not in node:  # a table the override creates: its keys are its own
            origins[here] = OVERRIDE
        if item is not None and not last:
            table = node.setdefault(part, {})
            if not isinstance(table, dict):
                raise CaseError(f"{OVERRIDE} {key}: '{here}' is not a table")
            names = list(table)
            entry = parts[i + 1]
            if entry not in table and entry.isdigit() and int(entry) < len(names):
                entry = names[int(entry)]
            whole = i + 1 == len(parts) - 1  # the whole entry is set (or created)
            if entry not in table and not (whole and isinstance(value, dict)):
                raise CaseError(f"{OVERRIDE} {key}: no entry '{parts[i + 1]}' in "
                                f"{here}{suggest(parts[i + 1], names)} "
                                f"(entries: {', '.join(names) or 'none'})")
            done += [part, entry]
            if whole:
                node, part, here = table, entry, ".".join(done)
                break
            node, cls = table[entry], item
            i += 2
            continue
        target = optional(tp) or tp
        if not last:
            if not dataclasses.is_dataclass(target):
                raise CaseError(f"{OVERRIDE} {key}: '{here}' is not a table")
            sub = node.setdefault(part, {})
            if not isinstance(sub, dict):
                raise CaseError(f"{OVERRIDE} {key}: '{here}' is not a table")
            done.append(part)
            node, cls = sub, target
            i += 1
            continue
        break
    not_paths = path_key(paths, here)
    if not_paths is not None and isinstance(value, str) and value not in not_paths:
        value = resolved(pathlib.Path(), value, f"{OVERRIDE} {key}")
    node[part] = value
    for p in [p for p in origins if p == here or p.startswith(here + ".")]:
        del origins[p]
    origins[here] = OVERRIDE
    record(value, OVERRIDE, here, origins)
