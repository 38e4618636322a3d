"""The modules of breakwater import each other without a cycle.

The import graph of ``breakwater/*.py`` is read from the sources (every import
statement that runs: at module level and inside functions), and must have no cycle:
an import hidden inside a function is a cycle all the same. Imports under
``if TYPE_CHECKING:`` never run (they name types for the annotations only), so they
are left out; the test checks that it sees them, to leave them out knowingly.
"""

from __future__ import annotations

import ast
import pathlib

import breakwater

PACKAGE = pathlib.Path(breakwater.__file__).parent


def import_graph(package: pathlib.Path) -> dict[str, set[str]]:
    """Module name -> the modules of the package it imports (relative or absolute)."""
    modules = {p.stem for p in package.glob("*.py")}
    graph: dict[str, set[str]] = {}
    for name in modules:
        tree = ast.parse((package / f"{name}.py").read_text(encoding="utf-8"))
        found: set[str] = set()
        type_only = {id(n) for block in ast.walk(tree) if _is_type_checking(block)
                     for n in ast.walk(block)}
        for node in ast.walk(tree):
            if id(node) in type_only:
                continue
            if isinstance(node, ast.ImportFrom):
                if node.level == 1:  # from .x import y / from . import x
                    targets = [node.module] if node.module else [a.name for a in node.names]
                elif node.level == 0 and (node.module or "").startswith("breakwater."):
                    targets = [node.module.split(".", 1)[1]]  # type: ignore[union-attr]
                elif node.level == 0 and node.module == "breakwater":
                    targets = [a.name for a in node.names]
                else:
                    targets = []
            elif isinstance(node, ast.Import):
                targets = [a.name.split(".", 1)[1] for a in node.names
                           if a.name.startswith("breakwater.")]
            else:
                continue
            found |= {t.split(".")[0] for t in targets} & modules
        graph[name] = found - {name, "__init__"}
    return graph


def _is_type_checking(node: ast.AST) -> bool:
    """An ``if TYPE_CHECKING:`` block."""
    return isinstance(node, ast.If) and (
        (isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING")
        or (isinstance(node.test, ast.Attribute) and node.test.attr == "TYPE_CHECKING"))


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The cycles found by a depth-first search (one per back edge)."""
    found: list[list[str]] = []
    state: dict[str, int] = {}  # 1: on the path, 2: done
    path: list[str] = []

    def visit(node: str) -> None:
        state[node] = 1
        path.append(node)
        for nxt in sorted(graph[node]):
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
    # The reader sees module-level, function-level and aliased imports.
    graph = import_graph(PACKAGE)
    assert "files" in graph["checkpoint"] and "checkpoint" in graph["surfaceoutputs"]
    assert "figures" in graph["simulation"]  # imported inside a function
    assert "checkpoint" in graph["simulation"]  # from . import checkpoint as ckpt
    # casebuild names the case's types under TYPE_CHECKING only: not an edge.
    source = (PACKAGE / "casebuild.py").read_text(encoding="utf-8")
    assert "from .case import" in source and "case" not in graph["casebuild"]
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == [["a", "b", "c", "a"]]


def test_no_import_cycle() -> None:
    assert cycles(import_graph(PACKAGE)) == []


def test_no_logging_set_up_on_import() -> None:
    # Importing breakwater's modules installs no handler or filter on its loggers
    # (a run sets up rank-0 logging for itself, and removes it again).
    import importlib
    import logging

    for p in sorted(PACKAGE.glob("*.py")):
        if p.stem not in ("__init__", "__main__"):
            importlib.import_module(f"breakwater.{p.stem}")
    names = [n for n in logging.Logger.manager.loggerDict if n.startswith("breakwater")]
    assert "breakwater.simulation" in names
    for name in names:
        logger = logging.getLogger(name)
        assert not logger.filters and not logger.handlers, name
