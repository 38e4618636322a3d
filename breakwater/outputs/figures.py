"""Figures of a run, drawn from its output files only (so they can be remade later).

:func:`make_figures` reads ``history.csv``, ``summary.json``, ``static.npz`` and
``snapshot_max_ux.npz`` of an output directory and writes PNG files in its
``figures/`` folder, with matplotlib's object API (no pyplot, no display needed):

- ``probes_ux.png``: horizontal displacement of the probes (the gauges, paper Fig. 18);
- ``pair_probes_ux.png``: horizontal displacement of both sides of each interface
  probe and their slip (the caisson corner and the nearest mound node, Fig. 19);
- ``pair_probes_uy.png``: vertical displacement of both sides and the opening (Fig. 21);
- ``energy.png``: the energy ledger (with the numerical dissipation) and its balance error;
- ``contact.png``: contact length, normal and tangential resultants, Newton iterations;
- ``static_uy.png``, ``static_syy.png``: static vertical displacement and vertical
  stress (Figs. 16-17);
- ``static_pressure.png``: static contact pressure along each interface (Fig. 17; a
  general pair's at its slave surface's nodes);
- ``max_ux_deformed.png``: deformed shape (×20) coloured by σ_yy at the instant of the
  largest horizontal displacement of the first probe (Figs. 20, 22);
- a storm's ``storm_sliding.png`` and ``storm_sliding_per_wave.png`` (from ``waves.csv``:
  :func:`breakwater.outputs.stormrecord.storm_figures`).

Usage: ``python -m breakwater.outputs.figures <output directory>``.
"""

from __future__ import annotations

import contextlib
import json
import pathlib
import re
import sys
from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.tri import Triangulation

from breakwater.common.files import (
    FIGURES,
    HISTORY,
    SNAPSHOT,
    STATIC,
    SUMMARY,
    per_metre,
    read_history,
    temporary_path,
    writing,
)
from breakwater.common.plotstyle import default_style
from breakwater.outputs.section import mid_row
from breakwater.outputs.stormrecord import storm_figures

__all__ = ["make_figures"]

LEDGER = ("kinetic", "strain", "penalty", "rayleigh_dissipation", "friction_dissipation",
          "external_work", "balance_error")
# Ledger entries plotted when present (histories written before they existed lack them).
NUMERICAL = ("numerical_dissipation", "numerical_dissipation_contact")
#: The meshes of the paper's model (the summary's ``mesh.source``): their figures' titles
#: refer to the paper's.
PAPER = ("goda",)


def _save(fig: Figure, path: pathlib.Path) -> pathlib.Path:
    """Save atomically (temporary file with the same suffix, then rename)."""
    tmp = temporary_path(path)
    with writing(path):
        try:
            fig.savefig(tmp, dpi=150, bbox_inches="tight")
            tmp.replace(path)
        except OSError:
            with contextlib.suppress(OSError):
                tmp.unlink()
            raise
    return path


def _names(columns: Sequence[str], suffix: str) -> list[str]:
    """Prefixes of the columns ending with ``suffix``."""
    return [c[: -len(suffix)] for c in columns if c.endswith(suffix)]


def _time_axis(ax: Any, t: np.ndarray, t_peak: float | None = None) -> None:
    ax.set_xlabel("t (s)")
    ax.set_xlim(t[0], t[-1] if len(t) > 1 else t[0] + 1.0)
    if t_peak is not None:
        ax.axvline(t_peak, color="0.6", lw=0.8, ls=":")
    ax.grid(True, lw=0.3)
    ax.label_outer()  # time label on the bottom plot of a column only


def _cf(summary: dict[str, Any], figure: str) -> str:
    """`` (cf. paper Fig. N)`` for a run on the paper's Goda mesh, else nothing.

    A user's own geometry is not the paper's model (its titles said "cf. paper Fig. 17").
    """
    return f" (cf. paper {figure})" if summary.get("mesh", {}).get("source") in PAPER else ""


def _probes(h: dict[str, np.ndarray], t_peak: float | None, path: pathlib.Path,
            cf: str = "") -> pathlib.Path | None:
    names = [n for n in _names(list(h), "_ux")
             if f"{n}_uy" in h and not n.endswith(("_slave", "_master"))]
    if not names:
        return None
    fig = Figure(figsize=(7, 4))
    ax = fig.subplots()
    for n in names:
        ax.plot(h["t"], 1e3 * h[f"{n}_ux"], label=n)
    ax.set_ylabel("horizontal displacement $u_x$ (mm)")
    ax.set_title(f"Probe displacements{cf}")
    _time_axis(ax, h["t"], t_peak)
    ax.legend()
    return _save(fig, path)


def _pair_probes(h: dict[str, np.ndarray], t_peak: float | None, component: str,
                 path: pathlib.Path, paper: bool = False) -> pathlib.Path | None:
    names = _names(list(h), "_slip")
    if not names:
        return None
    relative, label, fig_no = (("slip", "slip", 19) if component == "x"
                               else ("opening", "opening", 21))
    fig = Figure(figsize=(7, 3.2 * len(names)))
    axes = np.atleast_1d(fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0])
    for ax, n in zip(axes, names, strict=True):
        for side, style in (("slave", "-"), ("master", "--")):
            key = f"{n}_{side}_u{component}"
            if key in h:
                ax.plot(h["t"], 1e3 * h[key], style, label=f"{side}")
        ax.plot(h["t"], 1e3 * h[f"{n}_{relative}"], "k", lw=0.9, label=label)
        ax.set_ylabel(f"$u_{component}$ (mm)")
        ax.set_title(f"{n}: {'horizontal' if component == 'x' else 'vertical'} "
                     f"displacement" + (f" (cf. paper Fig. {fig_no})" if paper else ""))
        _time_axis(ax, h["t"], t_peak)
        ax.legend()
    return _save(fig, path)


def _energy(h: dict[str, np.ndarray], path: pathlib.Path, per: str) -> pathlib.Path | None:
    if not all(k in h for k in LEDGER):
        return None
    fig = Figure(figsize=(7, 6))
    ax, bx = fig.subplots(2, 1, sharex=True, height_ratios=(3, 1))
    for k in (*LEDGER[:-1], *(k for k in NUMERICAL if k in h)):
        ax.plot(h["t"], h[k], ":" if k == NUMERICAL[1] else "-", label=k.replace("_", " "))
    stored = h["kinetic"] + h["strain"] + h["penalty"]
    ax.plot(h["t"], stored - stored[0], "k--", lw=0.8, label="stored − stored(0)")
    ax.set_ylabel(f"energy (J{per})")
    ax.set_title("Energy ledger")
    ax.legend(fontsize=7)
    _time_axis(ax, h["t"])
    bx.plot(h["t"], h["balance_error"], "r")
    bx.set_ylabel(f"balance error (J{per})")
    _time_axis(bx, h["t"])
    return _save(fig, path)


def _contact(h: dict[str, np.ndarray], path: pathlib.Path, per: str) -> pathlib.Path | None:
    # The conforming pairs: those with a normal and a tangential resultant.
    pairs = [n.removesuffix("_tangential_force") for n in h if n.endswith("_tangential_force")]
    fig = Figure(figsize=(7, 8))
    axes = fig.subplots(4, 1, sharex=True)
    for name in pairs:
        axes[0].plot(h["t"], h[f"{name}_contact_length"], label=name)
        axes[1].plot(h["t"], h[f"{name}_normal_force"], label=name)
        axes[2].plot(h["t"], h[f"{name}_tangential_force"], label=name)
    axes[0].set_ylabel("contact length (m)" if per else "contact area (m²)")  # per: 2D
    axes[1].set_ylabel(f"normal force (N{per})")
    axes[2].set_ylabel(f"tangential force (N{per})")
    axes[3].step(h["t"], h["newton_iterations"], where="pre", color="k", lw=0.8)
    axes[3].set_ylabel("Newton iterations")
    ax_dt = axes[3].twinx()
    ax_dt.step(h["t"][1:], h["dt"][1:], where="pre", color="C3", lw=0.8)
    ax_dt.set_ylabel("Δt (s)", color="C3")
    ax_dt.set_ylim(0.0, 1.1 * float(h["dt"].max()) if h["dt"].max() > 0 else 1.0)
    axes[0].set_title("Contact resultants and solver")
    for ax in axes:
        _time_axis(ax, h["t"])
    if pairs:
        axes[0].legend()
    return _save(fig, path)


def _triangulations(data: Any, scale: float = 0.0
                    ) -> list[tuple[str, Triangulation, dict[str, np.ndarray]]]:
    out = []
    for name in (str(b) for b in data["bodies"]):
        if len(data[f"{name}_triangles"]) == 0:  # a 3D body the section misses
            continue
        x = data[f"{name}_x"]
        dx = scale * np.column_stack([data[f"{name}_ux"], data[f"{name}_uy"]])
        xy = x + dx
        tri = Triangulation(xy[:, 0], xy[:, 1], data[f"{name}_triangles"])
        fields = {k: data[f"{name}_{k}"] for k in ("ux", "uy", "von_mises", "stress_yy")}
        out.append((name, tri, fields))
    return out


def _contours(data: Any, field: str, factor: float, label: str, title: str,
              path: pathlib.Path, scale: float = 0.0, outline: bool = False,
              cmap: str = "viridis") -> pathlib.Path | None:
    bodies = _triangulations(data, scale)
    if not bodies:  # a 3D section that misses every body: no figure
        return None
    values = np.concatenate([f[field] for _, _, f in bodies]) * factor
    lo, hi = float(values.min()), float(values.max())
    if hi <= lo:
        hi = lo + max(abs(lo), 1.0) * 1e-6
    levels = np.linspace(lo, hi, 21)
    fig = Figure(figsize=(8, 4))
    ax = fig.subplots()
    sets = [ax.tricontourf(tri, f[field] * factor, levels=levels, cmap=cmap)
            for _, tri, f in bodies]
    for _, tri, _ in bodies:
        ax.triplot(tri, color="k", lw=0.1, alpha=0.3)
    if outline:
        for _, tri, _ in _triangulations(data, 0.0):
            ax.triplot(tri, color="0.5", lw=0.2, ls=":")
    fig.colorbar(sets[0], ax=ax, label=label, shrink=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title)
    return _save(fig, path)


#: A conforming pair's history columns before they were named by the pair (issue 21):
#: ``<quantity>_<k>``, read as ``<k>_<quantity>``.
_LEGACY_COLUMN = re.compile(r"^(contact_length|normal_force|tangential_force|penetration)_(\d+)$")
#: Snapshot keys before ``contact_<name>_<field>``: ``pair<k>_<field>``, ``surface_<name>_<field>``.
_LEGACY_KEY = re.compile(r"^(?:pair(\d+)|surface_(.+))_(x|normal|gap|slip|pressure)$")


def _legacy_columns(h: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """A history written before the pair-named columns, with the pair-named columns."""
    renamed = {}
    for column, values in h.items():
        m = _LEGACY_COLUMN.match(column)
        renamed[f"{m[2]}_{m[1]}" if m else column] = values
    return renamed


def _pair_arrays(data: Any) -> dict[str, dict[str, np.ndarray]]:
    """The snapshot's arrays of each pair, by pair name (old snapshot keys read too)."""
    if "contacts" in data.files:
        return {str(n): {f: data[f"contact_{n}_{f}"] for f in ("x", "pressure")}
                for n in data["contacts"]}
    pairs: dict[str, dict[str, np.ndarray]] = {}
    for key in data.files:
        m = _LEGACY_KEY.match(key)
        if m:
            pairs.setdefault(m[1] if m[1] is not None else m[2], {})[m[3]] = data[key]
    return {n: a for n, a in pairs.items() if "x" in a and "pressure" in a}


def _static_pressure(data: Any, summary: dict[str, Any], path: pathlib.Path
                     ) -> pathlib.Path | None:
    # Every pair's nodal state, contact_<name>_* (a general pair's on its slave).
    pairs = _pair_arrays(data)
    if not pairs:
        return None
    fig = Figure(figsize=(7, 4))
    ax = fig.subplots()
    section = ""
    for name, arrays in pairs.items():
        x, pressure = arrays["x"], arrays["pressure"]
        if f"contact_{name}_row_x" in data.files:  # 3D triangles: the facets' cut
            x, pressure = data[f"contact_{name}_row_x"], data[f"contact_{name}_row_pressure"]
            section = f" at z = {float(x[:, 2].mean()):.4g} m"
        elif x.shape[1] == 3:  # 3D: the nodes of the row nearest the interface's mid z
            row = mid_row(x)
            section = f" at z = {float(x[row, 2].mean()):.4g} m"
            x, pressure = x[row], pressure[row]
        # Abscissa along the interface: x for a horizontal one, else the arc length.
        span = np.ptp(x, axis=0)
        s = x[:, 0] if span[0] >= span[1] else x[:, 1]
        order = np.argsort(s)
        ax.plot(s[order], pressure[order], "o-", ms=3, label=f"contact {name}{section}")
    static = summary.get("static", {})
    mean = static.get("mean_contact_pressure")
    if mean is not None:
        ax.axhline(mean, color="k", ls="--", lw=0.8, label=f"mean {mean:.4g} Pa")
    ax.set_xlabel("position along the interface (m)")
    ax.set_ylabel("contact pressure (Pa)")
    ax.set_title("Static contact pressure" + _cf(summary, "Fig. 17"))
    ax.grid(True, lw=0.3)
    ax.legend()
    return _save(fig, path)


@default_style
def make_figures(directory: str | pathlib.Path, scale: float = 20.0) -> list[pathlib.Path]:
    """Draw every figure of a run whose outputs are in ``directory``.

    Args:
        directory: The run's output directory.
        scale: Displacement magnification of the deformed-shape figure.

    Returns:
        The figures written (in ``directory/figures``).
    """
    directory = pathlib.Path(directory)
    folder = directory / FIGURES
    folder.mkdir(exist_ok=True)
    summary: dict[str, Any] = {}
    if (directory / SUMMARY).is_file():
        summary = json.loads((directory / SUMMARY).read_text(encoding="utf-8"))
    t_peak = summary.get("dynamic", {}).get("time_of_max_ux")
    per = per_metre(summary)
    drawn: list[pathlib.Path | None] = []
    if (directory / HISTORY).is_file():
        h = _legacy_columns(read_history(directory / HISTORY))
        if len(h.get("t", ())) > 0:
            paper = bool(_cf(summary, ""))
            drawn += [_probes(h, t_peak, folder / "probes_ux.png", _cf(summary, "Fig. 18")),
                      _pair_probes(h, t_peak, "x", folder / "pair_probes_ux.png", paper),
                      _pair_probes(h, t_peak, "y", folder / "pair_probes_uy.png", paper),
                      _energy(h, folder / "energy.png", per),
                      _contact(h, folder / "contact.png", per)]
    if (directory / STATIC).is_file():
        with np.load(directory / STATIC) as data:
            drawn += [
                _contours(data, "uy", 1e3, "$u_y$ (mm)",
                          "Static vertical displacement" + _cf(summary, "Fig. 16"),
                          folder / "static_uy.png"),
                _contours(data, "stress_yy", 1.0, r"$\sigma_{yy}$ (Pa)",
                          "Static vertical stress" + _cf(summary, "Fig. 17"),
                          folder / "static_syy.png", cmap="viridis_r"),
                _static_pressure(data, summary, folder / "static_pressure.png"),
            ]
    if (directory / SNAPSHOT).is_file():
        with np.load(directory / SNAPSHOT) as data:
            t = float(data["time"])
            drawn.append(_contours(
                data, "stress_yy", 1.0, r"$\sigma_{yy}$ (Pa)",
                f"Deformed shape (×{scale:g}) and vertical stress at t = {t:.4g} s\n"
                "(largest $u_x$ of the first probe" + (
                    "; cf. paper Figs. 20, 22)" if _cf(summary, "") else ")"),
                folder / "max_ux_deformed.png", scale=scale, outline=True, cmap="viridis_r"))
    drawn += storm_figures(directory, folder)
    return [p for p in drawn if p is not None]


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m breakwater.outputs.figures DIR``: redraw a run's figures.

    A folder without a run's outputs (none, or a study's folder) is one line on
    stderr, exit 2 (it was a traceback, or nothing drawn and exit 0).
    """
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) != 1:
        print("usage: python -m breakwater.outputs.figures <output directory>",
              file=sys.stderr)
        return 2
    directory = pathlib.Path(args[0])
    if not any((directory / name).is_file() for name in (SUMMARY, HISTORY, SNAPSHOT)):
        print(f"breakwater: error: {directory}: no run outputs ({SUMMARY}, {HISTORY}): "
              "give a run's --out folder (a study's: one of its case-* folders)",
              file=sys.stderr)
        return 2
    for p in make_figures(directory):
        print(p)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
