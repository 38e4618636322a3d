"""Compare the Goda case meshed separately with the conforming (default) run.

    python examples/goda_nonmatching/compare.py            # runs both, then compares
    python examples/goda_nonmatching/compare.py --no-run   # compares the runs already made

Runs ``python -m breakwater run`` (the built-in goda case) and
``python -m breakwater run examples/goda_nonmatching.toml`` in subprocesses (outputs
in ``results/compare_conforming`` and ``results/compare_nonmatching``, or ``--runs
DIR``), then writes beside this script ``comparison.md`` (the headline results of both
``summary.json`` side by side with their relative differences, and the solver's cost)
and ``gauges.png`` (the two gauge histories overlaid).

The non-matching case measures its corners with point probes: its corner slip and
opening are computed from point probes on both sides of the corner,
slip = u_x(caisson) − u_x(mound) and opening = u_y(caisson) − u_y(mound), the pair
probes' definitions on this horizontal interface (``breakwater/probes.py``: slave
minus master along t = (n_y, −n_x) and n = +y); for the conforming run they are the
pair probes' columns.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import subprocess
import sys
from collections.abc import Callable
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
CASE = HERE.parent / "goda_nonmatching.toml"
GAUGES = ("gauge_top", "gauge_bottom")
CORNERS = ("corner_front", "corner_rear")


def read_history(path: pathlib.Path) -> dict[str, np.ndarray]:
    """The columns of a ``history.csv``."""
    with open(path, encoding="utf-8") as f:
        header = f.readline().strip().split(",")
        data = np.loadtxt(f, delimiter=",", ndmin=2)
    return {name: data[:, j] for j, name in enumerate(header)}


def corner(h: dict[str, np.ndarray], name: str) -> tuple[np.ndarray, np.ndarray]:
    """Slip and opening histories at a base corner (caisson minus mound)."""
    if f"{name}_slip" in h:  # a pair probe (conforming run)
        return h[f"{name}_slip"], h[f"{name}_opening"]
    return (h[f"{name}_caisson_ux"] - h[f"{name}_mound_ux"],
            h[f"{name}_caisson_uy"] - h[f"{name}_mound_uy"])


def headline(run: pathlib.Path) -> tuple[dict[str, float | None], dict[str, Any],
                                         dict[str, np.ndarray]]:
    """The compared results of a run (SI units), its summary and its history."""
    summary = json.loads((run / "summary.json").read_text(encoding="utf-8"))
    h = read_history(run / "history.csv")
    d = summary["dynamic"]
    out: dict[str, float | None] = {}
    for g in GAUGES:
        out[f"peak u_x {g} (mm)"] = 1e3 * d["peak_ux"][g]["value"]
        out[f"residual u_x {g} (mm)"] = 1e3 * d["residual_ux"][g]
    out["time of max u_x (s)"] = d["time_of_max_ux"]
    slips = {c: corner(h, c) for c in CORNERS}
    out["residual slip corner_front (mm)"] = 1e3 * float(slips["corner_front"][0][-1])
    out["max uplift (mm)"] = 1e3 * max(float(o.max()) for _, o in slips.values())
    static = summary.get("static") or {}
    p = static.get("mean_contact_pressure")
    if p is None and "interface_force_y" in h:  # a general pair: its first history row
        p = float(h["interface_force_y"][0] / h["interface_contact_length"][0])
    out["static mean contact pressure (Pa)"] = p
    return out, summary, h


def relative(a: float | None, b: float | None) -> str:
    """(b − a)/|a| in per cent, or a dash."""
    if a is None or b is None or a == 0:
        return "—"
    return f"{100.0 * (b - a) / abs(a):+.2f} %"


def number(x: float | None, fmt: str = ".4g") -> str:
    """A number in ``fmt``, or a dash for None."""
    return "—" if x is None else format(x, fmt)


def cost(summary: dict[str, Any]) -> dict[str, str]:
    """The solver's figures of a run."""
    s = summary["solver"]
    loop = s.get("time_loop", {})
    steps = max(s["steps"], 1)
    search = loop.get("contact_search")
    return {
        "steps": str(s["steps"]),
        "Newton iterations: mean / max": f"{s['mean_newton_iterations']:.2f} / "
                                         f"{s['max_newton_iterations']}",
        "failed steps / cut-backs": f"{s['failed_steps']} / {s['cutbacks']}",
        "wall time of the run (s)": f"{s['wall_time']:.1f}",
        "time loop: wall / CPU (s)": f"{number(loop.get('wall'), '.1f')} / "
                                     f"{number(loop.get('cpu'), '.1f')}",
        "interface assembly per step (ms)":
            number(1e3 * loop["interface_assembly"] / steps if "interface_assembly" in loop
                   else None, ".2f"),
        "contact search per step (ms)": number(
            1e3 * search / steps if search is not None else None, ".2f"),
        "contact search per Newton iteration (ms)": number(
            1e3 * search / max(s["newton_iterations"], 1) if search is not None else None,
            ".3f"),
        "contact search / time loop (wall)": number(
            100 * search / loop["wall"] if search is not None and loop.get("wall")
            else None, ".1f") + (" %" if search is not None else ""),
    }


def write_table(conforming: pathlib.Path, nonmatching: pathlib.Path,
                target: pathlib.Path, note: str) -> str:
    """Write the Markdown comparison; returns its text."""
    a, sa, _ = headline(conforming)
    b, sb, _ = headline(nonmatching)
    kind = (sb.get("static") or {}).get("initial_state")
    warn = [] if kind not in (None, "undeformed") else [
        "", "The non-matching run has **no static initial state**: it starts from the "
        "undeformed state at rest and settles under gravity while the pendulum strikes, "
        "so its results are not comparable with the conforming run's (which starts from "
        "the static equilibrium): this table is **provisional**."]
    lines = [
        "# Goda case: conforming mesh against the bodies meshed separately", "",
        f"Conforming: `{conforming}` (the built-in goda case). Non-matching: "
        f"`{nonmatching}` (`examples/goda_nonmatching.toml`: caisson elements 15.6 mm, "
        "mound 26.5 mm, general pair caisson_base → mound_crest). Written by "
        "`examples/goda_nonmatching/compare.py`." + (f" {note}" if note else ""),
        *warn, "",
        "| result | conforming | non-matching | difference |", "|---|---|---|---|",
    ]
    for key, va in a.items():
        vb = b[key]
        lines.append(f"| {key} | {number(va)} | {number(vb)} | {relative(va, vb)} |")
    lines += ["", "Solver (fast path; wall times on a shared machine):", "",
              "| | conforming | non-matching |", "|---|---|---|"]
    ca, cb = cost(sa), cost(sb)
    for key in ca:
        lines.append(f"| {key} | {ca[key]} | {cb[key]} |")
    text = "\n".join(lines) + "\n"
    target.write_text(text, encoding="utf-8")
    return text


def plot(conforming: pathlib.Path, nonmatching: pathlib.Path, target: pathlib.Path) -> None:
    """Overlay the two runs' gauge histories (and the corner slip)."""
    ha, hb = read_history(conforming / "history.csv"), read_history(nonmatching / "history.csv")
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4))
    for g, colour in zip(GAUGES, ("C0", "C1"), strict=True):
        ax.plot(1e3 * ha["t"], 1e3 * ha[f"{g}_ux"], colour, label=f"{g}, conforming")
        ax.plot(1e3 * hb["t"], 1e3 * hb[f"{g}_ux"], colour, ls="--",
                label=f"{g}, non-matching")
    ax.set(xlabel="t (ms)", ylabel="u_x (mm)", title="Gauge displacements")
    ax.legend(fontsize=8)
    for c, colour in zip(CORNERS, ("C2", "C3"), strict=True):
        bx.plot(1e3 * ha["t"], 1e3 * corner(ha, c)[0], colour, label=f"{c}, conforming")
        bx.plot(1e3 * hb["t"], 1e3 * corner(hb, c)[0], colour, ls="--",
                label=f"{c}, non-matching")
    bx.set(xlabel="t (ms)", ylabel="slip (mm)", title="Slip at the base corners")
    bx.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(target, dpi=120)
    plt.close(fig)


def run(args: list[str], out: pathlib.Path) -> None:
    """``python -m breakwater run ARGS --out OUT`` in a subprocess."""
    cmd = [sys.executable, "-m", "breakwater", "run", *args, "--out", str(out),
           "--no-progress"]
    print("$", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)


def main(argv: list[str] | None = None,
         runner: Callable[[list[str], pathlib.Path], None] = run) -> str:
    """Run (unless ``--no-run``) and compare; returns the Markdown text."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--runs", type=pathlib.Path, default=pathlib.Path("results"),
                   help="folder of the two runs (default: results)")
    p.add_argument("--no-run", action="store_true", help="compare the runs already made")
    p.add_argument("--out", type=pathlib.Path, default=HERE,
                   help="folder of comparison.md and gauges.png (default: beside this file)")
    p.add_argument("--note", default="", help="a line added to the table's heading")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="an override for both runs (e.g. time.end_time=0.05)")
    args = p.parse_args(argv)
    conforming, nonmatching = args.runs / "compare_conforming", args.runs / "compare_nonmatching"
    sets = [x for s in args.set for x in ("--set", s)]
    if not args.no_run:
        runner(sets, conforming)
        runner([str(CASE), *sets], nonmatching)
    args.out.mkdir(parents=True, exist_ok=True)
    text = write_table(conforming, nonmatching, args.out / "comparison.md", args.note)
    plot(conforming, nonmatching, args.out / "gauges.png")
    print(text)
    return text


if __name__ == "__main__":
    main()
