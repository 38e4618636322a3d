"""Compiled kernels: the fast step's per-iteration arithmetic in machine code (numba).

The fast GN22 step (:mod:`breakwater.stepping.condensed`) spends its time in small
loops over the interface's nodes and a few dense interface-sized matrices: in NumPy each
of them is a handful of calls whose overhead is larger than their arithmetic. They are
written as plain loops and compiled with numba's ``njit``, as the dolfinx demos compile
their custom kernels. :func:`kernel` is the one decorator: compiled once per machine
(``cache=True``: numba keeps the machine code beside the module, or in its user cache
directory where the package is read-only; where neither can be written, e.g. a read-only
install on a cluster node without a writable home, each process compiles them anew),
without fast-math (the kernels must give the
numbers of the NumPy and UFL references they are tested against, to round-off).

Processes that share a cache take turns to compile a kernel: numba's cache is not safe
when several processes compile the same function at once (numba issues #4807 and #10128:
two new signatures can be given the same data file, and the index then points one
signature at the other's machine code, a segmentation fault at its next load). Every rank
of an ``mpiexec`` run, or every run of a study on a fresh install, compiles the same
kernels at the same moment, so each compilation or cache load of a kernel holds that
kernel's file lock (:func:`cache_lock`, ``flock``; the kernel releases it if the process
is killed), and a kernel it calls, compiled within it, that one's too. A kernel's cache
files are its own (numba links the kernels it calls into its machine code), so processes
compile different kernels at once: two pytest processes on an empty cache, when one lock
held all the kernels, waited 152 s for it, 130 s of them while the other compiled
kernels they did not need (measured on five test files). Deadlock-free: a process takes a callee's
lock while it holds its caller's only, and the kernels' calls have no cycle (numba
compiles no mutual recursion without signatures), so no two processes can each hold a
lock that the other waits for.

A first run on a machine compiles them: half a minute for the conforming pair, a minute
or more for the general pairs' kernels. Where a compilation (or the wait for another
process's) lasts longer than :data:`NOTICE_AFTER`, one line says so on the
``breakwater`` logger, and where numba can cache nothing, how to let it.

numba keeps a kernel's machine code while the kernel's own source file is unchanged
(its modification time and size), not the files of the kernels it calls or of the
constants it reads, which are compiled into it: after a ``git pull`` that changed
``guardkernels.land`` but not ``friction3d.py``, an editable install would run the 3-D
slip guard with the old ``land`` (``tests/test_jit.py`` shows it on two small modules:
the caller kept the callee's old value). :func:`kernel` therefore adds a digest of its
package's Python sources to the stamp numba checks (:func:`sources_digest`): any change
to the package's sources compiles its kernels again.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib.util
import logging
import os
import pathlib
import threading
from collections.abc import Callable, Iterator
from typing import Any, cast

import numba

try:
    import fcntl
except ImportError:  # Windows: no flock; compilations go on unlocked
    fcntl = None  # type: ignore[assignment]

__all__ = ["NOTICE_AFTER", "cache_lock", "kernel", "lock_path", "sources_digest"]

NOTICE_AFTER = 3.0
"""Seconds of compilation after which the run says it is compiling (once per process)."""

_LOCK_FOLDER = "breakwater-numba-locks"
_held = threading.RLock()
_depth = 0
_handles: dict[str, list[Any]] = {}
"""This process's held kernel locks: name -> [open lock file, depth of its holds]."""
_timer: threading.Timer | None = None
_noticed = False
log = logging.getLogger("breakwater.common.jit")


def _notice(cached: bool) -> None:
    """Say once that the kernels are being compiled (a timer's call)."""
    global _noticed
    if _noticed:
        return
    _noticed = True
    if cached:
        log.info("compiling breakwater's kernels for this machine (once: numba keeps "
                    "them in its cache); this first run takes up to a few minutes longer")
    else:
        log.warning("compiling breakwater's kernels: numba finds no writable directory to "
                    "keep them in, so every run compiles them anew (a few minutes); set "
                    "NUMBA_CACHE_DIR to a writable directory")


def lock_path(name: str) -> pathlib.Path:
    """The file whose lock the compilations of the kernel ``name`` take turns on.

    In a folder of the kernels' locks: in ``NUMBA_CACHE_DIR`` where it is set; else
    beside the package's own cache (its ``__pycache__``) where that can be written; else
    in numba's user cache directory; else in the temporary directory.

    Args:
        name: The kernel's module and qualified name (``breakwater.contact.guardkernels.land``).
    """
    cache_dir = getattr(numba.config, "CACHE_DIR", "")  # NUMBA_CACHE_DIR
    if cache_dir:
        return pathlib.Path(cache_dir) / _LOCK_FOLDER / f"{name}.lock"
    beside = pathlib.Path(__file__).resolve().parents[1] / "__pycache__"
    if os.access(beside, os.W_OK) or (not beside.exists()
                                      and os.access(beside.parent, os.W_OK)):
        return beside / _LOCK_FOLDER / f"{name}.lock"
    from numba.misc.appdirs import AppDirs
    user = pathlib.Path(AppDirs(appname="numba", appauthor=False).user_cache_dir)
    with contextlib.suppress(OSError):
        user.mkdir(parents=True, exist_ok=True)
    if os.access(user, os.W_OK):
        return user / _LOCK_FOLDER / f"{name}.lock"
    import tempfile
    return pathlib.Path(tempfile.gettempdir()) / f"{_LOCK_FOLDER}.{os.getuid()}" / f"{name}.lock"


@contextlib.contextmanager
def cache_lock(name: str, cached: bool = True) -> Iterator[None]:
    """Hold the compilation lock of the kernel ``name`` (re-entrant in this process).

    A kernel compiles the kernels it calls within its own compilation: each takes its
    own lock there, the caller's still held. The process's threads compile one at a
    time (one lock of the process for all the kernels, as numba's own). Where numba
    keeps no cache (nothing to race on: the processes may compile at once), where the
    lock file cannot be opened, or on Windows (no ``flock``), the compilation goes on
    unlocked. Past :data:`NOTICE_AFTER` seconds in the outermost hold, the one line of
    :func:`_notice`.

    Args:
        name: The kernel's module and qualified name (its lock file's name).
        cached: Whether numba caches the kernel being compiled (the notice's words).
    """
    global _depth, _timer
    with _held:
        if _depth == 0 and not _noticed:
            _timer = threading.Timer(NOTICE_AFTER, _notice, (cached,))
            _timer.daemon = True
            _timer.start()
        held = _handles.get(name)
        if held is not None:  # this process holds it already (a kernel calling itself)
            held[1] += 1
        elif fcntl is not None and cached:  # (no cache: nothing to race on)
            try:
                path = lock_path(name)
                path.parent.mkdir(parents=True, exist_ok=True)
                handle = open(path, "a")  # held until this kernel's compilation ends
            except OSError:
                handle = None
            if handle is not None:
                try:
                    fcntl.flock(handle, fcntl.LOCK_EX)
                except OSError:  # a file system without locks: unlocked
                    handle.close()
                else:
                    held = _handles[name] = [handle, 1]
        _depth += 1
        try:
            yield
        finally:
            _depth -= 1
            if _depth == 0 and _timer is not None:
                _timer.cancel()
                _timer = None
            if held is not None:
                held[1] -= 1
                if held[1] == 0:
                    del _handles[name]
                    fcntl.flock(held[0], fcntl.LOCK_UN)
                    held[0].close()


@functools.cache
def sources_digest(package: str) -> str:
    """A digest of the Python sources of ``package`` (every ``.py`` below it), once a process.

    16 ms for breakwater's 166 files. An empty string where the package has no source
    folder (nothing to add to numba's stamp).
    """
    spec = importlib.util.find_spec(package)
    roots = list(spec.submodule_search_locations or []) if spec is not None else []
    digest = hashlib.sha256()
    for root in map(pathlib.Path, roots):
        for path in sorted(root.rglob("*.py")):
            digest.update(str(path.relative_to(root)).encode())
            digest.update(path.read_bytes())
    return digest.hexdigest() if roots else ""


def _stamp_with_sources(compiled: Any, package: str) -> None:
    """Add :func:`sources_digest` of ``package`` to the stamp numba checks for ``compiled``.

    numba's cache index holds the source stamp it was written with and is read only
    where the stamp is the same (``numba.core.caching.IndexDataCacheFile``); these are
    numba's private attributes (0.68), so a numba without them leaves its own stamp
    (``tests/test_jit.py`` checks that the digest is there).
    """
    index = getattr(getattr(compiled, "_cache", None), "_cache_file", None)
    digest = sources_digest(package)
    if index is not None and hasattr(index, "_source_stamp") and digest:
        index._source_stamp = (index._source_stamp, digest)


def kernel[F: Callable[..., Any]](function: F) -> F:
    """``numba.njit(cache=True)``: ``function`` compiled on its first call.

    Its compilations and cache loads hold its :func:`cache_lock`. Without a cache where
    numba finds no writable directory for it (it refuses ``cache=True`` then).
    """
    try:
        compiled = numba.njit(cache=True)(function)
        cached = True
    except RuntimeError:  # "cannot cache function ...: no locator available"
        compiled = numba.njit(function)
        cached = False
    _stamp_with_sources(compiled, function.__module__.partition(".")[0])
    unlocked = compiled.compile
    name = f"{function.__module__}.{function.__qualname__}"

    def compile(sig: Any) -> Any:
        with cache_lock(name, cached):
            return unlocked(sig)

    compiled.compile = compile  # type: ignore[method-assign]
    return cast(F, compiled)
