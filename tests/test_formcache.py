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
