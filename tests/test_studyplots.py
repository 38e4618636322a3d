"""A study's figures (breakwater.studies.plots): the numbers drawn are the table's.

Each panel draws a column against a varied key, scaled to a display unit named in the
axis label (m → mm, s → ms, Pa → MPa). The keys of ``[time]`` that are not times
(``time.beta1``, ``time.newton_max_it``) were drawn × 1000 and labelled ms: a study of
GN22's β₁ = 0.5, 0.6 showed x = 500, 600 ms.
"""

from __future__ import annotations

import csv
import pathlib

import pytest
from matplotlib.axes import Axes

from breakwater.studies.plots import make_figures
from breakwater.studies.studyfile import load_study

pytestmark = pytest.mark.serial  # files only: once is enough


def _drawn(monkeypatch: pytest.MonkeyPatch) -> tuple[list[tuple[list, list]], list[str]]:
    """Record the lines drawn and the x labels set."""
    lines: list[tuple[list, list]] = []
    labels: list[str] = []
    plot, xlabel = Axes.plot, Axes.set_xlabel

    def record_plot(self, x, y, *args, **kwargs):  # type: ignore[no-untyped-def]
        lines.append((list(x), list(y)))
        return plot(self, x, y, *args, **kwargs)

    def record_label(self, label, *args, **kwargs):  # type: ignore[no-untyped-def]
        labels.append(label)
        return xlabel(self, label, *args, **kwargs)

    monkeypatch.setattr(Axes, "plot", record_plot)
    monkeypatch.setattr(Axes, "set_xlabel", record_label)
    return lines, labels


@pytest.mark.parametrize(("key", "values", "factor", "unit"), [
    ("time.beta1", [0.5, 0.6], 1.0, ""),
    ("time.newton_max_it", [20, 40], 1.0, ""),
    ("time.dt", [1e-4, 5e-5], 1e3, "ms"),
    ("loads.impact.duration", [1e-3, 2e-3], 1e3, "ms"),
])
def test_axes_show_the_table_in_their_unit(tmp_path: pathlib.Path,
                                           monkeypatch: pytest.MonkeyPatch, key: str,
                                           values: list[float], factor: float,
                                           unit: str) -> None:
    study_file = tmp_path / "study.toml"
    study_file.write_text(f'base = "goda"\n[grid]\n"{key}" = {values}\n'
                          '[figures]\ny = ["time_of_max_ux"]\n')
    study = load_study(study_file)
    times = [0.0289, 0.0301]  # s: drawn in ms
    with open(tmp_path / "sweep.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["case", "folder", key, "status", "time_of_max_ux"])
        for j, (v, t) in enumerate(zip(values, times, strict=True)):
            w.writerow([j, f"case-{j:04d}", repr(v), "finished", repr(t)])
    lines, labels = _drawn(monkeypatch)
    assert len(make_figures(tmp_path, study)) == 1
    (x, y), = lines
    pairs = sorted(zip(values, times, strict=True))
    assert x == pytest.approx([v * factor for v, _ in pairs], rel=1e-15)
    assert y == pytest.approx([t * 1e3 for _, t in pairs], rel=1e-15)
    assert labels == [f"{key} ({unit})" if unit else key]


def test_redraw_checks_the_study(tmp_path: pathlib.Path,
                                 capsys: pytest.CaptureFixture[str]) -> None:
    # ``python -m breakwater.studies.plots``: a [figures] column misspelt after the study
    # ran drew nothing and exited 0; a missing study file was a traceback. Now both are
    # one line, exit 2, as sweep's refusals.
    from breakwater.studies.plots import main

    study_file = tmp_path / "study.toml"
    study_file.write_text('base = "goda"\n[grid]\n"time.dt" = [1e-4, 5e-5]\n'
                          '[figures]\ny = ["residual_slp"]\n')
    (tmp_path / "sweep.csv").write_text("case,folder,time.dt,status,residual_slip\n"
                                        "0,case-0000,0.0001,finished,0.001\n")
    assert main([str(study_file), str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "figures.y: 'residual_slp'" in err, err
    assert main([str(tmp_path / "none.toml"), str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "study file not found" in err, err
    assert not (tmp_path / "figures").exists()
