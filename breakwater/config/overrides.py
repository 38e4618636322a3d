"""``--set key=value`` overrides: a dotted key path checked against the schema, a TOML value.

:func:`apply_override` changes the raw data of a file before it is built: the key is
checked table by table (unknown keys refused with the closest valid one; its parts bare
or quoted as in TOML, ``contact."a b".friction``), an entry of
a named collection is given by its name or its index, a table value is merged into the
case's table key by key (as ``extends`` merges files; a new entry of a named collection
is given whole, as a table), a path value is resolved against the working directory;
the value is a TOML value, a bare word a string (:func:`parse_value`).
"""

from __future__ import annotations

import dataclasses
import os
import pathlib
import tomllib
from collections.abc import Collection, Iterable, Mapping
from dataclasses import fields
from typing import Any

from breakwater.common.errors import CaseError
from breakwater.config.fields import (
    key_field,
    keyed_item,
    optional,
    shown,
    suggest,
    suggest_key,
    type_hints,
)
from breakwater.config.tomlfiles import OUT_OF_RANGE, out_of_range, record, resolved

__all__ = ["OVERRIDE", "Override", "apply_override", "file_argument", "origin_of",
           "override_list", "parse_value", "path_key"]

OVERRIDE = "--set"
"""Origin of a value given as a ``key=value`` override."""


class Override(str):
    """A ``key=value`` override that names its origin for the messages.

    A study's values reach its cases as overrides beside ``sweep --set``'s: they are
    labelled with the study file, so that a bad value is blamed on where it was given
    (a ``--set`` value was named as the study's).
    """

    origin: str

    def __new__(cls, spec: str, origin: str = OVERRIDE) -> Override:
        """``spec`` (``key=value``) from ``origin`` (``--set``, a study file's name)."""
        self = super().__new__(cls, spec)
        self.origin = origin
        return self


def origin_of(spec: str) -> str:
    """Where an override was given: its :class:`Override` origin, else ``--set``."""
    return spec.origin if isinstance(spec, Override) else OVERRIDE


def override_list(overrides: Any, example: str = "load_case(None, ['time.end_time=0.05', "
                  "'contact.interface.friction=0.5'])") -> list[str]:
    """Overrides given from Python as a list of strings (None: none).

    A single string was read character by character (``load_case(None,
    "time.end_time=0.05")`` said ``--set t: expected key=value``), a dict by its keys
    (``--set time.end_time: expected key=value``), and None failed with ``TypeError:
    'NoneType' object is not iterable``.

    Args:
        overrides: A list (or tuple, or iterable) of ``key=value`` strings, or None.
        example: The call the message shows.

    Raises:
        CaseError: Not a list (or tuple) of strings, in one line saying what is.
    """
    if overrides is None:
        return []
    expected = f"overrides: expected a list of 'key=value' strings (e.g. {example})"
    if isinstance(overrides, str | bytes | Mapping) or not isinstance(overrides, Iterable):
        what = "a dict" if isinstance(overrides, Mapping) else shown(overrides)
        raise CaseError(f"{expected}, got {what}")
    items = list(overrides)
    wrong = next((o for o in items if not isinstance(o, str)), None)
    if wrong is not None:
        raise CaseError(f"{expected}, got an item {shown(wrong)}")
    return items


def file_argument(path: Any, what: str) -> None:
    """Refuse a file argument given from Python that is not a str or a path.

    ``load_case({...})`` or ``load_study(case)`` failed in ``pathlib`` with
    ``TypeError: argument should be a str or an os.PathLike object ...``.

    Args:
        path: The argument.
        what: What it names, e.g. ``"a case file (or a built-in case name, 'goda')"``.

    Raises:
        CaseError: One line saying what was given.
    """
    if not isinstance(path, str | os.PathLike):
        raise CaseError(f"path: expected {what} as a str or a pathlib.Path, got "
                        f"{shown(path)}")


def _split(spec: str) -> tuple[str, str] | None:
    r"""``key=value`` split at the first ``=`` outside the key's quotes (None: no ``=``).

    In a double-quoted part a backslash escapes the next character (TOML's ``"a\"b"``).
    """
    quote, escaped = "", False
    for i, c in enumerate(spec):
        if escaped:
            escaped = False
        elif quote == '"' and c == "\\":
            escaped = True
        elif quote:
            quote = "" if c == quote else quote
        elif c in "\"'":
            quote = c
        elif c == "=":
            return spec[:i].strip(), spec[i + 1:].strip()
    return None


def key_parts(key: str) -> list[str]:
    """The parts of a dotted key, each bare or quoted as in TOML (``contact."a b".friction``).

    A key TOML does not read as a dotted key is split at its dots (the schema's checks
    then name what is wrong in it).
    """
    try:
        data: Any = tomllib.loads(f"{key} = 0")
    except tomllib.TOMLDecodeError:
        return key.split(".")
    parts = []
    while isinstance(data, dict) and len(data) == 1:
        ((k, data),) = data.items()
        parts.append(k)
    return parts if data == 0 and not isinstance(data, dict) else key.split(".")


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
                   spec: str, origins: dict[str, str],
                   merged: list[str] | None = None) -> None:
    """Apply one ``key=value`` override to the raw data, checking the key path.

    A table value is merged into the case's table of that key, key by key, as
    ``extends`` merges files: ``damping={alpha=0.1}`` is ``damping.alpha=0.1``, the
    table's other keys stay (replacing the table would set them back to their defaults,
    silently). An empty table empties it (``output.probes={}``: no probes;
    ``damping={}``: the defaults), so that ``X={}`` then ``X={...}`` replaces it. A
    table value for an entry of a named collection that the case does not have creates
    it (``fixed.sides={components=[0]}``); a dotted key into such an entry is refused,
    naming the entries (a typo of a name is more likely).

    Args:
        root: The dataclass of a whole file.
        paths: The path keys (:attr:`Schema.paths <breakwater.config.schema.Schema.paths>`):
            a path value is resolved against the working directory.
        raw: The data of the file(s), changed in place.
        spec: The override, ``key=value``.
        origins: Where each key came from; the key's entries become ``--set`` (or
            the :class:`Override`'s origin, which the messages name too).
        merged: When given, the dotted keys of the tables a table value was merged into
            are appended (for the messages).

    Raises:
        CaseError: A malformed override, or a key path the schema does not have.
    """
    label = origin_of(spec)
    split = _split(spec)
    if split is None:
        raise CaseError(f"{label} {spec}: expected key=value")
    key, text = split
    parts = key_parts(key)
    if not key or not all(parts):
        raise CaseError(f"{label} {spec}: empty key")
    value = parse_value(text)
    if out_of_range(value) is not None:
        raise CaseError(f"{label} {key}: {OUT_OF_RANGE}")
    _set(root, paths, raw, parts, value, origins, merged, label)


def _set(root: type, paths: Mapping[str, Collection[str]], raw: dict[str, Any],
         parts: list[str], value: Any, origins: dict[str, str],
         merged: list[str] | None, label: str) -> None:
    """Set the value of the key path ``parts`` (a table value: key by key)."""
    node, part, here, table = _walk(root, raw, parts, origins, label)
    if table and isinstance(value, dict):
        if isinstance(node.get(part), dict) and value:
            if merged is not None and node[part]:
                merged.append(here)
        else:  # a table the override creates, or empties ({}: back to the defaults,
            node[part] = {}  # no entries), or a value it replaces: its keys are its own
            _forget(here, origins)
            origins[here] = label
        for k, v in value.items():
            _set(root, paths, raw, [*parts, k], v, origins, merged, label)
        return
    not_paths = path_key(paths, here)
    if not_paths is not None and isinstance(value, str) and value not in not_paths:
        value = resolved(pathlib.Path(), value, f"{label} {'.'.join(parts)}")
    node[part] = value
    _forget(here, origins)
    origins[here] = label
    record(value, label, here, origins)


def _forget(here: str, origins: dict[str, str]) -> None:
    """Drop the origins of the key ``here`` and of the keys under it."""
    for p in [p for p in origins if p == here or p.startswith(here + ".")]:
        del origins[p]


def _walk(root: type, raw: dict[str, Any], parts: list[str], origins: dict[str, str],
          label: str = OVERRIDE) -> tuple[dict[str, Any], str, str, bool]:
    """Where the key path ``parts`` goes: its table, last key and dotted path.

    Also whether the schema's value there is a table (a dataclass, a named collection
    or an entry of one). The tables on the way that the case does not have are made
    (their origin ``label``, ``--set``).

    Raises:
        CaseError: A key path the schema does not have, or a dotted key into an entry
            of a named collection that the case does not have.
    """
    key = ".".join(parts)
    cls: Any = root
    node = raw
    done: list[str] = []
    i = 0
    while True:
        part = parts[i]
        here = ".".join([*done, part])
        if not dataclasses.is_dataclass(cls):
            raise CaseError(f"{label} {key}: '{'.'.join(done)}' is not a table")
        key_name = key_field(cls)
        valid = [f.name for f in fields(cls) if f.init and f.name != key_name]
        if part not in valid:
            raise CaseError(f"{label} {key}: unknown key '{here}'"
                            f"{suggest_key(root, part, valid)} "
                            f"(valid keys: {', '.join(valid)})")
        tp = type_hints(cls)[part]
        item = keyed_item(tp)
        last = i == len(parts) - 1
        target = optional(tp) or tp
        if last:
            return node, part, here, item is not None or dataclasses.is_dataclass(target)
        if part not in node:  # a table the override creates: its keys are its own
            origins[here] = label
        if item is not None:
            table = node.setdefault(part, {})
            if not isinstance(table, dict):
                raise CaseError(f"{label} {key}: '{here}' is not a table")
            names = list(table)
            entry = parts[i + 1]
            if entry not in table and entry.isdigit() and int(entry) < len(names):
                entry = names[int(entry)]
            if i + 1 == len(parts) - 1:  # the whole entry is set (or created)
                return table, entry, f"{here}.{entry}", True
            if entry not in table:
                raise CaseError(f"{label} {key}: no entry '{parts[i + 1]}' in "
                                f"{here}{suggest(parts[i + 1], names)} "
                                f"(entries: {', '.join(names) or 'none'}; a new entry is "
                                f"given whole: {OVERRIDE} '{here}.{parts[i + 1]}="
                                "{key = value, ...}')")
            done += [part, entry]
            node, cls = table[entry], item
            i += 2
            continue
        if not dataclasses.is_dataclass(target):
            raise CaseError(f"{label} {key}: '{here}' is not a table")
        sub = node.setdefault(part, {})
        if not isinstance(sub, dict):
            raise CaseError(f"{label} {key}: '{here}' is not a table")
        done.append(part)
        node, cls = sub, target
        i += 1
