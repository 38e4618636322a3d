"""The fields of typed settings: declared, checked, typed, and written back as TOML data.

The machinery under :class:`~breakwater.config.schema.Schema`, one job: what a field is.

- :func:`setting` declares a dataclass field with its unit and meaning (and marks the
  key of a *named collection*: ``tuple[Item, ...]`` of a dataclass with a ``key``
  field, a table of tables keyed by the item's name);
- :class:`InvalidField`, :func:`positive`, :func:`suggest`, :func:`printable`: a
  dataclass's own checks in ``__post_init__`` and their one-line messages;
- the annotations (:func:`type_hints`, :func:`keyed_item`, :func:`optional`,
  :func:`alternatives`, :func:`type_name`), every dotted key of a tree of dataclasses
  (:func:`schema_keys`, :func:`suggest_key`) and the TOML data of a dataclass
  (:func:`to_toml`).
"""

from __future__ import annotations

import dataclasses
import difflib
import types
import typing
from collections.abc import Sequence
from dataclasses import MISSING, field, fields
from typing import Any, Literal

from breakwater.common.errors import CaseError

__all__ = ["InvalidField", "alternatives", "column_name", "describe", "key_field", "keyed_item",
           "optional", "positive", "printable", "schema_keys", "setting", "shown", "suggest",
           "suggest_key", "to_toml", "type_hints", "type_name"]


class InvalidField(CaseError):
    """A field's value is invalid; ``field`` is relative to the object that raised.

    ``others``: the sibling fields the problem involves too (``dt`` against
    ``end_time``), so that a message blames a ``--set`` of any of them.
    """

    def __init__(self, field_path: str, problem: str, others: tuple[str, ...] = ()) -> None:
        super().__init__(f"{field_path}: {problem}" if field_path else problem)
        self.field = field_path
        self.problem = problem
        self.others = others

    def __reduce__(self) -> tuple[Any, ...]:
        return type(self), (self.field, self.problem, self.others)

    def within(self, prefix: str) -> InvalidField:
        """The same error with the field path prefixed."""
        path = ".".join(p for p in (prefix, self.field) if p)
        return InvalidField(path, self.problem, self.others)

    def fields(self) -> list[str]:
        """The dotted paths of the field and of the others it involves."""
        parent = self.field.rsplit(".", 1)[0] if "." in self.field else ""
        return [self.field, *(f"{parent}.{o}" if parent else o for o in self.others)]


def setting(default: Any = MISSING, *, unit: str = "-", doc: str = "", key: bool = False
            ) -> Any:
    """A dataclass field documented with its unit (and marked as the key of a table)."""
    return field(default=default, metadata={"unit": unit, "doc": doc, "key": key})


def positive(value: float, name: str, strict: bool = True) -> None:
    """Raise :class:`InvalidField` unless ``value`` > 0 (``strict``) or >= 0."""
    if not (value > 0 if strict else value >= 0):
        raise InvalidField(name, f"must be {'>' if strict else '>='} 0 (got {value:g})")


def column_name(name: str, field_path: str = "name") -> None:
    """Raise :class:`InvalidField` unless ``name`` can head ``history.csv`` columns.

    A probe's name prefixes its columns (``<name>_ux``): a comma, a double quote or a
    line break in it split or broke the CSV header (one column more in the header
    than in the rows: ``read_history`` failed, other readers shifted the columns);
    an empty name gave ``body@(x, y)``, a comma too.
    """
    bad = sorted({c for c in name if c in ',"' or not c.isprintable()})
    if not name or bad:
        why = (f"it holds {printable(' '.join(repr(c) for c in bad))}: no comma, double "
               "quote or control character" if bad else "empty")
        raise InvalidField(field_path, f"{printable(repr(name))} cannot name history.csv "
                           f"columns ({why})")


def printable(text: str) -> str:
    r"""``text`` with its unprintable characters escaped as in a Python literal.

    A key or a name of a file may hold a line break or another control character
    (``"a\nb" = 1`` is a valid TOML key): a message quoting it must stay one line
    (``\n``, ``\x1f``, ``\u2028`` instead of the characters themselves).
    """
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def shown(value: Any) -> str:
    """A value given from Python, for a one-line message: its type and its start."""
    return f"{type(value).__name__} {printable(repr(value))[:60]}"


def suggest(word: str, choices: Sequence[str]) -> str:
    """`` (did you mean 'x'?)`` with the closest choice, or nothing without choices.

    Compared without case (:meth:`str.casefold`; the first of choices equal but for
    case): values and keys are case sensitive and stay refused, but ``"AUTO"`` is
    nearest ``'auto'``, not ``'reference'`` (difflib's ratio, case sensitive, saw no
    letter in common with ``auto``).
    """
    if not choices:
        return ""
    folded: dict[str, str] = {}
    for c in choices:
        folded.setdefault(c.casefold(), c)
    best = difflib.get_close_matches(word.casefold(), list(folded), n=1, cutoff=0.0)
    return f" (did you mean '{folded[best[0]]}'?)" if best else ""


# --- the types of the fields -----------------------------------------------------------

def type_hints(cls: Any) -> dict[str, Any]:
    """The resolved annotations of a dataclass's fields."""
    return typing.get_type_hints(cls)


def key_field(cls: Any) -> str | None:
    """The field marked ``key`` (the name of a named collection's entry), or None."""
    for f in fields(cls):
        if f.metadata.get("key"):
            return f.name
    return None


def keyed_item(tp: Any) -> type | None:
    """The item class of a ``tuple[Item, ...]`` named collection, else None."""
    if typing.get_origin(tp) is tuple:
        args = typing.get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis and dataclasses.is_dataclass(args[0]) \
                and key_field(args[0]) is not None:
            return args[0]  # type: ignore[return-value]
    return None


def optional(tp: Any) -> Any:
    """``X`` for ``X | None`` (``X`` may be a union itself), else None."""
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if len(args) == 1:
            return args[0]
        if len(args) < len(typing.get_args(tp)):
            return typing.Union[tuple(args)]  # noqa: UP007  (built from a list)
    return None


def alternatives(tp: Any) -> tuple[Any, ...]:
    """The members of a union without None (``str | tuple[str, ...]``), else ()."""
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        return typing.get_args(tp)
    return ()


def type_name(tp: Any) -> str:
    """The TOML type of an annotation, as messages and the reference name it."""
    inner = optional(tp)
    if inner is not None:
        return type_name(inner)
    if tp is float:
        return "number"
    if tp is int:
        return "integer"
    if tp is bool:
        return "boolean"
    if tp is str:
        return "string"
    if typing.get_origin(tp) is Literal:
        return " | ".join(f'"{a}"' for a in typing.get_args(tp))
    if typing.get_origin(tp) is tuple:
        return f"array of {type_name(typing.get_args(tp)[0])}"
    if alternatives(tp):
        return " or ".join(type_name(a) for a in alternatives(tp))
    if dataclasses.is_dataclass(tp):
        return "table"
    return str(tp)


def describe(value: Any) -> str:
    """A TOML value as a message names it (``a table``, ``an array``, its repr)."""
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        return "an array"
    if isinstance(value, bool):
        return "true" if value else "false"  # as TOML writes it (Python's True misleads)
    return repr(value)


def schema_keys(cls: type, prefix: str = "") -> list[str]:
    """Every dotted key of the schema (``<name>`` for the entries of named tables)."""
    keys = []
    hints = type_hints(cls)
    for f in fields(cls):
        if f.metadata.get("key"):
            continue
        key = f"{prefix}.{f.name}" if prefix else f.name
        keys.append(key)
        item = keyed_item(hints[f.name])
        nested = optional(hints[f.name]) or hints[f.name]
        if item is not None:
            keys += schema_keys(item, f"{key}.<name>")
        elif dataclasses.is_dataclass(nested):
            keys += schema_keys(nested, key)  # type: ignore[arg-type]
    return keys


def to_toml(obj: Any) -> Any:
    """TOML-ready data of a dataclass (None fields left out)."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        key_name = key_field(type(obj))
        out: dict[str, Any] = {}
        for f in fields(obj):
            value = getattr(obj, f.name)
            if f.name == key_name or value is None:
                continue
            if keyed_item(type_hints(type(obj))[f.name]) is not None:
                out[f.name] = {item.name: to_toml(item) for item in value}
            else:
                out[f.name] = to_toml(value)
        return out
    if isinstance(obj, tuple):
        return [to_toml(v) for v in obj]
    return obj


def suggest_key(root: type, word: str, valid: Sequence[str]) -> str:
    """The closest key of the table, unless the key belongs to (or is near) another one.

    Args:
        root: The dataclass of a whole file (where the other keys are looked for).
        word: The unknown key.
        valid: The keys of the table it was given in.
    """
    # Without case, as suggest: "DT" is 'time.dt'.
    elsewhere = {k.rsplit(".", 1)[-1].casefold(): k for k in reversed(schema_keys(root))}
    word = word.casefold()
    if word in elsewhere:
        return f" (did you mean '{elsewhere[word]}'?)"
    if difflib.get_close_matches(word, [v.casefold() for v in valid], n=1, cutoff=0.6):
        return suggest(word, valid)
    near = difflib.get_close_matches(word, list(elsewhere), n=1, cutoff=0.8)
    if near:
        return f" (did you mean '{elsewhere[near[0]]}'?)"
    return suggest(word, valid)
