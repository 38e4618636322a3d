"""What a built model fixes: its parts' settings, refused in one line when reassigned.

A :class:`~breakwater.model.model.ContactModel` builds its forms, solvers' data and
outputs from the settings it is given (bodies' materials, contact pairs' penalty and
friction, loads). The settings are frozen dataclasses, but the parts holding them were
not: in a notebook, ``model.pairs[0].spec = dataclasses.replace(spec, friction=0.1)``
was taken without a word and changed nothing (measured: the run's numbers those of
μ = 0.65 to the last digit, and ``case.toml`` said 0.65), as would replacing an item of
``model.pairs``. Now each is refused with one line saying what to do instead
(:data:`REBUILD`): change the case and build it again. The damping and the gravity are
the model's settings that may change (``model.damping``, ``model.gravity``), and its
initial state (``model.initial``), checked against the model when set
(:class:`initial_setting`): before, an initial velocity of a body the model does not
have (``"Caisson"``) or a load index beyond ``model.loads`` was taken and ignored (the
run started at rest, its numbers those of no velocity). An attribute the model does not
have is refused when set (:class:`KnownAttributes`): ``model.dampng = Damping(...)`` was
taken and the run went on with the old damping; so is one it built from
(``model.degree = 1``, ``model.mesh = ...``): taken, and the run went on with the old.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, ClassVar, NoReturn, overload

import numpy as np

from breakwater.common.errors import CaseError
from breakwater.config.fields import suggest
from breakwater.config.runspec import InitialSpec

__all__ = ["REBUILD", "SETTABLE", "BuiltPart", "BuiltParts", "KnownAttributes", "built_parts",
           "check_initial", "gravity_value", "initial_setting"]

SETTABLE = "model.damping, model.gravity and model.initial may be set"
"""What a built model takes: its settings (the rest it was built from)."""

REBUILD = ("a built model's bodies, contact pairs and loads are fixed: change the case (e.g. "
           "load_case(None, ['contact.interface.friction=0.3'])), or what ContactModel is "
           f"given, and build it again ({SETTABLE})")
"""What to do instead of changing a part of a built model."""


def _refuse(what: str) -> NoReturn:
    raise AttributeError(f"cannot change {what}: {REBUILD}")


class BuiltPart:
    """A part the model built (a body's, a pair's, a load's data): fixed once set.

    The attributes of :attr:`FIXED` are set once (by the dataclass's ``__init__``);
    assigning one again is refused (``AttributeError``, one line); the others (a load's
    stage) stay the model's to change.
    """

    FIXED: ClassVar[frozenset[str]] = frozenset()
    #: How a user reaches the part (``model.pairs[k]``).
    WHERE: ClassVar[str] = "a part of the model"

    def __setattr__(self, name: str, value: Any) -> None:
        if name in self.FIXED and name in self.__dict__:
            _refuse(f"{self.WHERE}.{name}")
        object.__setattr__(self, name, value)

    def __delattr__(self, name: str) -> None:
        if name in self.FIXED:
            _refuse(f"{self.WHERE}.{name}")
        object.__delattr__(self, name)


class KnownAttributes:
    """A built model's attributes: only its settings may be set.

    A misspelt setting (``model.dampng = Damping(alpha=20.0)``, ``model.gravty = ...``)
    was a new attribute nothing read: the run went on with the old value; so was a new
    value of one the model was built from (``model.degree = 1``: the spaces, forms and
    conditions stayed quadratic). Once the model is built (``_built`` set, the last
    step of its ``__init__``), a public name that is neither the model's nor its
    class's is refused (``AttributeError``, one line, with the closest name), and so is
    the model's own public attribute (build it again instead); the class's settings
    (properties and checked descriptors: damping, gravity, initial) and private ``_x``
    names are set as before.
    """

    def __setattr__(self, name: str, value: Any) -> None:
        if name.startswith("_") or "_built" not in vars(self) or hasattr(type(self), name):
            object.__setattr__(self, name, value)
            return
        if name in vars(self):
            raise AttributeError(
                f"cannot change model.{name}: the built model's spaces, forms and conditions "
                f"were made from it; give ContactModel the new {name} (or change the case) "
                f"and build it again ({SETTABLE})")
        names = sorted(n for n in {*dir(type(self)), *vars(self)} if not n.startswith("_"))
        raise AttributeError(f"model.{name}: a built {type(self).__name__} has no attribute "
                             f"'{name}'{suggest(name, names)}, so setting it would change "
                             f"nothing ({SETTABLE})")


class BuiltParts[T](tuple[T, ...]):
    """The model's bodies, pairs or loads: a tuple whose changes are refused in one line.

    A list before: ``model.pairs[0] = ...`` was taken and ignored by what had been
    built from it.
    """

    where: str

    def __new__(cls, items: Iterable[T] = (), where: str = "the model's parts"
                ) -> BuiltParts[T]:
        """The items, refused to change; ``where`` names them in the refusal."""
        parts = super().__new__(cls, items)
        parts.where = where
        return parts

    def _changed(self, *_: Any, **__: Any) -> NoReturn:
        _refuse(self.where)

    __setitem__ = __delitem__ = __iadd__ = __imul__ = _changed
    append = extend = insert = pop = remove = clear = sort = reverse = _changed


class built_parts[T]:  # a descriptor, used like a property
    """A model's attribute holding its parts: set once, as a :class:`BuiltParts`."""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name, self.private = name, f"_{name}"

    @overload
    def __get__(self, obj: None, owner: type) -> built_parts[T]: ...

    @overload
    def __get__(self, obj: object, owner: type) -> BuiltParts[T]: ...

    def __get__(self, obj: object | None, owner: type) -> built_parts[T] | BuiltParts[T]:
        if obj is None:
            return self
        parts: BuiltParts[T] = getattr(obj, self.private)
        return parts

    def __set__(self, obj: object, items: Iterable[T]) -> None:
        if self.private in vars(obj):
            _refuse(f"model.{self.name}")
        setattr(obj, self.private, BuiltParts(items, f"model.{self.name}"))


def gravity_value(g: Any, gdim: int) -> np.ndarray:
    """A gravity set on a built model (a vector, or a ``fem.Constant``), checked.

    Raises:
        ValueError: Not ``gdim`` finite numbers (one line).
    """
    value = np.asarray(getattr(g, "value", g))
    if value.shape != (gdim,) or value.dtype.kind not in "fiu" \
            or not np.all(np.isfinite(value)):
        raise ValueError(f"gravity: expected {gdim} finite numbers (m/s²), got {g!r}")
    return value


def check_initial(spec: Any, bodies: list[str], gdim: int, loads: int) -> InitialSpec:
    """An initial state set on a built model (``model.initial``), checked against it.

    Args:
        spec: What was assigned.
        bodies: The model's body names.
        gdim: Its geometric dimension (the components of a velocity).
        loads: Its number of loads (``InitialSpec.loads`` holds their indices).

    Raises:
        TypeError: Not an :class:`~breakwater.config.runspec.InitialSpec`.
        CaseError: A velocity of a body the model does not have, of a body given twice
            or not of ``gdim`` components, or a load index not in ``model.loads``
            (one line naming the field).
    """
    if not isinstance(spec, InitialSpec):
        raise TypeError(f"initial: expected an InitialSpec, got {type(spec).__name__}")
    seen: set[str] = set()
    for body, vector in spec.velocities:
        if body not in bodies:
            raise CaseError(f"initial.velocities: no body named '{body}'"
                            f"{suggest(body, bodies)} (bodies: {', '.join(bodies)})")
        if body in seen:
            raise CaseError(f"initial.velocities: body '{body}' given twice")
        seen.add(body)
        if len(vector) != gdim:
            raise CaseError(f"initial.velocities: '{body}': expected {gdim} components "
                            f"(a {gdim}D model), got {list(vector)}")
    wrong = [k for k in spec.loads or () if not 0 <= k < loads]
    if wrong:
        raise CaseError(f"initial.loads: no load {wrong[0]} in model.loads ("
                        + (f"indices 0 to {loads - 1})" if loads else "the model has none)"))
    return spec


class initial_setting:  # a descriptor, used like a property
    """A model's ``initial``: an InitialSpec, checked by :func:`check_initial` when set."""

    def __set_name__(self, owner: type, name: str) -> None:
        self.private = f"_{name}"

    @overload
    def __get__(self, obj: None, owner: type) -> initial_setting: ...

    @overload
    def __get__(self, obj: object, owner: type) -> InitialSpec: ...

    def __get__(self, obj: object | None, owner: type) -> initial_setting | InitialSpec:
        if obj is None:
            return self
        spec: InitialSpec = getattr(obj, self.private)
        return spec

    def __set__(self, obj: Any, spec: InitialSpec) -> None:  # a ContactModel
        names = [b.spec.name for b in obj.bodies]
        setattr(obj, self.private, check_initial(spec, names, obj.gdim, len(obj.loads)))
