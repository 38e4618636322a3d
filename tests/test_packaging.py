"""The wheel a user installs holds every module and data file of the checkout.

The tests run on the checkout (an editable install): a subpackage missing from
pyproject's package list passed them all while the installed package failed at its
first import (``breakwater.storms``: ``python -m breakwater run`` from a wheel was
``ModuleNotFoundError``). Built here from a copy of the sources (setuptools writes
``build/`` beside them), without build isolation (no download): about 1 s.
"""

from __future__ import annotations

import pathlib
import shutil
import subprocess
import sys
import zipfile

import pytest
from mpi4py import MPI

ROOT = pathlib.Path(__file__).resolve().parent.parent
SOURCES = {"breakwater": "breakwater", "forms": "breakwater/forms",
           "meshes": "breakwater/meshes"}
"""The checkout's package folders and where the wheel holds them (pyproject's
package-dir)."""


def expected_files() -> set[str]:
    """Every file of the checkout's packages, as a path inside the wheel."""
    names = set()
    for source, target in SOURCES.items():
        for path in (ROOT / source).rglob("*"):
            relative = path.relative_to(ROOT / source)
            if path.is_file() and "__pycache__" not in relative.parts \
                    and path.suffix != ".pyc":
                names.add(f"{target}/{relative.as_posix()}")
    return names


def build_wheel(folder: pathlib.Path) -> zipfile.ZipFile:
    """The wheel of a copy of the checkout, built in ``folder``."""
    source = folder / "src"
    source.mkdir()
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy(ROOT / name, source / name)
    for name in SOURCES:
        shutil.copytree(ROOT / name, source / name,
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    subprocess.run([sys.executable, "-m", "pip", "wheel", str(source), "--no-deps",
                    "--no-build-isolation", "--quiet", "-w", str(folder / "wheel")],
                   check=True, capture_output=True, timeout=300)
    (wheel,) = (folder / "wheel").glob("breakwater-*.whl")
    return zipfile.ZipFile(wheel)


@pytest.mark.serial
def test_the_wheel_holds_every_module_and_data_file(tmp_path: pathlib.Path) -> None:
    if MPI.COMM_WORLD.size > 1:
        pytest.skip("builds a wheel in a subprocess: serially")
    with build_wheel(tmp_path) as wheel:
        shipped = {name for name in wheel.namelist() if not name.startswith("breakwater-")}
    missing = sorted(expected_files() - shipped)
    assert not missing, f"the wheel leaves out {missing}"
    assert {"breakwater/cases/goda.toml", "breakwater/cases/goda3d.toml",
            "breakwater/forms/contact.py", "breakwater/meshes/goda.py",
            "breakwater/storms/waves.py"} <= shipped
