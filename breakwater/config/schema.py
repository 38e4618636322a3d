"""The TOML form of typed settings: frozen dataclasses read from (and written to) TOML.

A :class:`Schema` reads a tree of frozen dataclasses (the root: a whole case,
:class:`breakwater.casefile.case.Case`) from TOML files:

- a field is declared with :func:`setting`, which gives its unit and its meaning
  (:meth:`Schema.reference` prints them); ``tuple[Item, ...]`` of a dataclass with a
  ``key`` field is a *named collection*, a table of tables keyed by the item's name;
- every value is checked against its annotation (``float``, ``int``, ``bool``,
  ``str``, ``Literal``, tuples, unions such as ``str | tuple[str, ...]``, optional and
  nested dataclasses) and unknown keys are rejected with the closest valid key;
- ``extends = "<built-in name>"`` or ``"<file>"`` starts from another file, merged
  table by table; ``key=value`` overrides (``--set``) change any field by its dotted
  path (an entry of a named collection by its name or its index);
- the dataclasses check their own values in ``__post_init__`` and raise
  :class:`InvalidField` (the field relative to themselves): the schema prefixes the
  path of the table and names the file (or ``--set``) the offending key came from.

Every problem is a :class:`~breakwater.common.errors.CaseError`, one line.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import pathlib
import tomllib
import types
import typing
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import MISSING, dataclass, field, fields
from typing import Any, Literal

from breakwater.common.errors import CaseError
from breakwater.common.files import path_problem

__all__ = ["INTEGER_RANGE", "OUT_OF_RANGE", "OVERRIDE", "InvalidField", "Schema",
           "out_of_range", "positive", "printable", "setting", "suggest", "to_toml"]

OVERRIDE = "--set"
"""Origin of a value given as a ``key=value`` override."""


class InvalidField(CaseError):
    """A field's value is invalid; ``field`` is relative to the object that raised."""

    def __init__(self, field_path: str, problem: str) -> None:
        super().__init__(f"{field_path}: {problem}" if field_path else problem)
        self.field = field_path
        self.problem = problem

    def __reduce__(self) -> tuple[Any, ...]:
        return type(self), (self.field, self.problem)

    def within(self, prefix: str) -> InvalidField:
        """The same error with the field path prefixed."""
        path = ".".join(p for p in (prefix, self.field) if p)
        return InvalidField(path, self.problem)


def setting(default: Any = MISSING, *, unit: str = "-", doc: str = "", key: bool = False
            ) -> Any:
    """A dataclass field documented with its unit (and marked as the key of a table)."""
    return field(default=default, metadata={"unit": unit, "doc": doc, "key": key})


def positive(value: float, name: str, strict: bool = True) -> None:
    """Raise :class:`InvalidField` unless ``value`` > 0 (``strict``) or >= 0."""
    if not (value > 0 if strict else value >= 0):
        raise InvalidField(name, f"must be {'>' if strict else '>='} 0 (got {value:g})")


def printable(text: str) -> str:
    r"""``text`` with its unprintable characters escaped as in a Python literal.

    A key or a name of a file may hold a line break or another control character
    (``"a\nb" = 1`` is a valid TOML key): a message quoting it must stay one line
    (``\n``, ``\x1f``, ``\u2028`` instead of the characters themselves).
    """
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def suggest(word: str, choices: Sequence[str]) -> str:
    """`` (did you mean 'x'?)`` with the closest choice, or nothing without choices."""
    if not choices:
        return ""
    best = difflib.get_close_matches(word, choices, n=1, cutoff=0.0)
    return f" (did you mean '{best[0]}'?)" if best else ""


# --- the types of the fields -----------------------------------------------------------

def _hints(cls: Any) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _key_field(cls: Any) -> str | None:
    for f in fields(cls):
        if f.metadata.get("key"):
            return f.name
    return None


def _keyed_item(tp: Any) -> type | None:
    """The item class of a ``tuple[Item, ...]`` named collection, else None."""
    if typing.get_origin(tp) is tuple:
        args = typing.get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis and dataclasses.is_dataclass(args[0]) \
                and _key_field(args[0]) is not None:
            return args[0]  # type: ignore[return-value]
    return None


def _optional(tp: Any) -> Any:
    """``X`` for ``X | None`` (``X`` may be a union itself), else None."""
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if len(args) == 1:
            return args[0]
        if len(args) < len(typing.get_args(tp)):
            return typing.Union[tuple(args)]  # noqa: UP007  (built from a list)
    return None


def _alternatives(tp: Any) -> tuple[Any, ...]:
    """The members of a union without None (``str | tuple[str, ...]``), else ()."""
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        return typing.get_args(tp)
    return ()


def _type_name(tp: Any) -> str:
    inner = _optional(tp)
    if inner is not None:
        return _type_name(inner)
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
        return f"array of {_type_name(typing.get_args(tp)[0])}"
    if _alternatives(tp):
        return " or ".join(_type_name(a) for a in _alternatives(tp))
    if dataclasses.is_dataclass(tp):
        return "table"
    return str(tp)


def _describe(value: Any) -> str:
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        return "an array"
    return repr(value)


def schema_keys(cls: type, prefix: str = "") -> list[str]:
    """Every dotted key of the schema (``<name>`` for the entries of named tables)."""
    keys = []
    hints = _hints(cls)
    for f in fields(cls):
        if f.metadata.get("key"):
            continue
        key = f"{prefix}.{f.name}" if prefix else f.name
        keys.append(key)
        item = _keyed_item(hints[f.name])
        nested = _optional(hints[f.name]) or hints[f.name]
        if item is not None:
            keys += schema_keys(item, f"{key}.<name>")
        elif dataclasses.is_dataclass(nested):
            keys += schema_keys(nested, key)  # type: ignore[arg-type]
    return keys


def to_toml(obj: Any) -> Any:
    """TOML-ready data of a dataclass (None fields left out)."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        key_name = _key_field(type(obj))
        out: dict[str, Any] = {}
        for f in fields(obj):
            value = getattr(obj, f.name)
            if f.name == key_name or value is None:
                continue
            if _keyed_item(_hints(type(obj))[f.name]) is not None:
                out[f.name] = {item.name: to_toml(item) for item in value}
            else:
                out[f.name] = to_toml(value)
        return out
    if isinstance(obj, tuple):
        return [to_toml(v) for v in obj]
    return obj


# --- files ----------------------------------------------------------------------------

def display(path: pathlib.Path) -> str:
    """A path as the messages name it: relative to the working directory if inside."""
    try:
        return str(path.resolve().relative_to(pathlib.Path.cwd()))
    except ValueError:
        return str(path)


def _read_toml(path: pathlib.Path) -> dict[str, Any]:
    try:
        raw = path.read_bytes()
        data = tomllib.loads(raw.decode("utf-8"))
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


def _record(data: Any, label: str, prefix: str, origins: dict[str, str]) -> None:
    """Note the file every key (and table) comes from."""
    if isinstance(data, dict):
        for k, v in data.items():
            p = f"{prefix}.{k}" if prefix else k
            origins[p] = label
            _record(v, label, p, origins)


def _resolved(folder: pathlib.Path, text: str, where: str) -> str:
    """The absolute path of ``text`` (relative to ``folder``), or a CaseError at ``where``."""
    problem = path_problem(text)
    if problem is None:
        try:
            return str((folder / text).resolve())
        except (OSError, ValueError) as e:  # the folder and the path together too long
            problem = e.strerror if isinstance(e, OSError) and e.strerror else str(e)
    raise CaseError(f"{where}: {problem}")


def _merge(base: dict[str, Any], top: Mapping[str, Any]) -> dict[str, Any]:
    """``top`` merged over ``base``, table by table."""
    out = dict(base)
    for k, v in top.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = _merge(out[k], v)
        else:
            out[k] = v
    return out


def _origin(path: str, origins: Mapping[str, str], default: str) -> str:
    parts = path.replace("[", ".[").split(".")
    for n in range(len(parts), 0, -1):
        p = ".".join(parts[:n]).replace(".[", "[")
        if p in origins:
            return origins[p]
    return default


def _parse_value(text: str) -> Any:
    """A TOML value, or the bare text as a string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text.strip()


# --- the schema -------------------------------------------------------------------------

@dataclass(frozen=True)
class Schema:
    """How a tree of dataclasses is read from TOML files.

    Attributes:
        root: The dataclass of a whole file.
        builtin: The file of a built-in name (``extends = "<name>"``); raises
            :class:`~breakwater.common.errors.CaseError` for an unknown name.
        paths: Dotted keys whose string values are file paths, resolved against the
            file that gives them (the working directory for overrides), with the
            values that are names rather than paths (e.g. ``{"mesh.source": ("goda",)}``).
        name_key: Key set to the file's stem when the file (not one it extends)
            leaves it out.

    """

    root: type
    builtin: Callable[[str], pathlib.Path]
    paths: Mapping[str, Collection[str]] = field(default_factory=dict)
    name_key: str | None = "name"

    def load(self, file: pathlib.Path, overrides: Sequence[str] = (),
             check: Callable[[Any], None] | None = None) -> Any:
        """Read ``file`` (and what it extends), apply the overrides, build the root.

        Args:
            file: The TOML file.
            overrides: ``key=value`` strings (dotted paths, TOML values).
            check: Further checks of the built object (raising :class:`InvalidField`
                with a path from the root).

        Raises:
            CaseError: One line naming the file (or ``--set``), the field and the problem
                (unprintable characters of keys and values escaped: :func:`printable`).

        """
        try:
            return self._load(file, overrides, check)
        except CaseError as e:
            raise CaseError(printable(str(e))) from None

    def _load(self, file: pathlib.Path, overrides: Sequence[str],
              check: Callable[[Any], None] | None) -> Any:
        origins: dict[str, str] = {}
        raw = self._load_raw(file, (), origins)
        for spec in overrides:
            self._apply_override(raw, spec, origins)
        label = display(file)
        try:
            obj = self.build(self.root, raw, "")
            if check is not None:
                check(obj)
        except InvalidField as e:
            origin = _origin(e.field, origins, label)
            if origin not in (label, OVERRIDE):  # a key of a file this one extends
                origin = f"{label} (extends {origin})"
            raise CaseError(f"{origin}: {e}") from None
        return obj

    # --- TOML data to dataclasses ------------------------------------------------------

    def build(self, cls: type, table: Any, path: str, key: str | None = None) -> Any:
        """Build a dataclass from a TOML table, rejecting unknown keys."""
        if not isinstance(table, dict):
            raise InvalidField(path, f"expected a table, got {_describe(table)}")
        key_name = _key_field(cls)
        valid = [f.name for f in fields(cls) if f.init and f.name != key_name]
        for k in table:
            if k not in valid:
                raise InvalidField(f"{path}.{k}" if path else k,
                                   f"unknown key{self.suggest_key(k, valid)} (valid keys: "
                                   f"{', '.join(valid)})")
        hints = _hints(cls)
        kwargs: dict[str, Any] = {}
        for f in fields(cls):
            where = f"{path}.{f.name}" if path else f.name
            if f.name == key_name:
                kwargs[f.name] = key
            elif f.name in table:
                kwargs[f.name] = self._convert(hints[f.name], table[f.name], where)
            elif f.default is MISSING and f.default_factory is MISSING:
                raise InvalidField(where, "missing required key")
        try:
            return cls(**kwargs)
        except InvalidField as e:
            raise e.within(path) from None
        except ValueError as e:  # e.g. GodaGeometry's own checks
            raise InvalidField(path, str(e)) from None

    def _convert(self, tp: Any, value: Any, path: str) -> Any:
        """Check and convert one TOML value to the annotated type."""
        inner = _optional(tp)
        if inner is not None:
            return self._convert(inner, value, path)
        want = _type_name(tp)
        if tp is float:
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise InvalidField(path, f"expected a number, got {_describe(value)}")
            if not math.isfinite(value):
                raise InvalidField(path, f"must be finite (got {value})")
            return float(value)
        if tp is int:
            if isinstance(value, bool) or not isinstance(value, int):
                raise InvalidField(path, f"expected an integer, got {_describe(value)}")
            return value
        if tp is bool:
            if not isinstance(value, bool):
                raise InvalidField(path, f"expected true or false, got {_describe(value)}")
            return value
        if tp is str:
            if not isinstance(value, str):
                raise InvalidField(path, f"expected a string, got {_describe(value)}")
            return value
        if typing.get_origin(tp) is Literal:
            choices = [str(a) for a in typing.get_args(tp)]
            if value not in choices:
                hint = suggest(value, choices) if isinstance(value, str) else ""
                raise InvalidField(path, f"must be one of {want}, got {_describe(value)}{hint}")
            return value
        item = _keyed_item(tp)
        if item is not None:
            if not isinstance(value, dict):
                raise InvalidField(path, f"expected a table of named tables, got "
                                   f"{_describe(value)}")
            return tuple(self.build(item, v, f"{path}.{k}", key=k) for k, v in value.items())
        if typing.get_origin(tp) is tuple:
            if not isinstance(value, list):
                raise InvalidField(path, f"expected an array ({want}), got {_describe(value)}")
            elem = typing.get_args(tp)[0]
            return tuple(self._convert(elem, v, f"{path}[{i}]") for i, v in enumerate(value))
        if dataclasses.is_dataclass(tp):
            return self.build(tp, value, path)  # type: ignore[arg-type]
        if _alternatives(tp):  # an array: the array member; else the first that takes it
            arrays = [m for m in _alternatives(tp) if typing.get_origin(m) is tuple]
            if isinstance(value, list) and arrays:
                return self._convert(arrays[0], value, path)
            for member in _alternatives(tp):
                try:
                    return self._convert(member, value, path)
                except InvalidField:
                    continue
            raise InvalidField(path, f"expected a {want}, got {_describe(value)}")
        raise TypeError(f"unsupported field type {tp!r}")  # pragma: no cover

    def suggest_key(self, word: str, valid: Sequence[str]) -> str:
        """The closest key of the table, unless the key belongs to (or is near) another one."""
        elsewhere = {k.rsplit(".", 1)[-1]: k for k in reversed(schema_keys(self.root))}
        if word in elsewhere:
            return f" (did you mean '{elsewhere[word]}'?)"
        if difflib.get_close_matches(word, valid, n=1, cutoff=0.6):
            return suggest(word, valid)
        near = difflib.get_close_matches(word, list(elsewhere), n=1, cutoff=0.8)
        if near:
            return f" (did you mean '{elsewhere[near[0]]}'?)"
        return suggest(word, valid)

    # --- files, extends and overrides ------------------------------------------------------

    def _resolve_paths(self, raw: dict[str, Any], base: pathlib.Path, label: str) -> None:
        """Resolve the path values of a file's data against the file's folder.

        A ``*`` in a path key stands for every entry of a table (``loads.*.table.file``).

        Raises:
            CaseError: A path that can name no file (:func:`~breakwater.common.files.path_problem`),
                naming the file ``label`` and the key.
        """
        for key, names in self.paths.items():
            *tables, last = key.split(".")
            nodes: list[tuple[str, Any]] = [("", raw)]
            for part in tables:
                nodes = [(f"{at}{k}.", n[k]) for at, n in nodes if isinstance(n, dict)
                         for k in ([part] if part != "*" else list(n)) if k in n]
            for at, node in nodes:
                if isinstance(node, dict) and isinstance(node.get(last), str) \
                        and node[last] not in names:
                    node[last] = _resolved(base, node[last], f"{label}: {at}{last}")

    def _path_key(self, here: str) -> Collection[str] | None:
        """The names that are not paths, if the dotted key ``here`` is a path key."""
        parts = here.split(".")
        for key, names in self.paths.items():
            pattern = key.split(".")
            if len(pattern) == len(parts) and all(p in ("*", q)
                                                  for p, q in zip(pattern, parts, strict=True)):
                return names
        return None

    def sources(self, file: pathlib.Path) -> list[pathlib.Path]:
        """The files that :meth:`load` reads for ``file``: itself and those it extends.

        Raises:
            CaseError: As :meth:`load`, when a file cannot be read.
        """
        read: list[pathlib.Path] = []
        self._load_raw(file, (), {}, read)
        return read

    def _load_raw(self, path: pathlib.Path, chain: tuple[pathlib.Path, ...],
                  origins: dict[str, str], read: list[pathlib.Path] | None = None
                  ) -> dict[str, Any]:
        label = display(path)
        raw = _read_toml(path)
        if read is not None:
            read.append(path.resolve())
        self._resolve_paths(raw, path.parent, label)
        if self.name_key is not None and self.name_key not in raw and not chain:
            raw[self.name_key] = path.stem
        base = raw.pop("extends", None)
        if base is None:
            _record(raw, label, "", origins)
            return raw
        if not isinstance(base, str):
            raise CaseError(f"{label}: extends: expected a case name or file, got "
                            f"{_describe(base)}")
        candidate = pathlib.Path(_resolved(path.parent, base, f"{label}: extends"))
        if candidate.is_file():
            base_path = candidate
        elif "/" not in base and not base.endswith(".toml"):
            try:
                base_path = self.builtin(base)
            except CaseError as e:
                raise CaseError(f"{label}: extends: {e}") from None
        else:
            raise CaseError(f"{label}: extends: case file not found: {base}")
        if base_path in chain or base_path == path.resolve():
            raise CaseError(f"{label}: extends: circular ({base})")
        merged = _merge(self._load_raw(base_path, (*chain, path.resolve()), origins, read),
                        raw)
        _record(raw, label, "", origins)
        return merged

    def _apply_override(self, raw: dict[str, Any], spec: str, origins: dict[str, str]
                        ) -> None:
        """Apply one ``key=value`` override to the raw data, checking the key path."""
        if "=" not in spec:
            raise CaseError(f"{OVERRIDE} {spec}: expected key=value")
        key, text = (s.strip() for s in spec.split("=", 1))
        parts = key.split(".")
        if not key or not all(parts):
            raise CaseError(f"{OVERRIDE} {spec}: empty key")
        value = _parse_value(text)
        if out_of_range(value) is not None:
            raise CaseError(f"{OVERRIDE} {key}: {OUT_OF_RANGE}")
        cls: Any = self.root
        node = raw
        done: list[str] = []
        i = 0
        while i < len(parts):
            part = parts[i]
            here = ".".join([*done, part])
            if not (dataclasses.is_dataclass(cls)):
                raise CaseError(f"{OVERRIDE} {key}: '{'.'.join(done)}' is not a table")
            key_name = _key_field(cls)
            valid = [f.name for f in fields(cls) if f.init and f.name != key_name]
            if part not in valid:
                raise CaseError(f"{OVERRIDE} {key}: unknown key '{here}'"
                                f"{self.suggest_key(part, valid)} "
                                f"(valid keys: {', '.join(valid)})")
            tp = _hints(cls)[part]
            item = _keyed_item(tp)
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
            target = _optional(tp) or tp
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
        not_paths = self._path_key(here)
        if not_paths is not None and isinstance(value, str) and value not in not_paths:
            value = _resolved(pathlib.Path(), value, f"{OVERRIDE} {key}")
        node[part] = value
        for p in [p for p in origins if p == here or p.startswith(here + ".")]:
            del origins[p]
        origins[here] = OVERRIDE
        _record(value, OVERRIDE, here, origins)

    # --- the reference ----------------------------------------------------------------------

    def reference(self) -> str:
        """A Markdown table of every key: type, unit, default, meaning.

        A nested dataclass whose fields carry no :func:`setting` metadata (e.g.
        :class:`~breakwater.meshes.GodaGeometry`) takes its meanings from the
        ``Attributes:`` of its docstring and its unit from the field holding it
        (unless a field's metadata gives its own).
        """
        rows = ["| key | type | unit | default | meaning |", "|---|---|---|---|---|",
                '| `extends` | string | - | — | start from another case: a built-in name '
                '("goda") or a file (relative to this one); this file is merged over it, '
                'table by table |']
        self._walk(self.root, "", rows, None)
        return "\n".join(rows)

    def _walk(self, cls: Any, prefix: str, rows: list[str], unit_of_table: str | None
              ) -> None:
        hints = _hints(cls)
        docs = _attribute_docs(cls) if unit_of_table is not None else {}
        for f in fields(cls):
            tp = hints[f.name]
            key = f"{prefix}.{f.name}" if prefix else f.name
            if f.metadata.get("key"):
                continue
            item = _keyed_item(tp)
            nested = _optional(tp) or tp
            unit = f.metadata.get("unit", unit_of_table or "-")
            doc = f.metadata.get("doc", docs.get(f.name, ""))
            if item is not None:
                key_doc = next(g.metadata["doc"] for g in fields(item) if g.metadata["key"])
                rows.append(f"| `[{key}.<name>]` | table | | | {doc}; `<name>`: {key_doc} |")
                self._walk(item, f"{key}.<name>", rows, None)
            elif dataclasses.is_dataclass(nested):
                rows.append(f"| `[{key}]` | table | | | {doc} |")
                documented = any("doc" in g.metadata for g in fields(nested))
                self._walk(nested, key, rows, None if documented else unit)
            else:
                kind = _type_name(tp).replace("|", "\\|")
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
