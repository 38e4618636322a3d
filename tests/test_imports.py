"""The house rules of the package: layers, no import cycle, modest module and class sizes.

breakwater is a pipeline of subpackages (see ``docs/developer.md``). Each subpackage may
import from its own layer and the layers below it, never from a layer above:

======  ==============  ===================================================================
layer   subpackage      what it holds
======  ==============  ===================================================================
0       ``forms``       the physics in UFL (``forms/``); imports nothing of breakwater
1       ``common``      errors, MPI helpers, output files, the console, gmsh
2       ``meshes``      the geometries (``meshes/``)
2       ``config``      typed settings and their TOML form, the run specs
3       ``loads``       load signals, traction fields, Goda's pressure
4       ``model``       the mesh, bodies, materials, pair settings: the contact model
5       ``contact``     conforming and general contact pairs
6       ``stepping``    GN22, the Newton solvers, step-size control
7       ``energy``      the energy ledger
8       ``statics``     initial equilibrium, relaxation, calibration
9       ``outputs``     history, fields, probes, summary, figures, checkpoints
10      ``casefile``    the case file, read and built into a model and specs
11      ``run``         one run: the time loop and its session
12      ``studies``     parameter studies
13      top level       ``cli``, ``__main__``, ``__init__``
======  ==============  ===================================================================

The import graph is read from the sources: every import statement, at module level,
inside functions and under ``if TYPE_CHECKING:`` (an import that only names a type is
a dependency of the reader all the same). It must respect the layers and have no cycle.
"""

from __future__ import annotations

import ast
import importlib
import logging
import pathlib
import subprocess
import sys

import pytest

import breakwater

pytestmark = pytest.mark.serial  # the sources alone (no MPI): once is enough

PACKAGE = pathlib.Path(breakwater.__file__).parent
FORMS = pathlib.Path(importlib.import_module("breakwater.forms").__file__).parent
MESHES = pathlib.Path(importlib.import_module("breakwater.meshes").__file__).parent

LAYERS = {"forms": 0, "common": 1, "meshes": 2, "config": 2, "loads": 3, "storms": 3,
          "model": 4, "contact": 5, "stepping": 6, "energy": 7, "statics": 8, "outputs": 9,
          "casefile": 10, "run": 11, "studies": 12, "": 13}
MAX_MODULE_LINES = 600  # the brief: a module over ≈600 lines holds two jobs
MAX_CLASS_LINES = 200  # and a class over ≈200


ROOTS = ((PACKAGE, ""), (FORMS, "forms."), (MESHES, "meshes."))


def sources(roots: tuple[tuple[pathlib.Path, str], ...] = ROOTS) -> dict[str, pathlib.Path]:
    """Dotted module name (``contact.general``, ``cli``, ``forms.contact``) -> its file."""
    found = {}
    for root, prefix in roots:
        for path in sorted(root.rglob("*.py")):
            parts = path.relative_to(root).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            name = prefix + ".".join(parts) if parts else prefix.rstrip(".")
            found[name or "__init__"] = path
    return found


def layer(module: str) -> int:
    """The layer of a module: its subpackage's, or the top level's."""
    head = module.split(".")[0]
    is_subpackage = head in LAYERS and ("." in module or module in ("forms", "meshes"))
    return LAYERS[head] if is_subpackage or module in LAYERS else LAYERS[""]


def _resolve(name: str, modules: set[str]) -> str | None:
    """The module of ``breakwater.<name>`` (a module, or a package's ``__init__``)."""
    while name:
        if name in modules:
            return name
        name = name.rpartition(".")[0]
    return None


def import_graph(roots: tuple[tuple[pathlib.Path, str], ...] = ROOTS) -> dict[str, set[str]]:
    """Module -> the modules of the package it imports (any import statement at all)."""
    files = sources(roots)
    modules = set(files)
    graph: dict[str, set[str]] = {}
    for name, path in files.items():
        is_package = path.name == "__init__.py"
        here = name.split(".") if is_package else name.split(".")[:-1]
        found: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            targets: list[str] = []
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = here[: len(here) - node.level + 1]
                    module = ".".join([*base, *([node.module] if node.module else [])])
                elif (node.module or "").startswith("breakwater"):
                    module = node.module.removeprefix("breakwater").lstrip(".")  # type: ignore[union-attr]
                else:
                    continue
                targets = [f"{module}.{a.name}".lstrip(".") for a in node.names] + [module]
            elif isinstance(node, ast.Import):
                targets = [a.name.removeprefix("breakwater.") for a in node.names
                           if a.name.startswith("breakwater.")]
            for target in targets:
                # ``from breakwater.x import y``: y is a module if there is one, else x
                resolved = target if target in modules else _resolve(target, modules)
                if resolved:
                    found.add(resolved)
        if "__init__" in found and name != "__init__":
            found.discard("__init__")  # every module imports the package's __init__ first
        graph[name] = found - {name}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The cycles found by a depth-first search (one per back edge)."""
    found: list[list[str]] = []
    state: dict[str, int] = {}  # 1: on the path, 2: done
    path: list[str] = []

    def visit(node: str) -> None:
        state[node] = 1
        path.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                found.append([*path[path.index(nxt):], nxt])
            elif nxt not in state:
                visit(nxt)
        path.pop()
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node)
    return found


def test_the_graph_is_read() -> None:
    # The reader sees module-level, function-level, aliased and type-only imports.
    graph = import_graph()
    assert "common.files" in graph["outputs.checkpoint"]
    assert "outputs.figures" in graph["run.simulation"]  # inside a function
    assert "outputs.checkpoint" in graph["run.simulation"]  # import checkpoint as ckpt
    assert "common.gmshtools" in graph["meshes.goda"]  # meshes/ is mapped in
    assert "forms" in graph["model.model"] or "forms.contact" in graph["model.model"]
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == [["a", "b", "c", "a"]]
    assert layer("contact.general") == LAYERS["contact"] and layer("cli") == LAYERS[""]
    assert layer("forms.contact") == 0 and layer("forms") == 0


def test_type_checking_imports_are_edges(tmp_path: pathlib.Path) -> None:
    # An import under ``if TYPE_CHECKING:`` is an edge, relative or absolute.
    (tmp_path / "sub").mkdir()
    (tmp_path / "__init__.py").write_text("")
    (tmp_path / "sub" / "__init__.py").write_text("")
    (tmp_path / "sub" / "a.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .b import B\n")
    (tmp_path / "sub" / "b.py").write_text(
        "def f():\n    from breakwater.sub.a import A\n")
    graph = import_graph(((tmp_path, ""),))
    assert graph["sub.a"] == {"sub.b"} and graph["sub.b"] == {"sub.a"}
    assert cycles(graph) == [["sub.a", "sub.b", "sub.a"]]


def test_layers() -> None:
    # No module imports from a layer above its own (TYPE_CHECKING imports included).
    graph = import_graph()
    upward = sorted(f"{a} -> {b}" for a, targets in graph.items() for b in targets
                    if layer(b) > layer(a))
    assert upward == [], "imports from a higher layer:\n" + "\n".join(upward)


def test_no_import_cycle() -> None:
    found = cycles(import_graph())
    assert found == [], "import cycles:\n" + "\n".join(" -> ".join(c) for c in found)


def test_module_and_class_sizes() -> None:
    # A module over ≈600 lines, or a class over ≈200, holds two jobs (the brief).
    long_modules, long_classes = [], []
    for name, path in sources().items():
        text = path.read_text(encoding="utf-8")
        if len(text.splitlines()) > MAX_MODULE_LINES:
            long_modules.append(f"{name}: {len(text.splitlines())} lines")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.ClassDef):
                size = node.end_lineno - node.lineno + 1  # type: ignore[operator]
                if size > MAX_CLASS_LINES:
                    long_classes.append(f"{name}.{node.name}: {size} lines")
    assert long_modules == [] and long_classes == [], "\n".join(long_modules + long_classes)


def test_reading_a_case_needs_no_solver_stack() -> None:
    # Reading and checking a case file or a study file imports neither dolfinx nor
    # petsc4py (a login node, a spreadsheet export, ``show-case``): a fresh interpreter.
    code = ("import sys\n"
            "from breakwater.casefile.case import load_case\n"
            "from breakwater.studies.studyfile import load_study\n"
            "load_case(None, [])\n"
            "heavy = sorted(m for m in ('dolfinx', 'petsc4py', 'ufl') if m in sys.modules)\n"
            "print(','.join(heavy))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=300)
    assert out.stdout.strip() == "", f"reading a case imported {out.stdout.strip()}"


def test_no_logging_set_up_on_import() -> None:
    # Importing breakwater's modules installs no handler or filter on its loggers
    # (a run sets up rank-0 logging for itself, and removes it again).
    for name in sources():
        if name not in ("__init__", "__main__") and not name.startswith(("forms", "meshes")):
            importlib.import_module(f"breakwater.{name}")
    names = [n for n in logging.Logger.manager.loggerDict if n.startswith("breakwater")]
    assert "breakwater.run.simulation" in names
    for name in names:
        logger = logging.getLogger(name)
        assert not logger.filters and not logger.handlers, name
