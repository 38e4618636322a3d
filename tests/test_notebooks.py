"""The notebooks (notebooks/*.py, jupytext percent format), executed with short end times.

The ``.py`` files are the notebooks' only sources (no ``.ipynb`` is committed): jupytext
reads them into notebooks, JupyterLab opens them with jupytext (the ``notebook`` extra) and
the documentation executes them (``make docs``). Each notebook runs here in a Jupyter
kernel of this interpreter (nbclient), in a temporary working folder, with a run of a few
milliseconds on a coarse mesh; the test checks that no cell failed, that figures were
displayed, and that the runs wrote their outputs. Serial only: a kernel is a subprocess
of one rank.
"""

from __future__ import annotations

import json
import pathlib
import re
import time
from typing import Any

import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

NOTEBOOKS = pathlib.Path(__file__).resolve().parents[1] / "notebooks"
GODA = "01_goda_paper_figures.py"
VARIANT = "02_user_variant.py"
GENERAL = "03_general_contact.py"
STORM = "04_storm.py"

# 30 steps of the default Δt = 0.1 ms (the pulse lasts 2 ms: the impact is inside the
# run), on the mesh of refinement 0.7 (72 + 272 triangles): a few seconds per run.
END_TIME = 0.003
SHORT = {"BREAKWATER_NOTEBOOK_END_TIME": str(END_TIME),
         "BREAKWATER_NOTEBOOK_REFINEMENT": "0.7"}
# The storm notebook's short run: a rigid-block Monte Carlo of 20 storms (its finite-
# element run is three prototype waves, a few seconds).
STORMS = 20
SHORT_STORM = {"BREAKWATER_NOTEBOOK_STORMS": str(STORMS)}

serial_only = pytest.mark.skipif(MPI.COMM_WORLD.size > 1,
                                 reason="notebooks run in a serial kernel")


def test_sources_are_the_notebooks() -> None:
    """Every notebook of the folder is a ``NN_name.py`` source; no generator, no .ipynb."""
    assert sorted(p.name for p in NOTEBOOKS.glob("[0-9]*.py")) == [GODA, VARIANT, GENERAL,
                                                                   STORM]
    assert not (NOTEBOOKS / "make_notebooks.py").exists()


def _canonical(text: str) -> str:
    """The text without the jupytext version of its header."""
    return re.sub(r"(?m)^#\s+jupytext_version: .*\n", "", text)


@pytest.mark.parametrize("name", [GODA, VARIANT, GENERAL, STORM])
def test_source_is_a_percent_notebook(name: str) -> None:
    import jupytext
    import nbformat

    text = (NOTEBOOKS / name).read_text(encoding="utf-8")
    nb = jupytext.reads(text, fmt="py:percent")
    nbformat.validate(nb)
    assert nb.metadata["jupytext"]["text_representation"]["format_name"] == "percent"
    assert nb.metadata["kernelspec"]["name"] == "python3"
    kinds = [c.cell_type for c in nb.cells]
    assert kinds[0] == "markdown" and kinds.count("code") >= 10
    assert nb.cells[0].source.startswith("# ")  # the title
    # The settings cell reads the short-run variables (the tests and the docs set them).
    settings = next(c.source for c in nb.cells if c.cell_type == "code")
    for key in (*(SHORT_STORM if name == STORM else SHORT), "BREAKWATER_NOTEBOOK_OUTPUT"):
        assert f'os.environ.get("{key}"' in settings, key
    # Stored as jupytext writes it (opening and saving it in Jupyter changes nothing).
    assert _canonical(jupytext.writes(nb, fmt="py:percent")) == _canonical(text), \
        f"{name} is not in jupytext's percent format: `jupytext --to py:percent {name}`"


@pytest.fixture
def kernel(tmp_path: pathlib.Path, monkeypatch: pytest.MonkeyPatch) -> pathlib.Path:
    """A working folder, short-run settings, and a kernel of this interpreter.

    The kernelspec ``python3`` is written with ``sys.executable`` into a folder put first
    on ``JUPYTER_PATH``, so a user-wide ``python3`` kernelspec pointing to another Python
    cannot be picked up.
    """
    from ipykernel.kernelspec import write_kernel_spec

    jupyter = tmp_path / "jupyter"
    write_kernel_spec(jupyter / "kernels" / "python3")
    monkeypatch.setenv("JUPYTER_PATH", str(jupyter))
    monkeypatch.setenv("JUPYTER_RUNTIME_DIR", str(tmp_path / "runtime"))
    monkeypatch.setenv("IPYTHONDIR", str(tmp_path / "ipython"))
    monkeypatch.setenv("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    for key, value in {**SHORT, **SHORT_STORM}.items():
        monkeypatch.setenv(key, value)
    work = tmp_path / "work"
    work.mkdir()
    return work


def _execute(name: str, work: pathlib.Path, output: str,
             monkeypatch: pytest.MonkeyPatch) -> tuple[Any, pathlib.Path, float]:
    """Execute a notebook in ``work``; (executed notebook, output folder, seconds)."""
    import jupytext
    import nbformat
    from nbclient import NotebookClient

    monkeypatch.setenv("BREAKWATER_NOTEBOOK_OUTPUT", output)
    nb = jupytext.read(NOTEBOOKS / name)
    client = NotebookClient(nb, kernel_name="python3", timeout=300,
                            resources={"metadata": {"path": str(work)}})
    start = time.perf_counter()
    client.execute()  # raises CellExecutionError when a cell fails
    seconds = time.perf_counter() - start
    nbformat.write(nb, work / f"{pathlib.Path(name).stem}.ipynb")  # for inspection
    return nb, work / output, seconds


def _outputs(nb: Any, kind: str) -> list[dict[str, Any]]:
    return [o for c in nb.cells if c.cell_type == "code" for o in c.outputs
            if o.output_type == kind or kind in o.get("data", {})]


def _check_run(folder: pathlib.Path, figures: bool) -> dict[str, Any]:
    summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
    assert summary["finished"] and summary["error"] is None
    assert summary["time"]["reached"] == pytest.approx(END_TIME, rel=1e-12)
    for name in ("history.csv", "case.toml", "static.npz", "snapshot_max_ux.npz"):
        assert (folder / name).is_file(), name
    if figures:
        drawn = {p.name for p in (folder / "figures").glob("*.png")}
        assert {"static_uy.png", "static_syy.png", "probes_ux.png", "pair_probes_ux.png",
                "pair_probes_uy.png", "max_ux_deformed.png"} <= drawn
    return summary


@pytest.mark.serial
@serial_only
def test_goda_paper_figures(kernel: pathlib.Path, monkeypatch: pytest.MonkeyPatch) -> None:
    nb, out, _ = _execute(GODA, kernel, "goda_out", monkeypatch)
    assert not _outputs(nb, "error")
    summary = _check_run(out, figures=True)
    # The mound was calibrated to Goda's K_x = 500 kN/m (tolerance 1e-4 of the case).
    cal = summary["calibration"]
    assert cal["relative_error"] <= 1e-4 and cal["target"] * 0.205 == pytest.approx(500e3)
    # The notebook's own figures, and the paper's figures displayed inline.
    for name in ("notebook_static_pressure.png", "notebook_gauges.png",
                 "notebook_gap_at_max_ux.png", "notebook_pyvista_von_mises.png"):
        assert (out / "figures" / name).is_file(), name
    assert len(_outputs(nb, "image/png")) >= 10
    # The run's progress line, left at its end.
    assert any(o["data"]["text/plain"].startswith("goda: 100% |")
               for o in _outputs(nb, "display_data") if "text/plain" in o["data"])
    # The comparison table with the paper's numbers.
    tables = [o["data"]["text/markdown"] for o in _outputs(nb, "text/markdown")]
    assert any("4586 Pa" in t and "about 0.4 mm" in t for t in tables)


@pytest.mark.serial
@serial_only
def test_user_variant(kernel: pathlib.Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import tomllib

    nb, out, _ = _execute(VARIANT, kernel, "variant_out", monkeypatch)
    assert not _outputs(nb, "error")
    reference = _check_run(out / "goda", figures=False)
    variant = _check_run(out / "slope3_bolt34", figures=False)
    berm = _check_run(out / "berm", figures=True)
    # The variant is what the notebook says: 1:3 slopes, the 34 mm bolt on its 3.527 m
    # cord, and the reference's calibrated gravel (not re-calibrated).
    G = reference["calibration"]["shear_modulus"]
    case = tomllib.loads((out / "slope3_bolt34" / "case.toml").read_text(encoding="utf-8"))
    assert case["mesh"]["goda"]["slope"] == 3.0
    assert case["mesh"]["goda"]["bolt_height"] == 0.034
    assert case["loads"]["impact"]["pendulum"]["cord_length"] == 3.527
    assert case["bodies"]["mound"]["shear_modulus"] == G
    assert "calibration" not in variant
    # The user's gmsh mesh was used, with the same gravel.
    case = tomllib.loads((out / "berm" / "case.toml").read_text(encoding="utf-8"))
    assert pathlib.Path(case["mesh"]["source"]).name == "berm.msh"
    assert case["bodies"]["mound"]["shear_modulus"] == G
    assert berm["mesh"]["source"].endswith("berm.msh")
    # The measured record was read from its CSV file as the wave load's table.
    measured = _check_run(out / "measured_wave", figures=False)
    assert measured["loads"]["wave"]["time_function"] == "table"
    assert "impact" not in measured["loads"]  # the pendulum was switched off
    case = tomllib.loads((out / "measured_wave" / "case.toml").read_text(encoding="utf-8"))
    assert pathlib.Path(case["loads"]["wave"]["table"]["file"]).name == "pressure_record.csv"
    for name in ("comparison.png", "meshes.png", "berm/berm_mesh.png", "berm/berm.msh",
                 "measured/record_and_profile.png"):
        assert (out / name).is_file(), name
    assert len(_outputs(nb, "image/png")) >= 5


@pytest.mark.serial
@serial_only
def test_general_contact(kernel: pathlib.Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import tomllib

    nb, out, _ = _execute(GENERAL, kernel, "general_out", monkeypatch)
    assert not _outputs(nb, "error")
    # The sliding block example ran from its case file, with its general pair.
    block = json.loads((out / "block" / "summary.json").read_text(encoding="utf-8"))
    assert block["finished"] and block["error"] is None
    case = tomllib.loads((out / "block" / "case.toml").read_text(encoding="utf-8"))
    assert case["contact"]["sliding"]["master_surface"] == "base_top"
    # The Goda case both ways: the general run is the conforming mesh's interface made a
    # general pair with the settings the notebook names, on the conforming run's gravel.
    conforming = _check_run(out / "conforming", figures=False)
    general = json.loads((out / "general" / "summary.json").read_text(encoding="utf-8"))
    assert general["finished"] and general["error"] is None
    case = tomllib.loads((out / "general" / "case.toml").read_text(encoding="utf-8"))
    pair = case["contact"]["interface"]
    assert pair["master_surface"] == ["interface", "mound_surface"]
    assert (pair["integration"], pair["rotations"]) == ("nodes", "small")
    assert case["bodies"]["mound"]["shear_modulus"] == \
        conforming["calibration"]["shear_modulus"]
    assert len(_outputs(nb, "image/png")) >= 4
    tables = [o["data"]["text/markdown"] for o in _outputs(nb, "text/markdown")]
    assert any("Newton iterations" in t for t in tables)


@pytest.mark.serial
@serial_only
def test_storm(kernel: pathlib.Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from breakwater.outputs.stormrecord import read_waves

    nb, out, _ = _execute(STORM, kernel, "storm_out", monkeypatch)
    assert not _outputs(nb, "error")
    # The finite-element storm: the notebook's three waves, each recorded beside the
    # rigid block's sliding, the record's total the sum of the waves'.
    summary = json.loads((out / "fe" / "summary.json").read_text(encoding="utf-8"))
    assert summary["finished"] and summary["error"] is None
    waves = read_waves(out / "fe" / "waves.csv")
    assert len(waves["wave"]) == 3 and waves["height"][0] == waves["height"][2] == 8.0
    assert waves["height"][1] > 15.0  # the storm's highest wave, seed 0
    assert summary["storm"]["total_sliding"] == pytest.approx(waves["sliding"].sum(),
                                                              rel=1e-12, abs=1e-15)
    assert summary["solver"]["adaptive"]["rejected_steps"] >= 0
    # The rigid-block Monte Carlo over the short run's storms, printed.
    text = "".join(o.get("text", "") for o in _outputs(nb, "stream"))
    assert f"{STORMS} storms of 1000 waves: expected sliding" in text
    assert "P(S > limit): 0.1 m:" in text
    tables = [o["data"]["text/markdown"] for o in _outputs(nb, "text/markdown")]
    assert any("rigid block (mm)" in t for t in tables)
    assert len(_outputs(nb, "image/png")) >= 3


def _run_cells(sources: list[str], work: pathlib.Path) -> Any:
    """Execute code cells in a kernel of this interpreter in ``work``; the notebook."""
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(s) for s in sources]
    NotebookClient(nb, kernel_name="python3", timeout=300,
                   resources={"metadata": {"path": str(work)}}).execute()
    return nb


_SHORT_RUN = f"""\
import breakwater
from mpi4py import MPI
from breakwater.casefile.case import load_case
from breakwater.run.simulation import run
case = load_case(None, ["time.end_time={END_TIME}", "mesh.refinement=0.7",
                        "output.directory='out'", "output.figures=false"])
built = case.build(MPI.COMM_WORLD)
model, time, output, extra = built
"""


@pytest.mark.serial
@serial_only
def test_progress_line_in_a_kernel(kernel: pathlib.Path) -> None:
    """A run in a notebook shows one progress line, updated in place; none when off.

    Before, a kernel's stderr being no terminal, the cell showed nothing until the
    final report (and ``progress=True`` wrote tqdm's carriage returns into it).
    """
    nb = _run_cells([_SHORT_RUN, "summary = run(model, time, output, report=False)",
                     "import dataclasses\n"
                     "run(model, time, dataclasses.replace(output, progress=False), "
                     "report=False)"], kernel)
    shown = [o for o in nb.cells[1].outputs if o.output_type == "display_data"]
    assert len(shown) == 1
    line = shown[0]["data"]["text/plain"]
    assert line.startswith("goda: 100% |")
    assert f"t = {END_TIME:.4g}/{END_TIME:.4g} s, 30 steps," in line, line
    assert not any("\r" in o.get("text", "") for c in nb.cells for o in c.outputs)
    assert not [o for o in nb.cells[2].outputs if o.output_type == "display_data"]
