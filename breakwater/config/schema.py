"""The TOML form of typed settings: frozen dataclasses read from TOML files.

A :class:`Schema` reads a tree of frozen dataclasses (the root: a whole case,
:class:`breakwater.casefile.case.Case`) from TOML files:

- a field is declared with :func:`~breakwater.config.fields.setting`, which gives its
  unit and its meaning (:meth:`Schema.reference` prints them); ``tuple[Item, ...]`` of
  a dataclass with a ``key`` field is a *named collection*, a table of tables keyed by
  the item's name;
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

This module is the reading of a whole file (its ``extends`` chain, its path values,
the overrides, the origin of each key); the machinery lives beside it, one job each:
:mod:`~breakwater.config.fields` (declaring, checking and typing fields, TOML data of a
dataclass), :mod:`~breakwater.config.tomlfiles` (reading, merging, the origin of keys),
:mod:`~breakwater.config.convert` (TOML data to dataclasses),
:mod:`~breakwater.config.overrides` (``--set``) and :mod:`~breakwater.config.reference`
(the table of every key).
"""

from __future__ import annotations

import pathlib
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from breakwater.common.errors import CaseError
from breakwater.config import convert
from breakwater.config import reference as _reference
from breakwater.config.fields import InvalidField, describe, printable
from breakwater.config.overrides import OVERRIDE, apply_override, origin_of, path_key
from breakwater.config.tomlfiles import display, merge, origin, read_toml, record, resolved

RawCheck = Callable[[dict[str, Any], Callable[[str], str], Sequence[str]], None]
"""A check of the raw table: given it, where a dotted key was set and the labels in the
order they apply (see :meth:`Schema.load`)."""

__all__ = ["Schema"]


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
             check: Callable[[Any], None] | None = None,
             prepare: Callable[[dict[str, Any]], None] | None = None,
             check_raw: RawCheck | None = None
             ) -> Any:
        """Read ``file`` (and what it extends), apply the overrides, build the root.

        Args:
            file: The TOML file.
            overrides: ``key=value`` strings (dotted paths, TOML values).
            check: Further checks of the built object (raising :class:`InvalidField`
                with a path from the root).
            prepare: Changes the file's table (with what it extends) before the
                overrides (``calibrate``: a ``[time]`` it does not use, when none).
            check_raw: Checks of the table after the overrides, given it, where a
                dotted key was set (the file's label, or ``--set``; a key the file
                extends: that file's label) and the labels in the order they apply
                (the case extended first, the file, then ``--set``), raising
                :class:`InvalidField`.

        Raises:
            CaseError: One line naming the file (or ``--set``), the field and the problem
                (unprintable characters of keys and values escaped: :func:`printable`).

        """
        try:
            return self._load(file, overrides, check, prepare, check_raw)
        except CaseError as e:
            raise CaseError(printable(str(e))) from None

    def _load(self, file: pathlib.Path, overrides: Sequence[str],
              check: Callable[[Any], None] | None,
              prepare: Callable[[dict[str, Any]], None] | None,
              check_raw: RawCheck | None
              ) -> Any:
        origins: dict[str, str] = {}
        labels: list[str] = []
        raw = self._load_raw(file, (), origins, labels=labels)
        if prepare is not None:
            prepare(raw)
        merged: list[str] = []
        for spec in overrides:
            apply_override(self.root, self.paths, raw, spec, origins, merged)
        label = display(file)
        # Where overrides come from: --set first (blamed first), a study's file.
        given = [OVERRIDE, *dict.fromkeys(origin_of(s) for s in overrides)]

        def where_set(key: str) -> str:  # every override after every file
            found = origin(key, origins, label)
            return OVERRIDE if found in given else found

        try:
            if check_raw is not None:
                check_raw(raw, where_set, [*labels, OVERRIDE])
            obj = convert.build(self.root, self.root, raw, "")
            if check is not None:
                check(obj)
        except InvalidField as e:
            # The override of any field the problem involves is the one to blame (of an
            # involved table, any key in it: mesh.goda's sizes for the mesh's size).
            field, *others = e.fields()
            involved = {origin(f, origins, label) for f in e.fields()} | {
                o for f in others for k, o in origins.items() if k.startswith(f + ".")}
            where = next((w for w in given if w in involved),
                         origin(field, origins, label))
            if where not in (label, *given):  # a key of a file this one extends
                where = f"{label} (extends {where})"
            table = next((t for t in merged if e.field == t or e.field.startswith(t + ".")),
                         None)
            hint = "" if table is None else \
                f" ({OVERRIDE} merged a table into the case's {table}, whose other keys " \
                f"stay: {OVERRIDE} '{table}={{}}' first empties it)"
            raise CaseError(f"{where}: {e}{hint}") from None
        return obj

    # --- files and extends -----------------------------------------------------------------

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
                    node[last] = resolved(base, node[last], f"{label}: {at}{last}")

    def path_key(self, here: str) -> Collection[str] | None:
        """The names that are not paths, if the dotted key ``here`` is a path key."""
        return path_key(self.paths, here)

    def sources(self, file: pathlib.Path) -> list[pathlib.Path]:
        """The files that :meth:`load` reads for ``file``: itself and those it extends.

        Raises:
            CaseError: As :meth:`load`, when a file cannot be read.
        """
        read: list[pathlib.Path] = []
        self._load_raw(file, (), {}, read)
        return read

    def _load_raw(self, path: pathlib.Path, chain: tuple[pathlib.Path, ...],
                  origins: dict[str, str], read: list[pathlib.Path] | None = None,
                  labels: list[str] | None = None) -> dict[str, Any]:
        """The file's table merged over those it extends.

        ``origins``, ``read`` (the files, the file first) and ``labels`` (their labels,
        the case extended first) are filled in.
        """
        label = display(path)
        raw = read_toml(path)
        if read is not None:
            read.append(path.resolve())
        self._resolve_paths(raw, path.parent, label)
        if self.name_key is not None and self.name_key not in raw and not chain:
            raw[self.name_key] = path.stem
        base = raw.pop("extends", None)
        if base is None:
            record(raw, label, "", origins)
            if labels is not None:
                labels.append(label)
            return raw
        if not isinstance(base, str):
            raise CaseError(f"{label}: extends: expected a case name or file, got "
                            f"{describe(base)}")
        candidate = pathlib.Path(resolved(path.parent, base, f"{label}: extends"))
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
        merged = merge(self._load_raw(base_path, (*chain, path.resolve()), origins, read,
                                      labels), raw)
        record(raw, label, "", origins)
        if labels is not None:
            labels.append(label)
        return merged

    def reference(self) -> str:
        """A Markdown table of every key: type, unit, default, meaning.

        See :func:`breakwater.config.reference.reference`.
        """
        return _reference.reference(self.root)
