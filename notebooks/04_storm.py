# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: percent
#       format_version: '1.3'
#       jupytext_version: 1.19.6
#   kernelspec:
#     display_name: Python 3 (ipykernel)
#     language: python
#     name: python3
# ---

# %% [markdown]
# # A caisson through a storm, wave by wave, and its expected sliding
#
# Performance-based design of a caisson breakwater (Shimosako & Takahashi 1994, 1999;
# Goda & Takagi 2000) asks how far the caisson slides over a storm, not only whether
# the design wave moves it. This notebook, on the prototype of `examples/prototype/`
# (a caisson B = 30 m wide in h = 20 m of water on a rubble mound, μ = 0.6):
#
# 1. draws a storm's wave heights (H_1/3 = 8 m, T_1/3 = 14 s) from the Rayleigh
#    distribution, capped at the breaker height, and shows one wave's force history;
# 2. runs the finite-element model through a few waves of a wave table, the caisson on
#    its deformable mound, and compares each wave's sliding with the rigid-block model's
#    under the same load;
# 3. runs the rigid-block Monte Carlo over many storms: the expected sliding per storm,
#    its percentiles and the probability of exceeding a tolerable sliding.
#
# The finite-element Monte Carlo is a study: `mpiexec -n 2 python -m breakwater sweep
# examples/prototype/storms.toml` ([Storms](../storms.md)).
#
# | environment variable | default | meaning |
# |---|---|---|
# | `BREAKWATER_NOTEBOOK_STORMS` | `1000` | storms of the rigid-block Monte Carlo |
# | `BREAKWATER_NOTEBOOK_OUTPUT` | `results/notebook_storm` | output folder, relative to the working directory |

# %%
import os
import pathlib

STORMS = int(os.environ.get("BREAKWATER_NOTEBOOK_STORMS", "1000"))
OUT = pathlib.Path(os.environ.get("BREAKWATER_NOTEBOOK_OUTPUT", "results/notebook_storm"))
print(f"{STORMS} storms in the Monte Carlo, output folder {OUT}")

# %%
import dataclasses
import json

import breakwater  # first: it loads the PETSc of the dolfinx wheel (when installed)
import matplotlib.pyplot as plt
import numpy as np
from IPython.display import Markdown, display
from mpi4py import MPI

from breakwater.casefile.case import load_case
from breakwater.outputs.stormrecord import read_waves
from breakwater.run import simulation
from breakwater.storms.montecarlo import expected_sliding
from breakwater.storms.rigid import Caisson
from breakwater.storms.seastate import SeaState, wave_heights, wave_train
from breakwater.storms.waveforce import wave_load
from breakwater.storms.waves import Site

comm = MPI.COMM_WORLD

# %% [markdown]
# The site and the caisson of `examples/prototype/caisson.toml`, per metre of breakwater:
# Goda's geometry (h, h', d, h_c) and B.

# %%
EXAMPLES = next(p / "examples" / "prototype"
                for p in (pathlib.Path.cwd(), *pathlib.Path.cwd().parents,
                          pathlib.Path(breakwater.__file__).resolve().parents[1])
                if (p / "examples" / "prototype" / "caisson.toml").is_file())

# The site and the caisson of examples/prototype/caisson.toml (per metre of breakwater).
B, h, h1, d, hc = 30.0, 20.0, 14.5, 11.0, 5.0
SITE = Site(depth=h, toe_depth=h1, berm_depth=d, crest_height=hc, base_width=B)
SEA = SeaState(significant_height=8.0, significant_period=14.0, waves=1000, seed=0)

# %% [markdown]
# ## 1. A storm's waves and one wave's force
#
# The heights are drawn with `numpy.random.default_rng(seed)`:
# P(H > x) = exp[−2 (x/H_1/3)²] (Longuet-Higgins 1952; Goda 2000 §2.2), a height above
# the breaker height at the site capped there. Below, the storm's exceedance against
# Rayleigh's.

# %%
heights = wave_heights(SEA, SITE)
top = np.sort(heights.heights)[-len(heights.heights) // 3:]
print(f"H_1/3 of the drawn heights {top.mean():.2f} m (asked 8 m); highest "
      f"{heights.heights.max():.2f} m; {heights.broken} heights capped at the breaker "
      f"height {heights.limit:.2f} m")

# %%
H = np.sort(heights.heights)[::-1]
exceed = np.arange(1, len(H) + 1) / len(H)
x = np.linspace(0.0, H.max(), 200)
fig, ax = plt.subplots(figsize=(7, 3.5))
ax.semilogy(H, exceed, ".", ms=3, label=f"the storm (seed {SEA.seed}, {len(H)} waves)")
ax.semilogy(x, np.exp(-2 * (x / SEA.significant_height) ** 2), "k--", lw=1,
            label="Rayleigh, exp[−2 (H/H_1/3)²]")
ax.axvline(heights.limit, color="C3", lw=0.8, label=f"breaker height {heights.limit:.1f} m")
ax.set_xlabel("H (m)")
ax.set_ylabel("P(H > x)")
ax.set_ylim(0.5 / len(H), 1.0)
ax.legend()
plt.show()

# %% [markdown]
# Each wave's front pressure is Goda's for its own H and T, its time history a sine
# hump of Goda's p₁ over τ₀ = T/2 (the durations are this program's choice,
# [Storms](../storms.md)); the uplift under the base follows the same hump. The storm's
# highest wave:

# %%
train = wave_train(SEA, SITE)
highest = max(train.waves, key=lambda w: w.height)
load = wave_load(highest, SITE)
print(f"wave {train.waves.index(highest) + 1}: H = {highest.height:.2f} m, T = "
      f"{highest.period:g} s, peak p₁ = {load.p1.peak / 1e3:.1f} kPa, its force lasts "
      f"τ₀ = {load.duration:g} s")

# %%
τ = np.linspace(0.0, load.duration, 400)
fig, ax = plt.subplots(figsize=(7, 3))
ax.plot(τ, [load.p1(t) / 1e3 for t in τ], label="p₁(τ), front")
ax.plot(τ, [load.uplift(t) / 1e3 for t in τ], label="p_u(τ), uplift at the seaward edge")
ax.set_xlabel("τ, time since the wave's force began (s)")
ax.set_ylabel("kPa")
ax.legend()
plt.show()

# %% [markdown]
# ## 2. The finite-element model through a few waves
#
# `examples/prototype/storm.toml` runs a sea state of 100 waves (`[loads.storm.storm.sea]`).
# Here a wave table instead (`waves = [[H, T], ...]`): a moderate wave, the storm's
# highest, and a moderate one again, with the example's adaptive time steps. The
# caisson's state carries from wave to wave; `waves.csv` records each wave's sliding
# beside the rigid block's under the same load (the FE model's mass, its static normal
# force W' and μ).

# %%
waves = [[8.0, 14.0], [round(highest.height, 2), 14.0], [8.0, 14.0]]
case_text = f"""
extends = {json.dumps((EXAMPLES / "caisson.toml").as_posix())}
name = "notebook_storm"

[loads.wave]
enabled = false

[loads.storm]
group = "caisson_front"
groups = ["impact"]

[loads.storm.storm]
depth = {h}
toe_depth = {h1}
berm_depth = {d}
crest_height = {hc}
still_water_level = 20.0
uplift_group = "interface"
waves = {json.dumps(waves)}

[time]
dt = 0.25
end_time = {14.0 * len(waves)}
adaptive = true
tolerance = 1.0e-2

[output]
field_interval = 0
directory = {json.dumps((OUT / "fe").as_posix())}
"""
OUT.mkdir(parents=True, exist_ok=True)
(OUT / "storm.toml").write_text(case_text, encoding="utf-8")
print(f"waves (H, T): {waves}; the case: {OUT / 'storm.toml'}")

# %%
built = load_case(OUT / "storm.toml").build(comm)
model, time_spec, output_spec, extra = built
summary = simulation.run(model, time_spec, dataclasses.replace(output_spec, progress=False),
                         resolved_case=built.case.resolved(), extra_summary=extra)
s = summary["solver"]
print(f"{s['steps']} adaptive steps ({s['adaptive']['rejected_steps']} rejected), "
      f"{s['newton_iterations']} Newton iterations, {s['wall_time']:.1f} s")

# %%
w = read_waves(OUT / "fe" / "waves.csv")
rows = ["| wave | H (m) | peak force (kN/m) | sliding (mm) | rigid block (mm) | rocking (mrad) |",
        "|---|---|---|---|---|---|"]
for k in range(len(w["wave"])):
    rows.append(f"| {int(w['wave'][k])} | {w['height'][k]:.2f} | "
                f"{w['peak_force_per_length'][k] / 1e3:.0f} | {w['sliding'][k] * 1e3:.3g} | "
                f"{w['rigid_sliding'][k] * 1e3:.3g} | {w['rocking'][k] * 1e3:.3g} |")
display(Markdown("\n".join(rows)))
storm = summary["storm"]
print(f"total sliding {storm['total_sliding'] * 1e3:.3g} mm (the rigid block "
      f"{storm['rigid']['total_sliding'] * 1e3:.3g} mm)")

# %% [markdown]
# The rigid block does not move while μW' exceeds the wave's horizontal force. The
# caisson on its deformable mound rocks under the same force, its heel unloads, and
# its base slips where the normal force drops: its sliding need not be zero where the
# rigid block's is (the record measures it at mid-base). The run's per-wave figures are
# in `figures/` (`storm_sliding.png`, `storm_sliding_per_wave.png`).

# %% [markdown]
# ## 3. The expected sliding over storms (rigid-block Monte Carlo)
#
# Each storm is a seed: its heights, each wave's load, the rigid block's sliding under
# each (Shimosako & Takahashi's equation of motion, added mass 1.0855 ρh'²), summed.
# The mean over the storms is the expected sliding distance; the limits are the
# tolerable slidings of the performance design (0.1 and 0.3 m).

# %%
caisson = Caisson(mass=2100.0 * B * (h1 + hc), base_width=B, toe_depth=h1, friction=0.6)
result = expected_sliding(SEA, SITE, caisson, storms=STORMS, limits=(0.1, 0.3))
p = result.percentiles
print(f"{STORMS} storms of {SEA.count} waves: expected sliding {result.mean:.3f} m "
      f"± {result.half_width():.3f} m (95 %); percentiles 5/50/95: "
      f"{p[5.0]:.3f} / {p[50.0]:.3f} / {p[95.0]:.3f} m")
print("P(S > limit): " + ", ".join(f"{lim:g} m: {prob:.3g}"
                                   for lim, prob in result.exceedance.items()))
if result.std > 0:
    print(f"storms needed for the mean within ±10 % at 95 %: {result.storms_needed()}")

# %%
fig, ax = plt.subplots(figsize=(7, 3.5))
ax.hist(result.totals, bins=max(10, min(50, STORMS // 5)), color="0.7", edgecolor="0.3",
        lw=0.5)
ax.axvline(result.mean, color="C0", label=f"mean {result.mean:.3f} m")
for lim, style in zip(result.limits, ("--", ":"), strict=True):
    ax.axvline(lim, color="C3", ls=style, lw=0.9, label=f"tolerable {lim:g} m")
ax.set_xlabel("total sliding per storm (m)")
ax.set_ylabel("storms")
ax.legend()
plt.show()
