"""The forms' JIT cache kept usable when a compilation is interrupted.

FFCx claims a form's module in the cache by creating its ``.c`` file, and marks it
compiled with a ``.c.cached`` file; a process that finds the ``.c`` file without the
mark waits for it (10 s), then fails. On an ``Exception`` FFCx renames the claim to
``.c.failed``; on a KeyboardInterrupt it leaves it. Measured: an interrupt while a case
was built for the first time (its forms compiled: tens of seconds) made every later
build of that case, in the same notebook and in any later process, fail after 10 s
with ``TimeoutError: JIT compilation timed out, probably due to a failed previous
compile``, until the file was removed by hand. :func:`install` makes an interrupted
compilation give its claims back as FFCx does on an error.
"""

from __future__ import annotations

import contextlib
import functools
import os
import pathlib
from collections.abc import Callable
from typing import Any

__all__ = ["install"]

_claimed: list[pathlib.Path] = []
"""The ``.c`` files this process has claimed and not yet compiled (in order)."""


def _claiming(get: Callable[..., Any]) -> Callable[..., Any]:
    """FFCx's ``get_cached_module``, noting a module this process claims to compile."""

    @functools.wraps(get)
    def claiming(*args: Any, **kwargs: Any) -> Any:
        found = get(*args, **kwargs)
        # FFCx 0.11's (module_name, object_names, cache_dir, timeout); another FFCx's
        # call passes through untouched.
        with contextlib.suppress(Exception):
            module_name = kwargs.get("module_name", args[0] if args else None)
            cache_dir = kwargs.get("cache_dir", args[2] if len(args) > 2 else None)
            if found[0] is None and isinstance(module_name, str) and cache_dir is not None:
                # The .c file was created here: this process compiles it.
                _claimed.append(pathlib.Path(cache_dir).joinpath(module_name)
                                .with_suffix(".c"))
        return found

    return claiming


def _releasing(compile_objects: Callable[..., Any]) -> Callable[..., Any]:
    """FFCx's ``compile_forms``/``compile_expressions``, its claims given back if cut short."""

    @functools.wraps(compile_objects)
    def releasing(*args: Any, **kwargs: Any) -> Any:
        mark = len(_claimed)
        try:
            return compile_objects(*args, **kwargs)
        except BaseException:  # (an Exception's claim is renamed by FFCx already)
            for claim in _claimed[mark:]:
                if not claim.with_suffix(".c.cached").exists():
                    with contextlib.suppress(OSError):
                        os.replace(claim, claim.with_suffix(".c.failed"))
            raise
        finally:
            del _claimed[mark:]

    return releasing


def install() -> None:
    """Wrap FFCx's JIT functions once per process (dolfinx calls them through the module)."""
    try:
        import ffcx.codegeneration.jit as jit
    except ImportError:  # another FFCx layout: its own behaviour
        return
    names = ("get_cached_module", "compile_forms", "compile_expressions")
    if getattr(jit, "_breakwater_releases_claims", False) or not all(
            callable(getattr(jit, n, None)) for n in names):
        return
    jit.get_cached_module = _claiming(jit.get_cached_module)
    jit.compile_forms = _releasing(jit.compile_forms)
    jit.compile_expressions = _releasing(jit.compile_expressions)
    jit._breakwater_releases_claims = True  # type: ignore[attr-defined]
