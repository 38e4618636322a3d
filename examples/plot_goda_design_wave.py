"""Draw the load of examples/goda_design_wave.toml: Goda's profile and the impact history.

    python examples/plot_goda_design_wave.py   (writes examples/figures/goda_design_wave_load.png)

The pressures come from the case itself (``load_case`` reads the Goda table and the CSV
history beside it), so the figure is what a run applies: the front pressure on the
caisson's seaward face and the uplift under its base at the factor 1, and the factor
in time.
"""

from __future__ import annotations

import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from breakwater.casefile.case import load_case

HERE = pathlib.Path(__file__).resolve().parent


def main() -> pathlib.Path:
    """Draw the figure; returns its path."""
    case = load_case(HERE / "goda_design_wave.toml")
    wave = next(ld for ld in case.loads if ld.name == "wave")
    goda = wave.goda
    assert goda is not None and wave.table is not None
    g = goda.pressure()
    geometry = case.mesh.goda
    base, top = geometry.mound_height, geometry.mound_height + geometry.caisson_height
    y = np.linspace(base, top - 1e-9, 400)  # (the crest point itself: round-off)
    profile = goda.front()  # p(s), s = y − still water level
    front = profile.pressure(profile.coordinate(np.column_stack([np.zeros_like(y), y])))
    history = wave.time_factor()
    t = np.linspace(0.0, case.time.end_time, 801)

    fig, (ax1, ax2, ax3) = plt.subplots(1, 3, figsize=(12, 3.8),
                                        gridspec_kw={"width_ratios": [1, 1.2, 1.6]})
    ax1.plot(front, y, "b")
    ax1.fill_betweenx(y, 0, front, alpha=0.2)
    ax1.axhline(goda.still_water_level, color="tab:cyan", lw=1, label="still water")
    ax1.set(xlabel="p (Pa)", ylabel="y (m)", title="front face (caisson_front)")
    ax1.legend(fontsize=8)
    width = geometry.caisson_width
    s = np.linspace(0.0, width, 50)
    ax2.plot(s, g.uplift * (1 - s / width), "r")
    ax2.fill_between(s, 0, g.uplift * (1 - s / width), color="r", alpha=0.2)
    ax2.set(xlabel="distance from the seaward edge (m)", ylabel="p (Pa)",
            title="uplift under the base (interface)")
    ax3.plot(t, [history(v) for v in t], "k")
    ax3.set(xlabel="t (s)", ylabel="factor (1 = Goda's design pressure)",
            title="history (goda_design_wave_impact.csv)")
    for ax in (ax1, ax2, ax3):
        ax.grid(lw=0.3)
    fig.suptitle(f"H_max = {goda.wave_height} m, T = {goda.period} s, h = {goda.depth} m: "
                 f"p1 = {g.p1:.0f} Pa, p3 = {g.p3:.0f} Pa, p4 = {g.p4:.0f} Pa, "
                 f"p_u = {g.uplift:.0f} Pa; P = {g.force:.0f} N/m, U = "
                 f"{g.uplift_force(width):.0f} N/m", fontsize=10)
    fig.tight_layout()
    out = HERE / "figures" / "goda_design_wave_load.png"
    out.parent.mkdir(exist_ok=True)
    fig.savefig(out, dpi=110)
    return out


if __name__ == "__main__":
    print(main())
