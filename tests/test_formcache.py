"""A form compilation cut short by an interrupt leaves the JIT cache usable.

FFCx claims a module by creating its ``.c`` file and renames the claim on an error,
not on a KeyboardInterrupt: the interrupted form's next compilation, in the same
notebook or any later process, waited for the claim and failed after the JIT timeout
(``TimeoutError: JIT compilation timed out, probably due to a failed previous
compile``). Each rank compiles in its own cache, on its own mesh (no collective).
"""

from __future__ import annotations

import pathlib

import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
import ffcx.codegeneration.jit as ffcx_jit
import ufl
from dolfinx import fem, mesh

from breakwater.common import formcache


def _compile(cache: pathlib.Path, coefficient: float) -> fem.Form:
    msh = mesh.create_unit_square(MPI.COMM_SELF, 2, 2)
    V = fem.functionspace(msh, ("Lagrange", 1))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    return fem.form(coefficient * u * v * ufl.dx,
                    jit_options={"cache_dir": str(cache), "timeout": 1})


def test_an_interrupted_compilation_gives_its_claim_back(tmp_path: pathlib.Path,
                                                         monkeypatch: pytest.MonkeyPatch
                                                         ) -> None:
    formcache.install()
    cache = tmp_path / f"cache{MPI.COMM_WORLD.rank}"

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt  # in the C compiler's subprocess, as measured

    with monkeypatch.context() as mp:
        mp.setattr(ffcx_jit, "_compile_objects", interrupted)
        with pytest.raises(KeyboardInterrupt):
            _compile(cache, 2.0)
    left = [p.name for p in cache.glob("*.c") if not p.with_suffix(".c.cached").exists()]
    assert left == []  # no claim left for the next one to wait on
    form = _compile(cache, 2.0)  # the same form compiles (was: TimeoutError after 1 s)
    assert form.rank == 2
    formcache.install()  # once per process: not wrapped twice
    assert ffcx_jit.compile_forms.__wrapped__.__module__ == "ffcx.codegeneration.jit"


_KILLED = """
import os, signal, sys
import breakwater  # noqa: F401
import ffcx.codegeneration.jit as ffcx_jit
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI
from breakwater.common import formcache
formcache.install()
ffcx_jit._compile_objects = lambda *a, **k: os.kill(os.getpid(), signal.SIGKILL)
msh = mesh.create_unit_square(MPI.COMM_SELF, 2, 2)
V = fem.functionspace(msh, ("Lagrange", 1))
u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
fem.form(3.0 * u * v * ufl.dx, jit_options={"cache_dir": sys.argv[1], "timeout": 1})
"""


@pytest.mark.serial
def test_a_killed_compilation_is_compiled_again(tmp_path: pathlib.Path) -> None:
    # A process killed while it compiles (SIGKILL: a batch system's time limit, the
    # out-of-memory killer) leaves its claim: the next compilation of the form waited
    # for it and failed after the timeout, in every later run, until removed by hand.
    import subprocess
    import sys

    formcache.install()
    cache = tmp_path / "cache"
    child = subprocess.run([sys.executable, "-c", _KILLED, str(cache)], capture_output=True,
                           text=True, timeout=300, check=False)
    assert child.returncode == -9, child.stderr
    claims = [p for p in cache.glob("*.c") if not p.with_suffix(".c.cached").exists()]
    assert len(claims) == 1 and claims[0].with_suffix(".c.owner").exists()
    form = _compile(cache, 3.0)  # was: TimeoutError after the 1 s timeout
    assert form.rank == 2
    assert claims[0].with_suffix(".c.cached").exists()
    assert not claims[0].with_suffix(".c.owner").exists()  # removed once compiled


def _module_of(tmp: pathlib.Path, coefficient: float) -> str:
    """The JIT module name of :func:`_compile`'s form (compiled in a scratch cache)."""
    _compile(tmp / "scratch", coefficient)
    (name,) = [p.stem for p in (tmp / "scratch").glob("*.c")]
    return name


def _claimed(tmp_path: pathlib.Path, coefficient: float) -> tuple[pathlib.Path, pathlib.Path]:
    """This rank's folder and a claim of :func:`_compile`'s form in its ``cache`` (no mark)."""
    formcache.install()
    tmp = tmp_path / f"rank{MPI.COMM_WORLD.rank}"
    claim = (tmp / "cache" / _module_of(tmp, coefficient)).with_suffix(".c")
    claim.parent.mkdir()
    claim.touch()
    return tmp, claim


def test_a_live_claim_is_waited_for(tmp_path: pathlib.Path) -> None:
    # The claim of a process that is alive (this one) is not taken over: FFCx waits
    # for it and times out, as without breakwater.
    import os
    import socket

    tmp, claim = _claimed(tmp_path, 4.0)
    claim.with_suffix(".c.owner").write_text(f"{socket.gethostname()} {os.getpid()}")
    with pytest.raises(TimeoutError):
        _compile(tmp / "cache", 4.0)
    assert claim.exists()


def test_an_old_claim_of_no_known_owner_is_compiled_again(tmp_path: pathlib.Path) -> None:
    # Another host's or another program's claim (no owner recorded): taken over once
    # none of its module's files changed for formcache.STALE_AGE, waited for before.
    import os
    import time

    tmp, claim = _claimed(tmp_path, 5.0)
    with pytest.raises(TimeoutError):  # fresh: it may be compiling
        _compile(tmp / "cache", 5.0)
    old = time.time() - formcache.STALE_AGE - 60.0
    os.utime(claim, (old, old))
    assert _compile(tmp / "cache", 5.0).rank == 2
    assert claim.with_suffix(".c.cached").exists()


def test_a_module_found_once_is_given_from_memory(tmp_path: pathlib.Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    # FFCx looked each form's module up in the cache folder at every creation of the
    # form, listing the folder (3.5 ms a form at 13 600 files: a third of a short Goda
    # case's build and run) for the module the process had loaded before. Found once,
    # it is given from memory: the same module, the folder not listed again.
    import importlib.machinery

    formcache.install()
    cache = tmp_path / f"cache{MPI.COMM_WORLD.rank}"
    _compile(cache, 6.0)  # compiled (and loaded) by this process
    listed: list[str] = []
    fill = importlib.machinery.FileFinder._fill_cache

    def counted(self: importlib.machinery.FileFinder) -> None:
        listed.append(self.path)
        fill(self)

    monkeypatch.setattr(importlib.machinery.FileFinder, "_fill_cache", counted)
    first = _compile(cache, 6.0)  # found in the cache folder
    assert str(cache) in listed
    looked_up = len(listed)
    second = _compile(cache, 6.0)
    assert len(listed) == looked_up  # was: the folder listed again
    assert second.module is first.module and second.rank == 2
