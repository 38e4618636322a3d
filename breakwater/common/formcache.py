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

A process killed while it compiles (SIGKILL: a batch system's time limit, the
out-of-memory killer) cannot give its claim back, and every later run of the case
failed the same way (measured). Each claim made here is recorded in an ``.c.owner``
file (host and process id); a claim found without its mark is taken over (renamed
``.c.failed``, as FFCx does on an error, and compiled again) where its owner is a
process of this host that no longer exists, or where none of its module's files has
changed for :data:`STALE_AGE` (a claim of another host or of another program).

A module this process has found compiled is given again from memory when a form asks
for it again (a case built twice, a study's cases, a notebook's reruns, each of the
~70 forms of a Goda case): FFCx looks it up anew each time, listing the whole cache
folder, 3.5 ms a time at 13 600 files, for the module the process loaded before (the
same module name is the same forms' code). Measured: the 3 ms Goda case built and run
a second time in a process 0.88 → 0.28 s; on 2 ranks, where dolfinx makes the ranks
look up one after the other, test_sweep's two studies of 4 cases 22 → 6 s.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import os
import pathlib
import socket
import time
from collections.abc import Callable
from typing import Any

__all__ = ["STALE_AGE", "install"]

log = logging.getLogger(__name__)

STALE_AGE = 600.0
"""Seconds without a change to any file of a claimed module after which its claim is a
dead process's, whoever made it (a form compiles in seconds to a minute here)."""

_loaded: dict[tuple[str, tuple[str, ...], str], Any] = {}
"""The modules found compiled by FFCx's lookup in this process: its answer, by module
name, object names and cache folder (a loaded extension module stays loaded)."""

_claimed: list[pathlib.Path] = []
"""The ``.c`` files this process has claimed and not yet compiled (in order)."""


def _owner() -> str:
    """The record of the running process in an ``.c.owner`` file: host and PID."""
    return f"{socket.gethostname()} {os.getpid()}"


def _dead_owner(claim: pathlib.Path) -> str | None:
    """Why ``claim`` (a ``.c`` file without its ``.c.cached`` mark) is a dead process's.

    None where it may be a live one's: its owner is alive, or on another host, or not
    recorded, and a file of its module changed within :data:`STALE_AGE`.
    """
    with contextlib.suppress(OSError, ValueError):
        host, pid = claim.with_suffix(".c.owner").read_text().split()
        if host == socket.gethostname():
            try:
                os.kill(int(pid), 0)
            except ProcessLookupError:
                return f"its process {pid} no longer exists"
            except PermissionError:
                pass  # another user's, alive
    try:
        changed = max(p.stat().st_mtime for p in claim.parent.glob(claim.stem + ".*"))
    except (OSError, ValueError):
        return None
    age = time.time() - changed
    return f"none of its files changed for {age:.0f} s" if age > STALE_AGE else None


def _claiming(get: Callable[..., Any]) -> Callable[..., Any]:
    """FFCx's ``get_cached_module``: a module found before given from memory.

    A dead process's claim is taken over, ours recorded.
    """

    @functools.wraps(get)
    def claiming(*args: Any, **kwargs: Any) -> Any:
        # FFCx 0.11's (module_name, object_names, cache_dir, timeout); another FFCx's
        # call passes through untouched.
        claim = key = None
        with contextlib.suppress(Exception):
            module_name = kwargs.get("module_name", args[0] if args else None)
            names = kwargs.get("object_names", args[1] if len(args) > 1 else ())
            cache_dir = kwargs.get("cache_dir", args[2] if len(args) > 2 else None)
            if isinstance(module_name, str) and cache_dir is not None:
                claim = pathlib.Path(cache_dir).joinpath(module_name).with_suffix(".c")
                key = (module_name, tuple(names), str(cache_dir))
        if key is not None and key in _loaded:
            return _loaded[key]
        if claim is not None and claim.exists() and not claim.with_suffix(".c.cached").exists():
            why = _dead_owner(claim)
            if why is not None:
                with contextlib.suppress(OSError):  # (another process may take it first)
                    os.replace(claim, claim.with_suffix(".c.failed"))
                    log.info("the JIT cache's %s was claimed by a compilation that did "
                             "not finish (%s): compiling it again", claim.name, why)
        found = get(*args, **kwargs)
        if key is not None and found[0] is not None:
            _loaded[key] = found
        if claim is not None and found[0] is None:
            # The .c file was created here: this process compiles it.
            _claimed.append(claim)
            with contextlib.suppress(OSError):
                claim.with_suffix(".c.owner").write_text(_owner())
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
            for claim in _claimed[mark:]:
                with contextlib.suppress(OSError):
                    claim.with_suffix(".c.owner").unlink()
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
