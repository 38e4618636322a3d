"""Figures of a study: its headline numbers against each varied key, from ``sweep.csv``.

:func:`make_figures` draws, for each x column (``[figures] x`` of the study file, by
default every numeric varied key), one PNG ``figures/vs_<x>.png`` with a panel per
headline number (``[figures] y``, by default the time of the largest displacement,
the residual slip, the peak and residual ``ux`` of each probe and the uplift). The
finished cases are drawn as lines against x, one line per value of the other varied
keys (colour: the first of them; line style: the others), so a 2-D grid gives a line
per value of its second key. ``[figures] reference`` marks values (e.g. the paper's):
a horizontal line in the panel of a y column, a vertical line in every panel when it
names the x column; ``reference_label`` names them in the legend (default "reference").
Displacements are shown in mm, times in ms, moduli in MPa.

Usage: ``python -m breakwater.studies.plots STUDY.toml DIR`` redraws them.
"""

from __future__ import annotations

import csv
import itertools
import math
import pathlib
import sys
from collections.abc import Mapping, Sequence
from typing import Any

from matplotlib.figure import Figure

from breakwater.common.errors import CaseError
from breakwater.common.files import temporary_path
from breakwater.common.plotstyle import default_style
from breakwater.studies.studyfile import Study, check_points, load_study

__all__ = ["make_figures", "read_table"]

DEFAULT_Y = ("time_of_max_ux", "residual_slip", "peak_ux.", "residual_ux.", "max_uplift")
STYLES = ("-", "--", ":", "-.")


def _scale(column: str) -> tuple[float, str]:
    """Display factor and unit of a column.

    Times in ms: the headline times (``time_of_max_ux``, ``time_peak_ux.<p>``,
    ``time_reached``) and the case keys that are times (``time.dt``,
    ``time.end_time``, a load's ``duration`` and ``start``); not the other keys of
    ``[time]`` (``time.beta1``, ``time.newton_max_it``: they were drawn × 1000 as ms).
    """
    last = column.rsplit(".", 1)[-1]
    name = column.split(".", 1)[0]
    if name.startswith("time_") or last in ("duration", "start", "dt", "end_time"):
        return 1e3, "ms"
    if name in ("peak_ux", "residual_ux", "residual_slip", "max_uplift") \
            or last in ("bolt_height",):
        return 1e3, "mm"
    if "modulus" in column:
        return 1e-6, "MPa"
    return 1.0, ""


def _number(text: str) -> float | None:
    try:
        value = float(text)
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) else None


def _label(column: str) -> str:
    unit = _scale(column)[1]
    return f"{column} ({unit})" if unit else column


def _text(value: str) -> str:
    x = _number(value)
    return f"{x:.4g}" if x is not None else value


def read_table(path: pathlib.Path) -> tuple[list[str], list[dict[str, str]]]:
    """Read ``sweep.csv``: its header and its rows."""
    with open(path, encoding="utf-8", newline="") as f:
        reader = csv.DictReader(f)
        rows = list(reader)
        return list(reader.fieldnames or []), rows


@default_style
def make_figures(directory: str | pathlib.Path, study: Study, table: str = "sweep.csv"
                 ) -> list[pathlib.Path]:
    """Draw the study's figures from ``directory/sweep.csv``; the files written."""
    directory = pathlib.Path(directory)
    header, rows = read_table(directory / table)
    done = [r for r in rows if r.get("status") == "finished"]
    if not done:
        return []
    spec = study.figures
    xs = list(spec.get("x") or [k for k in study.varied
                                if all(_number(r[k]) is not None for r in done)])
    ys = list(spec.get("y") or [c for c in header
                                if any(c == d or (d.endswith(".") and c.startswith(d))
                                       for d in DEFAULT_Y)])
    ys = [y for y in ys if y in header]
    reference: Mapping[str, Any] = spec.get("reference", {})
    ref_label = str(spec.get("reference_label", "reference"))
    out = directory / "figures"
    out.mkdir(exist_ok=True)
    drawn = []
    for x in xs:
        if x not in header or not ys:
            continue
        others = [k for k in study.varied if k != x]
        drawn.append(_figure(out / f"vs_{x.replace('.', '_')}.png", x, ys, others, done,
                             reference, ref_label, study.name))
    return drawn


def _marks(reference: Mapping[str, Any], column: str, label: str) -> list[tuple[float, str]]:
    value = reference.get(column)
    if value is None:
        return []
    if isinstance(value, Mapping):
        return [(float(v), str(k)) for k, v in value.items()]
    return [(float(value), label)]


def _figure(path: pathlib.Path, x: str, ys: Sequence[str], others: Sequence[str],
            rows: Sequence[Mapping[str, str]], reference: Mapping[str, Any],
            ref_label: str, title: str) -> pathlib.Path:
    ncols = 2 if len(ys) > 1 else 1
    nrows = math.ceil(len(ys) / ncols)
    fig = Figure(figsize=(5.2 * ncols, 3.4 * nrows), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    fx, _ = _scale(x)
    colour_key, style_keys = (others[0], others[1:]) if others else (None, [])
    colours = sorted({r[colour_key] for r in rows}, key=_sort) if colour_key else [""]
    styles = sorted({tuple(r[k] for k in style_keys) for r in rows}, key=lambda t: [
        _sort(v) for v in t])
    for ax, y in zip(axes, ys, strict=False):
        fy, _ = _scale(y)
        for (ci, c), (si, s) in itertools.product(enumerate(colours), enumerate(styles)):
            line = [r for r in rows if (colour_key is None or r[colour_key] == c)
                    and tuple(r[k] for k in style_keys) == s]
            pts: list[tuple[float, float]] = []
            for r in line:
                a, b = _number(r[x]), _number(r[y])
                if a is not None and b is not None:
                    pts.append((a, b))
            pts.sort()
            if not pts:
                continue
            parts = ([f"{colour_key.rsplit('.', 1)[-1]}={_text(c)}"] if colour_key else []) \
                + [f"{k.rsplit('.', 1)[-1]}={_text(v)}" for k, v in zip(style_keys, s,
                                                                         strict=True)]
            ax.plot([a * fx for a, _ in pts], [b * fy for _, b in pts], marker="o", ms=3,
                    color=f"C{ci % 10}", ls=STYLES[si % len(STYLES)], lw=1.0,
                    label=", ".join(parts) or None)
        for value, label in _marks(reference, y, ref_label):
            ax.axhline(value * fy, color="k", lw=1.0, ls="--", label=label)
        for value, label in _marks(reference, x, ref_label):
            ax.axvline(value * fx, color="0.4", lw=0.8, ls=":")
            ax.annotate(label, (value * fx, 1.0), xycoords=("data", "axes fraction"),
                        rotation=90, va="top", ha="right", fontsize=7, color="0.3")
        ax.set_xlabel(_label(x))
        ax.set_ylabel(_label(y))
        ax.grid(True, lw=0.3)
    for ax in axes[len(ys):]:
        ax.set_visible(False)
    handles, labels = axes[0].get_legend_handles_labels()
    for ax in axes[1:len(ys)]:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    if labels:
        fig.legend(handles, labels, loc="outside right upper", fontsize=7)
    fig.suptitle(f"{title}: against {x}", fontsize=10)
    tmp = temporary_path(path)
    fig.savefig(tmp, dpi=80)
    tmp.replace(path)
    return path


def _sort(value: str) -> tuple[int, float, str]:
    x = _number(value)
    return (0, x, "") if x is not None else (1, 0.0, value)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m breakwater.studies.plots STUDY.toml DIR``.

    The study is checked as ``sweep`` checks it (its ``[figures]`` columns included:
    a misspelt one drew nothing); a problem is one line on stderr, exit 2.
    """
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) != 2:
        print("usage: python -m breakwater.studies.plots STUDY.toml DIR", file=sys.stderr)
        return 2
    try:
        study = load_study(args[0])
        check_points(study, pathlib.Path(args[1]))
        if not (pathlib.Path(args[1]) / "sweep.csv").is_file():
            raise CaseError(f"{args[1]}: no sweep.csv (the study's --out folder?)")
    except CaseError as e:
        print(f"breakwater: error: {e}", file=sys.stderr)
        return 2
    for p in make_figures(args[1], study):
        print(p)
    return 0


if __name__ == "__main__":
    sys.exit(main())
