"""The compiled kernels' decorator (:func:`breakwater.common.jit.kernel`)."""

from __future__ import annotations

import logging
import subprocess
import sys
import time

import numba
import numpy as np
import pytest
from numba.core import caching

from breakwater.common import jit
from breakwater.common.jit import kernel, lock_path


def _sum_of_squares(x: np.ndarray) -> float:
    s = 0.0
    for v in x:
        s += v * v
    return s


SUM_OF_SQUARES = f"{_sum_of_squares.__module__}.{_sum_of_squares.__qualname__}"
"""The name of ``kernel(_sum_of_squares)``'s lock."""


def test_kernel_without_a_writable_cache(monkeypatch: pytest.MonkeyPatch) -> None:
    # Where numba finds no directory to cache in (a read-only install, no writable
    # home), njit(cache=True) raises at decoration; kernel() compiles without a cache.
    monkeypatch.setattr(caching.CacheImpl, "_locator_classes", [])
    with pytest.raises(RuntimeError, match="no locator"):
        numba.njit(cache=True)(_sum_of_squares)
    compiled = kernel(_sum_of_squares)
    assert type(compiled._cache).__name__ == "NullCache"
    assert compiled(np.arange(5.0)) == 30.0


@pytest.mark.serial
def test_kernel_without_a_cache_takes_no_lock(monkeypatch: pytest.MonkeyPatch) -> None:
    # Nothing cached, nothing to race on: it compiles while another process holds the
    # lock (3 s; the compilation alone takes well under a second).
    monkeypatch.setattr(caching.CacheImpl, "_locator_classes", [])
    compiled = kernel(_sum_of_squares)
    holder = subprocess.Popen([sys.executable, "-c", _HOLDER, "3", SUM_OF_SQUARES],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        start = time.perf_counter()
        assert compiled(np.arange(5.0)) == 30.0
        assert time.perf_counter() - start < 2.0
    finally:
        holder.wait(timeout=60)


def test_kernel_is_cached_where_it_can_be() -> None:
    compiled = kernel(_sum_of_squares)
    assert type(compiled._cache).__name__ == "FunctionCache"
    assert compiled(np.ones(3)) == 3.0


@kernel
def _inner(x: float) -> float:
    return 2.0 * x


@kernel
def _outer(x: np.ndarray) -> float:
    s = 0.0
    for v in x:
        s += _inner(v)
    return s


_HOLDER = """
import fcntl, sys, time
from breakwater.common.jit import lock_path
path = lock_path(sys.argv[2])
path.parent.mkdir(parents=True, exist_ok=True)
with open(path, "a") as f:
    fcntl.flock(f, fcntl.LOCK_EX)
    print("held", flush=True)
    time.sleep(float(sys.argv[1]))
"""


@pytest.mark.serial
def test_kernels_take_turns_to_compile(monkeypatch: pytest.MonkeyPatch,
                                       caplog: pytest.LogCaptureFixture) -> None:
    # numba's cache is not safe for processes compiling at once (numba #4807, #10128):
    # while another process holds the lock, a kernel's first call (its cache load or
    # compilation) waits for it. The holder keeps it 3 s; the call must wait at least
    # 2 s of them (the holder's start-up is not counted: it has printed "held"). Past
    # NOTICE_AFTER (here 0.5 s) of it, one line says the kernels are being compiled.
    monkeypatch.setattr(jit, "NOTICE_AFTER", 0.5)
    monkeypatch.setattr(jit, "_noticed", False)
    caplog.set_level(logging.INFO, logger="breakwater")
    holder = subprocess.Popen([sys.executable, "-c", _HOLDER, "3", SUM_OF_SQUARES],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        start = time.perf_counter()
        compiled = kernel(_sum_of_squares)
        assert compiled(np.arange(3.0)) == 5.0
        waited = time.perf_counter() - start
    finally:
        holder.wait(timeout=60)
    assert waited > 2.0
    notices = [r.getMessage() for r in caplog.records if r.name == "breakwater.common.jit"]
    assert len(notices) == 1 and "compiling breakwater's kernels" in notices[0]
    # Re-entrant: a kernel compiles the kernels it calls under the lock it holds.
    assert _outer(np.arange(4.0)) == 12.0
    assert lock_path(SUM_OF_SQUARES).exists()


@pytest.mark.serial
def test_a_kernel_does_not_wait_for_another_kernels_lock() -> None:
    # Each kernel has its own lock: while another process holds another kernel's (3 s),
    # this one's first call (a cache load or a compilation, well under 2 s) goes on.
    holder = subprocess.Popen([sys.executable, "-c", _HOLDER, "3", f"{__name__}._outer"],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        start = time.perf_counter()
        assert kernel(_sum_of_squares)(np.arange(5.0)) == 30.0
        assert time.perf_counter() - start < 2.0
    finally:
        holder.wait(timeout=60)


def test_the_kernels_calls_have_no_cycle() -> None:
    """The kernels' locks cannot deadlock while no kernel calls itself or, through
    others, a kernel that calls it (:mod:`breakwater.common.jit`): a process waits for a
    kernel's lock holding only the locks of the kernels it is compiled within, its
    callers. The graph of the calls between breakwater's kernels, by name (two kernels of
    the same name are one node: a cycle through them is reported too)."""
    import ast
    import pathlib

    import breakwater

    bodies: dict[str, list[ast.FunctionDef]] = {}
    for path in pathlib.Path(breakwater.__file__).parent.rglob("*.py"):
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, ast.FunctionDef) and any(
                    getattr(d, "id", getattr(d, "attr", None)) == "kernel"
                    for d in node.decorator_list):
                bodies.setdefault(node.name, []).append(node)
    calls = {name: {getattr(c.func, "id", getattr(c.func, "attr", None))
                    for node in nodes for c in ast.walk(node) if isinstance(c, ast.Call)}
             & bodies.keys() for name, nodes in bodies.items()}
    assert len(bodies) > 50 and sum(map(len, calls.values())) > 30  # the graph is read
    done: set[str] = set()

    def visit(name: str, path: tuple[str, ...]) -> None:
        assert name not in path, "a cycle of kernel calls: " + " -> ".join((*path, name))
        if name not in done:
            for callee in calls[name]:
                visit(callee, (*path, name))
            done.add(name)

    for name in bodies:
        visit(name, ())


@pytest.mark.serial
def test_a_kernel_compiles_again_when_a_kernel_it_calls_changes(tmp_path) -> None:
    """A kernel ``outer`` in ``b.py`` calls the kernel ``inner`` of ``a.py``; ``a.py`` is
    edited (``inner`` returns 2, not 1) and ``b.py`` is not: a new process runs the new
    ``inner``. numba's own stamp (``b.py``'s time and size) took the cached ``outer``
    with the old ``inner`` compiled into it (1); the digest of the package's sources in
    the stamp compiles it again (``kernel``'s ``_stamp_with_sources``)."""
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    inner = "from breakwater.common.jit import kernel\n\n@kernel\ndef inner():\n    return {}\n"
    (package / "a.py").write_text(inner.format(1))
    (package / "b.py").write_text(
        "from breakwater.common.jit import kernel\nfrom pkg.a import inner\n\n"
        "@kernel\ndef outer():\n    return inner()\n")
    env = {**__import__("os").environ, "PYTHONPATH": str(tmp_path),
           "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    run = [sys.executable, "-c", "import breakwater, pkg.b; print(pkg.b.outer())"]
    first = subprocess.run(run, env=env, capture_output=True, text=True, timeout=300)
    assert first.stdout.split() == ["1"], first.stderr
    (package / "a.py").write_text(inner.format(2))
    again = subprocess.run(run, env=env, capture_output=True, text=True, timeout=300)
    assert again.stdout.split() == ["2"], again.stderr
    assert list((tmp_path / "cache").rglob("*outer*.nbi"))  # cached, not uncached


def test_the_stamp_holds_the_sources_digest() -> None:
    """breakwater's kernels' cache indexes are stamped with the package's sources
    (numba's private ``_cache._cache_file._source_stamp``, 0.68: under a numba without
    it the stale-callee hazard of the test above would be back, and this test says so)."""
    from breakwater.contact import guardkernels

    stamp = guardkernels.land._cache._cache_file._source_stamp
    assert stamp[1] == jit.sources_digest("breakwater")
    assert len(stamp[1]) == 64
