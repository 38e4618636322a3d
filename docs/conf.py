"""Sphinx configuration of the breakwater documentation (Sphinx + MyST-NB).

Build with ``make docs`` (``sphinx-build -W --keep-going -b html docs docs/_build/html``).
Three things are generated at build time into ``docs/_generated/`` (not committed):

- ``case_reference.md``, the case-file table, from :func:`breakwater.casefile.case.case_reference`;
- ``api.md``, one ``automodule`` per module, grouped by subpackage;
- the notebooks, converted from their jupytext sources ``notebooks/*.py`` to ``.ipynb``,
  which MyST-NB executes during the build, with the short end time of
  ``NOTEBOOK_SETTINGS`` (an environment variable of the same name overrides it).
"""

from __future__ import annotations

import importlib
import os
import pathlib
import pkgutil
import re
import shutil

import jupytext
import nbformat
from sphinx.application import Sphinx

import breakwater  # first: it loads the PETSc of the dolfinx wheel (when installed)
from breakwater.casefile.case import case_reference

DOCS = pathlib.Path(__file__).resolve().parent
ROOT = DOCS.parent
GENERATED = DOCS / "_generated"
BUILD = DOCS / "_build"

# -- the notebooks: a shortened run ------------------------------------------------------
# 0.05 s (500 steps of 0.1 ms) covers the impact, the largest sway (t ≈ 0.032 s) and the
# lift-off of the heel, on the paper's mesh; the paper's comparison needs 0.15 s
# (``BREAKWATER_NOTEBOOK_END_TIME=0.15 make docs``, after ``rm -rf docs/_build``).
NOTEBOOK_SETTINGS = {
    "BREAKWATER_NOTEBOOK_END_TIME": "0.05",
    "BREAKWATER_NOTEBOOK_REFINEMENT": "1.0",
    "BREAKWATER_NOTEBOOK_STORMS": "200",  # the storm notebook's rigid Monte Carlo (1000)
}
for _key, _value in NOTEBOOK_SETTINGS.items():
    os.environ.setdefault(_key, _value)
os.environ.pop("BREAKWATER_NOTEBOOK_OUTPUT", None)  # each notebook's own folder
os.environ["MPLBACKEND"] = "module://matplotlib_inline.backend_inline"

NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9]*.py"))


def _write_if_changed(path: pathlib.Path, text: str) -> None:
    """Write ``text`` unless the file holds it already (Sphinx rebuilds on mtime)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.is_file() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")


def _kernel() -> None:
    """A ``python3`` kernelspec of this interpreter, first on ``JUPYTER_PATH``.

    The notebooks ask for the kernel ``python3``; a user-wide kernelspec of that name
    pointing to another Python (without breakwater) must not be picked up.
    """
    from ipykernel.kernelspec import write_kernel_spec

    jupyter = BUILD / "jupyter"
    shutil.rmtree(jupyter, ignore_errors=True)
    write_kernel_spec(jupyter / "kernels" / "python3")
    paths = [str(jupyter), *filter(None, os.environ.get("JUPYTER_PATH", "").split(os.pathsep))]
    os.environ["JUPYTER_PATH"] = os.pathsep.join(paths)


def _modules(package: str) -> list[str]:
    """The package and its modules (``__main__`` left out), in alphabetical order."""
    module = importlib.import_module(package)
    names = [package]
    for info in pkgutil.iter_modules(module.__path__, package + "."):
        if not info.name.endswith("__main__") and not info.ispkg:
            names.append(info.name)
    return names


# One section per subpackage, in the order of the pipeline (the package's docstring first).
API_SECTIONS = {
    "Foundations (breakwater.common)": "breakwater.common",
    "Settings (breakwater.config)": "breakwater.config",
    "Loads (breakwater.loads)": "breakwater.loads",
    "Storms (breakwater.storms)": "breakwater.storms",
    "The model (breakwater.model)": "breakwater.model",
    "Contact (breakwater.contact)": "breakwater.contact",
    "Time stepping (breakwater.stepping)": "breakwater.stepping",
    "Energy (breakwater.energy)": "breakwater.energy",
    "Static states (breakwater.statics)": "breakwater.statics",
    "Outputs (breakwater.outputs)": "breakwater.outputs",
    "The case file (breakwater.casefile)": "breakwater.casefile",
    "A run (breakwater.run)": "breakwater.run",
    "Studies (breakwater.studies)": "breakwater.studies",
    "The physics in UFL (forms/)": "breakwater.forms",
    "Geometries (meshes/)": "breakwater.meshes",
}


def _api() -> str:
    lines = ["```{eval-rst}", ".. automodule:: breakwater", "```", "",
             "```{eval-rst}", ".. automodule:: breakwater.cli", "   :members:", "```", ""]
    for title, package in API_SECTIONS.items():
        lines += [f"## {title}", ""]
        for name in _modules(package):
            # A package's own page is its docstring: its members are its modules'. A
            # module's members are those it defines (not the names its __all__ re-exports
            # from another module, which would be documented twice: ambiguous references).
            options = [] if name == package else ["   :members:", "   :ignore-module-all:"]
            lines += ["```{eval-rst}", f".. automodule:: {name}", *options, "```", ""]
    listed = {m for p in API_SECTIONS.values() for m in _modules(p)}
    packages = [m.name for m in pkgutil.iter_modules(breakwater.__path__, "breakwater.")
                if m.ispkg and m.name != "breakwater.cases"]
    missing = sorted(set(packages) - listed)
    if missing:
        raise RuntimeError(f"docs/conf.py: subpackages missing from API_SECTIONS: {missing}")
    return "\n".join(lines)


_CODE = re.compile(r"(`[^`]*`)")


def _markdown_text(line: str) -> str:
    """``<`` and ``>`` outside code spans as text (``results/<name>`` is not an HTML tag)."""
    return "".join(part if part.startswith("`") else
                   part.replace("<", "&lt;").replace(">", "&gt;")
                   for part in _CODE.split(line))


def _generate() -> None:
    reference = "\n".join(_markdown_text(line) for line in case_reference().splitlines())
    _write_if_changed(GENERATED / "case_reference.md", reference + "\n")
    _write_if_changed(GENERATED / "api.md", _api())
    for stale in {p.stem for p in GENERATED.glob("*.ipynb")} - {p.stem for p in NOTEBOOKS}:
        (GENERATED / f"{stale}.ipynb").unlink()  # a notebook renamed or removed
    for source in NOTEBOOKS:
        notebook = jupytext.read(source)
        _write_if_changed(GENERATED / f"{source.stem}.ipynb", nbformat.writes(notebook))


_generate()
_kernel()

# -- project -----------------------------------------------------------------------------
project = "breakwater"
author = "the breakwater authors"
copyright = "2025, the breakwater authors"
release = breakwater.__version__
version = release

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
]
exclude_patterns = ["_build", "_generated/*.md"]
source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb"}
root_doc = "index"

# -- MyST and MyST-NB --------------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath", "substitution", "colon_fence"]
myst_heading_anchors = 3
myst_substitutions = {
    "end_time": os.environ["BREAKWATER_NOTEBOOK_END_TIME"],
    "refinement": os.environ["BREAKWATER_NOTEBOOK_REFINEMENT"],
}
nb_execution_mode = "force"
nb_execution_in_temp = True  # the runs write their outputs to a temporary folder
nb_execution_timeout = 1800
nb_execution_raise_on_error = True  # a failing cell fails the build
nb_execution_show_tb = True
nb_render_markdown_format = "myst"  # the notebooks display Markdown tables and math
nb_merge_streams = True

# -- autodoc (Google-style docstrings) ---------------------------------------------------
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_ivar = True  # dataclass "Attributes:" as fields, not duplicate attributes

_LITERAL = re.compile(r"(``.*?``)")


def _escape_bars(app: Sphinx, what: str, name: str, obj: object, options: object,
                 lines: list[str]) -> None:
    """Escape ``|`` outside inline literals in docstrings.

    The docstrings write absolute values as plain text, ``|g|`` or ``|v_T|²``, which
    reStructuredText would read as substitution references (undefined: an error).
    """
    for i, line in enumerate(lines):
        if "|" in line:
            parts = _LITERAL.split(line)
            lines[i] = "".join(part if part.startswith("``") else part.replace("|", r"\|")
                               for part in parts)


def setup(app: Sphinx) -> None:
    """Connect the docstring filter."""
    app.connect("autodoc-process-docstring", _escape_bars)


# -- HTML --------------------------------------------------------------------------------
html_theme = "furo"
html_title = f"breakwater {release}"
