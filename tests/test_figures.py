"""Figures redrawn from output folders, including folders written before the pair-named
columns and snapshot keys (issue 21): ``python -m breakwater.outputs.figures DIR`` draws
the same contact figures from an old folder as from a new one with the same numbers."""

from __future__ import annotations

import gc
import pathlib

import numpy as np
import pytest
from mpi4py import MPI

from breakwater.outputs import figures

pytestmark = pytest.mark.serial  # files and matplotlib alone (no MPI): once is enough

COMM = MPI.COMM_WORLD


@pytest.fixture(autouse=True)
def _collect():
    yield
    gc.collect()
    COMM.barrier()


def _folder(path: pathlib.Path, columns: dict[str, str], keys: dict[str, str]) -> pathlib.Path:
    """An output folder with a history and a static snapshot of one conforming pair.

    ``columns``/``keys``: quantity → the column/key name it is written under.
    """
    path.mkdir()
    t = np.linspace(0.0, 0.01, 11)
    history = {"t": t, "dt": np.full_like(t, 1e-3), "newton_iterations": np.full_like(t, 3),
               columns["length"]: 0.2 - t, columns["normal"]: 900.0 + 1e4 * t,
               columns["tangential"]: -50.0 * np.sin(300 * t)}
    header = ",".join(history)
    rows = np.column_stack(list(history.values()))
    np.savetxt(path / "history.csv", rows, delimiter=",", header=header, comments="")
    x = np.column_stack([np.linspace(-0.1, 0.1, 9), np.zeros(9)])
    # One body of two triangles, for the contour figures the static snapshot also gives.
    corners = np.array([[-0.1, 0.0], [0.1, 0.0], [0.1, 0.2], [-0.1, 0.2]])
    body = {"bodies": np.array(["block"]), "block_x": corners,
            "block_triangles": np.array([[0, 1, 2], [0, 2, 3]]),
            **{f"block_{k}": np.array([0.0, 1.0, 2.0, 3.0]) * 1e-4
               for k in ("ux", "uy", "von_mises", "stress_yy")}}
    np.savez(path / "static.npz", **body,
             **{keys["x"]: x, keys["pressure"]: 4e3 + 1e5 * x[:, 0] ** 2},
             **keys.get("extra", {}))
    return path


def test_old_folders_draw_the_same_contact_figures(tmp_path: pathlib.Path) -> None:
    old = _folder(tmp_path / "old", {"length": "contact_length_0", "normal": "normal_force_0",
                                     "tangential": "tangential_force_0"},
                  {"x": "pair0_x", "pressure": "pair0_pressure"})
    new = _folder(tmp_path / "new", {"length": "0_contact_length", "normal": "0_normal_force",
                                     "tangential": "0_tangential_force"},
                  {"x": "contact_0_x", "pressure": "contact_0_pressure",
                   "extra": {"contacts": np.array(["0"])}})
    drawn = {f.name for f in figures.make_figures(old)}
    assert {"contact.png", "static_pressure.png"} <= drawn
    assert {f.name for f in figures.make_figures(new)} == drawn
    for name in ("contact.png", "static_pressure.png"):
        # The same numbers under the old and the new names: the same picture.
        assert (old / "figures" / name).read_bytes() == (new / "figures" / name).read_bytes()


def test_the_figures_do_not_take_the_sessions_matplotlib_settings(
        tmp_path: pathlib.Path) -> None:
    # A notebook's plt.style.use("dark_background") drew a run's figures black on black
    # (its lines' colours are set, the background was the style's), and rcParams
    # "text.usetex" without LaTeX ended a finished run in a RuntimeError. The figures are
    # now drawn with matplotlib's defaults, as from the command line: the same bytes.
    import matplotlib

    columns = {"length": "0_contact_length", "normal": "0_normal_force",
               "tangential": "0_tangential_force"}
    keys = {"x": "contact_0_x", "pressure": "contact_0_pressure",
            "extra": {"contacts": np.array(["0"])}}
    plain, styled = _folder(tmp_path / "plain", columns, keys), _folder(tmp_path / "styled",
                                                                         columns, keys)
    drawn = [f.name for f in figures.make_figures(plain)]
    session = {"axes.facecolor": "black", "figure.facecolor": "black", "font.size": 20.0,
               "lines.linewidth": 0.2, "text.usetex": True}
    with matplotlib.rc_context(session):
        assert [f.name for f in figures.make_figures(styled)] == drawn
        # ... and the session's settings are left as they were
        assert {k: matplotlib.rcParams[k] for k in session} == session
    assert len(drawn) >= 4
    for name in drawn:
        assert (plain / "figures" / name).read_bytes() == (styled / "figures" / name).read_bytes()


def test_redraw_needs_a_run_folder(tmp_path: pathlib.Path,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    # python -m breakwater.outputs.figures DIR: a folder that does not exist was a
    # traceback (FileNotFoundError from mkdir); a study's folder (sweep.csv, case-*
    # folders) drew nothing and exited 0. Both: one line naming the folder, exit 2.
    if MPI.COMM_WORLD.rank != 0:
        return
    study = tmp_path / "study"
    (study / "case-0000").mkdir(parents=True)
    (study / "sweep.csv").write_text("case,folder,status\n")
    for folder in (tmp_path / "none", study):
        assert figures.main([str(folder)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and str(folder) in err and "no run outputs" in err
    assert not (study / "figures").exists()


@pytest.mark.parametrize("source, paper", [("goda", True), ("/home/me/caisson.geo", False)])
def test_titles_cite_the_paper_for_its_model_only(tmp_path: pathlib.Path,
                                                  monkeypatch: pytest.MonkeyPatch,
                                                  source: str, paper: bool) -> None:
    # A user's own geometry is not the paper's model: its titles said "cf. paper Fig. 17".
    import json

    from matplotlib.axes import Axes

    folder = _folder(tmp_path / "run", {"length": "0_contact_length", "normal": "0_normal_force",
                                        "tangential": "0_tangential_force"},
                     {"x": "contact_0_x", "pressure": "contact_0_pressure",
                      "extra": {"contacts": np.array(["0"])}})
    (folder / "summary.json").write_text(json.dumps({"mesh": {"source": source}}))
    titles: list[str] = []
    original = Axes.set_title
    monkeypatch.setattr(Axes, "set_title", lambda ax, label, *a, **k: (
        titles.append(str(label)), original(ax, label, *a, **k))[1])
    figures.make_figures(folder)
    assert any("Static vertical stress" in t for t in titles), titles
    cited = [t for t in titles if "cf. paper" in t]
    assert (len(cited) >= 3) if paper else cited == [], titles
