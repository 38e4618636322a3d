"""Frozen settings that say, when assigned, how to change them.

A frozen dataclass refuses an assignment with ``cannot assign to field 'dt'``: in a
notebook, ``time.dt = 5e-5`` or ``model.pairs[0].spec.friction = 0.3`` then left the
user to find out what to do instead. :func:`assignment_hint` keeps the refusal (the
same ``FrozenInstanceError``) and adds what to do.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, NoReturn

__all__ = ["assignment_hint"]


def assignment_hint[C: type](hint: str) -> Callable[[C], C]:
    """A class decorator (above ``@dataclass(frozen=True)``): refusals with ``hint``.

    Args:
        hint: What to do instead; ``{name}`` is the field assigned.
    """
    def decorate(cls: C) -> C:
        def refuse(self: Any, name: str, *_: Any) -> NoReturn:
            raise dataclasses.FrozenInstanceError(
                f"cannot assign to field {name!r} of {cls.__name__}: "
                + hint.format(name=name))

        cls.__setattr__ = refuse  # type: ignore[method-assign,assignment]
        cls.__delattr__ = refuse  # type: ignore[method-assign,assignment]
        return cls

    return decorate
