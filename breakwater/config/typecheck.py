"""The fields of a dataclass built from Python, checked against their annotations.

A case file's values are checked by :func:`breakwater.config.convert.convert` when the
file is read; a dataclass built (or changed with :func:`dataclasses.replace`) in Python
skips the reader. :func:`check_fields`, called first in a dataclass's
``__post_init__``, applies the same rules to its fields' Python values: a ``bool``
field takes ``True`` or ``False`` only (``adaptive="no"`` is refused, not a truthy
string), a ``float`` field a finite real number (``end_time="0.002"`` is refused),
``Literal`` fields one of their values, tuples their items' types, nested dataclasses
an instance. One line (:class:`~breakwater.config.fields.InvalidField`) names the field.

Python's own forms are accepted where they mean the same value: an ``int`` (or a NumPy
number) for a ``float`` field (stored as ``float``), a NumPy integer for an ``int``
field, a list or a NumPy array for a tuple (stored as a tuple), a ``str`` for a path.
"""

from __future__ import annotations

import dataclasses
import functools
import numbers
import os
import pathlib
import typing
from typing import Any

from breakwater.config.convert import convert
from breakwater.config.fields import (
    InvalidField,
    alternatives,
    describe,
    optional,
    type_hints,
    type_name,
)

__all__ = ["check_fields", "check_value"]


@functools.cache
def _hints(cls: Any) -> dict[str, Any]:
    return type_hints(cls)


def check_fields(obj: Any, error: type[Exception] | None = None, finite: bool = True
                 ) -> None:
    """Check every field of the dataclass ``obj`` against its annotation.

    Values of an equivalent Python form are stored in the annotated one (``1`` as
    ``1.0`` for a ``float``, a list as a tuple).

    Args:
        obj: The dataclass (in its ``__post_init__``).
        error: Raise this instead of :class:`InvalidField`, with the same message (a
            class whose own checks raise it, e.g. ``ValueError``).
        finite: Refuse NaN and infinite numbers, as the reader does (False: the types
            only, for a class that holds a NaN on purpose).

    Raises:
        InvalidField: A value of the wrong type, or a non-finite number (the field named
            relative to ``obj``, as its own checks name it).
    """
    hints = _hints(obj.__class__)
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        try:
            checked = check_value(hints[f.name], value, f.name, finite)
        except InvalidField as e:
            if error is None:
                raise
            raise error(str(e)) from None
        if checked is not value:
            object.__setattr__(obj, f.name, checked)  # frozen: in __post_init__ only


def check_value(tp: Any, value: Any, path: str, finite: bool = True) -> Any:
    """The Python ``value`` checked against the annotation ``tp`` (normalised).

    Raises:
        InvalidField: Naming ``path``.
    """
    inner = optional(tp)
    if inner is not None:
        return None if value is None else check_value(inner, value, path, finite)
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise InvalidField(path, f"expected a number, got {describe(value)}")
        try:
            number = float(value)
        except OverflowError:  # an int beyond the floats
            raise InvalidField(path, f"must be finite (got {value})") from None
        return convert(object, float, number, path) if finite else number
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise InvalidField(path, f"expected an integer, got {describe(value)}")
        return value if type(value) is int else int(value)
    if dataclasses.is_dataclass(tp):
        if not isinstance(value, tp):  # type: ignore[arg-type]
            raise InvalidField(path, f"expected a {getattr(tp, '__name__', tp)}, got "
                               f"{describe(value)}")
        return value
    if typing.get_origin(tp) is tuple:
        return _tuple(tp, value, path, finite)
    if alternatives(tp):
        for member in alternatives(tp):
            try:
                return check_value(member, value, path, finite)
            except InvalidField:
                continue
        raise InvalidField(path, f"expected a {type_name(tp)}, got {describe(value)}")
    if isinstance(tp, type) and issubclass(tp, pathlib.PurePath):
        if not isinstance(value, str | os.PathLike):
            raise InvalidField(path, f"expected a path, got {describe(value)}")
        return value if isinstance(value, tp) else tp(value)
    return convert(object, tp, value, path)  # bool, str, Literal: the reader's checks


def _tuple(tp: Any, value: Any, path: str, finite: bool) -> tuple[Any, ...]:
    if hasattr(value, "__array__") and hasattr(value, "tolist"):  # a NumPy array
        value = value.tolist()
    if not isinstance(value, tuple | list):
        raise InvalidField(path, f"expected a tuple ({type_name(tp)}), got {describe(value)}")
    args = typing.get_args(tp)
    if len(args) == 2 and args[1] is Ellipsis:
        items = (args[0],) * len(value)
    elif len(value) != len(args):
        raise InvalidField(path, f"expected {len(args)} items, got {len(value)}")
    else:
        items = args
    out = tuple(check_value(t, v, f"{path}[{i}]", finite)
                for i, (t, v) in enumerate(zip(items, value, strict=True)))
    if isinstance(value, tuple) and all(a is b for a, b in zip(out, value, strict=True)):
        return value  # unchanged: the same object
    return out
