"""TOML data to dataclasses: every value checked against its annotation, unknown keys refused.

:func:`build` makes a dataclass (and the dataclasses nested in it) from a TOML table:
``float``, ``int``, ``bool``, ``str``, ``Literal``, tuples, unions such as
``str | tuple[str, ...]``, optional and nested dataclasses, named collections
(:func:`~breakwater.config.fields.keyed_item`); an unknown key is refused with the
closest valid key. The dataclasses check their own values in ``__post_init__``
(:class:`~breakwater.config.fields.InvalidField`), prefixed here with the table's path.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
import typing
from dataclasses import MISSING, fields
from typing import Any, Literal

from breakwater.config.fields import (
    InvalidField,
    alternatives,
    describe,
    key_field,
    keyed_item,
    optional,
    suggest,
    suggest_key,
    type_hints,
    type_name,
)

__all__ = ["build", "convert"]


def build(root: type, cls: type, table: Any, path: str, key: str | None = None) -> Any:
    """Build a dataclass from a TOML table, rejecting unknown keys.

    Args:
        root: The dataclass of a whole file (an unknown key may belong elsewhere in it).
        cls: The dataclass of the table.
        table: The TOML table.
        path: Its dotted path from the root (for the messages).
        key: The entry's name, for an entry of a named collection.

    Raises:
        InvalidField: A key, a value or the dataclass's own checks, the path prefixed.
    """
    if not isinstance(table, dict):
        raise InvalidField(path, f"expected a table, got {describe(table)}")
    key_name = key_field(cls)
    valid = [f.name for f in fields(cls) if f.init and f.name != key_name]
    for k in table:
        if k not in valid:
            raise InvalidField(f"{path}.{k}" if path else k,
                               f"unknown key{suggest_key(root, k, valid)} (valid keys: "
                               f"{', '.join(valid)})")
    hints = type_hints(cls)
    kwargs: dict[str, Any] = {}
    for f in fields(cls):
        where = f"{path}.{f.name}" if path else f.name
        if f.name == key_name:
            kwargs[f.name] = key
        elif f.name in table:
            kwargs[f.name] = convert(root, hints[f.name], table[f.name], where)
        elif f.default is MISSING and f.default_factory is MISSING:
            raise InvalidField(where, "missing required key")
    try:
        return cls(**kwargs)
    except InvalidField as e:
        raise e.within(path) from None
    except ValueError as e:  # e.g. GodaGeometry's own checks
        raise InvalidField(path, str(e)) from None

def convert(root: type, tp: Any, value: Any, path: str) -> Any:
    """Check and convert one TOML value to the annotated type."""
    inner = optional(tp)
    if inner is not None:
        return convert(root, inner, value, path)
    want = type_name(tp)
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise InvalidField(path, f"expected a number, got {describe(value)}"
                               f"{_spelling(float, value)}")
        if not math.isfinite(value):
            raise InvalidField(path, f"must be finite (got {value})")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise InvalidField(path, f"expected an integer, got {describe(value)}"
                               f"{_spelling(int, value)}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise InvalidField(path, f"expected true or false, got {describe(value)}"
                               f"{_spelling(bool, value)}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise InvalidField(path, f"expected a string, got {describe(value)}"
                               f"{_spelling(str, value)}")
        return value
    if typing.get_origin(tp) is Literal:
        choices = [str(a) for a in typing.get_args(tp)]
        if value not in choices:
            hint = suggest(value, choices) if isinstance(value, str) else ""
            raise InvalidField(path, f"must be one of {want}, got {describe(value)}{hint}")
        return value
    item = keyed_item(tp)
    if item is not None:
        if not isinstance(value, dict):
            raise InvalidField(path, f"expected a table of named tables, got "
                               f"{describe(value)}")
        return tuple(build(root, item, v, f"{path}.{k}", key=k) for k, v in value.items())
    if typing.get_origin(tp) is tuple:
        if not isinstance(value, list):
            raise InvalidField(path, f"expected an array ({want}), got {describe(value)}")
        elem = typing.get_args(tp)[0]
        return tuple(convert(root, elem, v, f"{path}[{i}]") for i, v in enumerate(value))
    if dataclasses.is_dataclass(tp):
        return build(root, tp, value, path)  # type: ignore[arg-type]
    if alternatives(tp):  # an array: the array member; else the first that takes it
        arrays = [m for m in alternatives(tp) if typing.get_origin(m) is tuple]
        if isinstance(value, list) and arrays:
            return convert(root, arrays[0], value, path)
        for member in alternatives(tp):
            try:
                return convert(root, member, value, path)
            except InvalidField:
                continue
        raise InvalidField(path, f"expected a {want}, got {describe(value)}")
    raise TypeError(f"unsupported field type {tp!r}")  # pragma: no cover


def _spelling(tp: type, value: Any) -> str:
    """How to write ``value`` as a TOML ``tp``, when it reads as one: a hint, or ``""``.

    A number or a boolean quoted (a spreadsheet's ``"1e10"``), written as Python or a
    spreadsheet does (``.5``, ``5.``, ``True``, ``1`` for true), a whole float for an
    integer (``1e6``), or a number or boolean for a string (a name ``1e3``).
    """
    if tp is str:
        return " (quote it to give text)" if not isinstance(value, dict | list) else ""
    if tp is bool:
        if isinstance(value, str) and value.strip().lower() in ("true", "false"):
            return f" (write {value.strip().lower()}: lowercase, unquoted)"
        if isinstance(value, int | float) and value in (0, 1):
            return f" (write {'true' if value else 'false'})"
        return ""
    if isinstance(value, str):
        try:
            number = float(value.replace("_", ""))
        except ValueError:
            return ""
        if tp is int and number.is_integer() and abs(number) < 2**63:
            return f" (write {int(number)}, unquoted)"
        if tp is not float or not math.isfinite(number):
            return ""
        try:  # the text itself when TOML reads it (1e-4), else Python's spelling (.5)
            text = value.strip() if isinstance(tomllib.loads(f"v = {value}")["v"], float) \
                else repr(number)
        except tomllib.TOMLDecodeError:
            text = repr(number)
        return f" (write {text}, unquoted)"
    if tp is int and isinstance(value, float) and value.is_integer() and abs(value) < 2**63:
        return f" (write {int(value)}: an integer has no point or exponent)"
    return ""
