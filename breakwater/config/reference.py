"""The reference of a schema: a Markdown table of every key, its type, unit, default and meaning.

:func:`reference` walks a tree of dataclasses declared with
:func:`~breakwater.config.fields.setting` (``show-case --reference``, the case-key table
of the documentation).
"""

from __future__ import annotations

import dataclasses
from dataclasses import MISSING, fields
from typing import Any

from breakwater.config.fields import keyed_item, optional, to_toml, type_hints, type_name

__all__ = ["reference"]


def reference(root: type) -> str:
    """A Markdown table of every key: type, unit, default, meaning.

    A nested dataclass whose fields carry no :func:`~breakwater.config.fields.setting`
    metadata (e.g. :class:`~breakwater.meshes.GodaGeometry`) takes its meanings from the
    ``Attributes:`` of its docstring and its unit from the field holding it (unless a
    field's metadata gives its own).
    """
    rows = ["| key | type | unit | default | meaning |", "|---|---|---|---|---|",
            '| `extends` | string | - | — | start from another case: a built-in name '
            '("goda") or a file (relative to this one); this file is merged over it, '
            'table by table |']
    _walk(root, "", rows, None)
    return "\n".join(rows)


def _walk(cls: Any, prefix: str, rows: list[str], unit_of_table: str | None) -> None:
    hints = type_hints(cls)
    docs = _attribute_docs(cls) if unit_of_table is not None else {}
    for f in fields(cls):
        tp = hints[f.name]
        key = f"{prefix}.{f.name}" if prefix else f.name
        if f.metadata.get("key"):
            continue
        item = keyed_item(tp)
        nested = optional(tp) or tp
        unit = f.metadata.get("unit", unit_of_table or "-")
        doc = f.metadata.get("doc", docs.get(f.name, ""))
        if item is not None:
            key_doc = next(g.metadata["doc"] for g in fields(item) if g.metadata["key"])
            rows.append(f"| `[{key}.<name>]` | table | | | {doc}; `<name>`: {key_doc} |")
            _walk(item, f"{key}.<name>", rows, None)
        elif dataclasses.is_dataclass(nested):
            rows.append(f"| `[{key}]` | table | | | {doc} |")
            documented = any("doc" in g.metadata for g in fields(nested))
            _walk(nested, key, rows, None if documented else unit)
        else:
            kind = type_name(tp).replace("|", "\\|")
            rows.append(f"| `{key}` | {kind} | {unit} | {_default_text(f)} | {doc} |")


def _default_text(f: dataclasses.Field[Any]) -> str:
    if f.metadata.get("key"):
        return "(table name)"
    if f.default is MISSING:
        return "required"
    if f.default is None:
        return "—"
    if dataclasses.is_dataclass(f.default) or f.default == ():
        return ""
    return f"`{_toml_value(to_toml(f.default))}`"


def _toml_value(value: Any) -> str:
    """A short TOML rendering of a default value."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return repr(value)


def _attribute_docs(cls: type) -> dict[str, str]:
    """``Attributes:`` entries of a Google-style class docstring."""
    docs: dict[str, str] = {}
    lines = (cls.__doc__ or "").splitlines()
    current = None
    inside = False
    for line in lines:
        s = line.strip()
        if s == "Attributes:":
            inside = True
            continue
        if not inside:
            continue
        if not s:
            if docs:
                break
            continue
        if ":" in s and s.split(":", 1)[0].isidentifier():
            current, text = s.split(":", 1)
            docs[current] = text.strip()
        elif current is not None:
            docs[current] += " " + s
    return docs
