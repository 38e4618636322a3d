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
# # A user-defined variant: a flatter mound, the lowest bolt, a mound of your own
#
# The notebook `01_goda_paper_figures.py` reproduces the paper's case. Here a user
# changes it, with the same Python API:
#
# 1. the paper's case, as the reference;
# 2. a variant of the built-in geometry: the mound's side slopes flattened from 1:2 to
#    1:3 (V:H), and the pendulum striking the lowest of Goda's three bolts, 34 mm above
#    the caisson base, with its own cord length. It is made with case overrides, the
#    `key=value` strings of `--set` on the command line;
# 3. the comparison: peak displacement, residual slip, uplift;
# 4. a geometry the built-in generator does not make, a mound with a berm on the
#    seaward side, built with the gmsh Python API, written as a `.msh` file with named
#    physical groups and run through a case file that `extends` the built-in case;
# 5. a measured wave-pressure record read from a CSV file and applied to the caisson's
#    seaward face instead of the pendulum, beside Goda's design wave pressure.
#
# | environment variable | default | meaning |
# |---|---|---|
# | `BREAKWATER_NOTEBOOK_END_TIME` | `0.15` | final time (s); by 0.15 s the caisson has about come to rest |
# | `BREAKWATER_NOTEBOOK_REFINEMENT` | `1.0` | element sizes are divided by it (1: the paper's mesh) |
# | `BREAKWATER_NOTEBOOK_OUTPUT` | `results/notebook_variant` | output folder, relative to the working directory |

# %%
import os
import pathlib

# Short values make a quick run (the tests and the documentation build set them).
END_TIME = float(os.environ.get("BREAKWATER_NOTEBOOK_END_TIME", "0.15"))  # s
REFINEMENT = float(os.environ.get("BREAKWATER_NOTEBOOK_REFINEMENT", "1.0"))
OUT = pathlib.Path(os.environ.get("BREAKWATER_NOTEBOOK_OUTPUT",
                                  "results/notebook_variant"))
print(f"end time {END_TIME} s, refinement {REFINEMENT}, output folder {OUT}")

# %%
import dataclasses
import json
import math

import breakwater  # first: it loads the PETSc of the dolfinx wheel (when installed)
import gmsh
import matplotlib.pyplot as plt
import numpy as np
from IPython.display import Image, Markdown, display
from mpi4py import MPI

from breakwater import meshes
from breakwater.casefile.case import load_case
from breakwater.common.gmshtools import gmsh_session
from breakwater.meshes import GodaGeometry
from breakwater.outputs.writers import read_history
from breakwater.run import simulation
from breakwater.statics.calibrate import HorizontalStiffness

comm = MPI.COMM_WORLD


def common(folder, figures=False, refine=True):
    # Overrides shared by every run of this notebook (refine=False: a mesh file, which
    # berm_mesh refines itself; mesh.refinement refines the built-in mesh only).
    return [f"time.end_time={END_TIME}",
            *([f"mesh.refinement={REFINEMENT}"] if refine else []),
            f"output.directory={json.dumps((OUT / folder).as_posix())}",
            f"output.figures={str(figures).lower()}"]


def run(case):
    # Build and run a case; its summary (also in <output>/summary.json).
    built = case.build(comm)  # built.case: the case as run (calibrated modulus written in)
    model, time_spec, output_spec, extra = built
    output_spec = dataclasses.replace(output_spec, progress=False)
    return simulation.run(model, time_spec, output_spec,
                          resolved_case=built.case.resolved(), extra_summary=extra)


def sway_stiffness(case, shear_modulus):
    # Goda's K_x (N/m) of the case's caisson with this mound shear modulus.
    model = case.build_model(case.read_mesh(comm), {"mound": shear_modulus},
                             dynamic=False)
    k = HorizontalStiffness(model, "caisson", case.calibration.tangential_penalty)()
    return k * case.out_of_plane_length


# %% [markdown]
# ## 1. The reference: the paper's case
#
# The built-in case calibrates the mound's shear modulus $G$ so that the caisson's
# horizontal stiffness is Goda's $K_x$ = 500 kN/m. The gravel is the same in every
# variant below, so this $G$ is kept for them: a new geometry then changes $K_x$
# (re-calibrating it to 500 kN/m would model a different gravel).

# %%
reference = load_case(None, common("goda"))
summary_ref = run(reference)
G = summary_ref["calibration"]["shear_modulus"]
K_ref = summary_ref["calibration"]["stiffness"] * reference.out_of_plane_length
print(f"gravel: G = {G:.4g} Pa, K_x = {K_ref / 1e3:.1f} kN/m")

# %% [markdown]
# ## 2. The variant: a 1:3 mound, the pendulum on the lowest bolt
#
# Goda's pendulum hung from the ceiling; its three cord lengths, $l_0$ = 3.393, 3.46 and
# 3.527 m, were adjusted so that it struck each of the three bolts, $l_i$ = 168, 101 and
# 34 mm above the block base (paper §5.1). The pivot stays where it is, so $l_i + l_0$ is
# the same for the three: the longest cord goes with the lowest bolt. The paper's case
# is the 3.393 m cord on the 168 mm bolt; the variant takes the 3.527 m cord on the
# 34 mm bolt, which strikes a little slower (eq. 29) and much lower.

# %%
for l_i, l_0 in ((0.168, 3.393), (0.101, 3.46), (0.034, 3.527)):
    print(f"bolt {l_i * 1e3:3.0f} mm, cord {l_0:.3f} m: pivot {l_i + l_0:.3f} m above "
          "the block base")

variant = load_case(None, [
    *common("slope3_bolt34"),
    "name=slope3_bolt34",
    "mesh.goda.slope=3.0",                    # 1:3 (V:H) side slopes
    "mesh.goda.bolt_height=0.034",            # the lowest bolt
    "loads.impact.pendulum.cord_length=3.527",  # its cord
    f"bodies.mound.shear_modulus={G!r}",      # the reference's gravel ...
    "calibration.enabled=false",              # ... not re-calibrated
])
impact = {c.name: next(ld for ld in c.loads if ld.name == "impact")
          for c in (reference, variant)}
for c in (reference, variant):
    ld = impact[c.name]
    print(f"{c.name}: slopes 1:{c.mesh.goda.slope:g}, base {c.mesh.goda.base_width:.2f} m "
          f"wide, bolt {c.mesh.goda.bolt_height * 1e3:g} mm, ω = "
          f"{ld.pendulum.velocity:.4f} m/s, I = {ld.total_impulse:.3f} N s")

# %% [markdown]
# The overrides edit the case's `GodaGeometry`; the same geometry can be built
# directly, e.g. to check a design before running it (its properties give the points
# of interest):

# %%
geometry = GodaGeometry(slope=3.0, bolt_height=0.034)
assert geometry == variant.mesh.goda
print(f"impact point {geometry.impact_point}, gauges {geometry.gauge_top} and "
      f"{geometry.gauge_bottom}")


# %%
def plot_mesh(path, ax, title):
    # A gmsh mesh read with meshio, coloured by body, with its named points.
    m = meshes.read(path)
    triangles = m.cells_dict["triangle"]
    for body, color in (("mound", "tab:brown"), ("caisson", "tab:gray")):
        cells = triangles[m.cell_sets_dict[body]["triangle"]]
        ax.triplot(m.points[:, 0], m.points[:, 1], cells, color=color, lw=0.4)
    for name, marker in (("gauge_top", "s"), ("gauge_bottom", "s"),
                         ("corner_front", "o"), ("corner_rear", "o")):
        if name in m.cell_sets_dict:
            x = m.points[m.cells_dict["vertex"][m.cell_sets_dict[name]["vertex"]].ravel()]
            ax.plot(x[:, 0], x[:, 1], marker, ms=5, label=name)
    if "impact" in m.cell_sets_dict:
        lines = m.cells_dict["line"][m.cell_sets_dict["impact"]["line"]]
        x = m.points[np.unique(lines)]
        ax.plot(x[:, 0], x[:, 1], "r-", lw=4, label="impact")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"{title}: {len(m.cell_sets_dict['caisson']['triangle'])} + "
                 f"{len(m.cell_sets_dict['mound']['triangle'])} triangles")

fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
for ax, c in zip(axes, (reference, variant)):
    plot_mesh(c.mesh_file(comm), ax, c.name)
axes[0].set_xlabel("")
axes[0].legend(fontsize=7, loc="upper right")
fig.savefig(OUT / "meshes.png", dpi=120, bbox_inches="tight")
plt.show()

# %% [markdown]
# With the same gravel, the wider 1:3 mound holds the caisson hardly more stiffly (the
# crest carries it; the flatter slopes only add gravel far from it):

# %%
K_variant = sway_stiffness(variant, G)
print(f"K_x: reference {K_ref / 1e3:.1f} kN/m, variant {K_variant / 1e3:.1f} kN/m "
      f"({100 * (K_variant / K_ref - 1):+.1f} %)")
summary_variant = run(variant)

# %% [markdown]
# ## 3. Comparison
#
# The gauges, and the slip and opening of the caisson's struck-side corner (the heel),
# for both cases.

# %%
runs = {"paper's case": (OUT / "goda", summary_ref),
        "1:3 mound, 34 mm bolt": (OUT / "slope3_bolt34", summary_variant)}
histories = {label: read_history(folder / "history.csv")
             for label, (folder, _) in runs.items()}

fig, axes = plt.subplots(2, 2, figsize=(11, 6), sharex=True)
panels = [("gauge_top_ux", "top gauge $u_x$"), ("gauge_bottom_ux", "bottom gauge $u_x$"),
          ("corner_front_slip", "heel slip"), ("corner_front_opening", "heel opening")]
for ax, (column, title) in zip(axes.flat, panels):
    for label, h in histories.items():
        ax.plot(h["t"], 1e3 * h[column], label=label)
    ax.set_title(title)
    ax.set_ylabel("mm")
    ax.grid(lw=0.3)
for ax in axes[1]:
    ax.set_xlabel("t (s)")
axes[0, 0].legend()
fig.tight_layout()
fig.savefig(OUT / "comparison.png", dpi=120, bbox_inches="tight")
plt.show()

rows = ["| | " + " | ".join(runs) + " |", "|---|" + "---|" * len(runs)]


def row(name, values):
    rows.append(f"| {name} | " + " | ".join(values) + " |")


row("$K_x$ (kN/m)", [f"{K_ref / 1e3:.1f}", f"{K_variant / 1e3:.1f}"])
for gauge in ("gauge_top", "gauge_bottom"):
    row(f"peak $u_x$, {gauge} (mm)",
        [f"{s['dynamic']['peak_ux'][gauge]['value'] * 1e3:.3f} at "
         f"{s['dynamic']['peak_ux'][gauge]['time']:.4f} s" for _, s in runs.values()])
row("residual slip of the heel (mm)",
    [f"{s['dynamic']['pair_probes']['corner_front']['slip_change'] * 1e3:.3f}"
     for _, s in runs.values()])
row("largest uplift (mm)", [f"{s['dynamic']['max_uplift'] * 1e3:.3f}"
                            for _, s in runs.values()])
display(Markdown("\n".join(rows)))


# %% [markdown]
# Struck low, the caisson rocks much less: the bottom gauge moves nearly as much as the
# top one and the heel hardly lifts, and more of the impulse goes into shearing the
# interface, so it slides further. As the flatter mound changes $K_x$ by less than 1 %,
# the difference is the bolt's. (With a short end time, a test or documentation run,
# only the first milliseconds of the impact are computed.)
#
# ## 4. A mound of your own: a berm, with gmsh
#
# Any gmsh mesh works if its **named** physical groups are the ones the case refers
# to. The built-in case needs:
#
# - cells (2D): `caisson`, `mound` (its `[bodies.*]`);
# - facets (1D): `interface`, one curve shared by the two bodies' surfaces (conforming
#   contact), `base` (fixed), `impact` (the loaded patch);
# - points (0D): `gauge_top`, `gauge_bottom` (probes), `corner_front`, `corner_rear`
#   (interface probes).
#
# Below, a mound with a 150 mm wide berm 80 mm above the floor on the seaward
# (struck, $x < 0$) side, with the paper's caisson, written to `berm.msh`.

# %%
def berm_mesh(path, size=0.029 / REFINEMENT):
    H, crest, slope = 0.190, 0.400, 2.0     # mound height, crest, slopes (H per V)
    berm_y, berm_w = 0.080, 0.150           # berm level and width (seaward side)
    w, h, bolt, patch, gauge = 0.205, 0.202, 0.168, 0.010, 0.041  # caisson
    with gmsh_session(model="berm"):
        geo = gmsh.model.geo

        def point(x, y):
            return geo.addPoint(x, y, 0.0, size)

        # Mound outline, counter-clockwise from the seaward foot.
        x_berm = -crest / 2 - slope * (H - berm_y)
        foot_front = point(x_berm - berm_w - slope * berm_y, 0.0)
        foot_rear = point(crest / 2 + slope * H, 0.0)
        crest_rear, crest_front = point(crest / 2, H), point(-crest / 2, H)
        berm_in, berm_out = point(x_berm, berm_y), point(x_berm - berm_w, berm_y)
        corner_front, corner_rear = point(-w / 2, H), point(w / 2, H)
        # Caisson: the front face split at the gauges and the impact patch.
        top_front, top_rear = point(-w / 2, H + h), point(w / 2, H + h)
        levels = {"gauge_top": H + h - gauge, "impact_high": H + bolt + patch / 2,
                  "impact_low": H + bolt - patch / 2, "gauge_bottom": H + gauge}
        front = {name: point(-w / 2, y) for name, y in levels.items()}
        chain = [top_front, *(front[n] for n in sorted(levels, key=levels.get,
                                                       reverse=True)), corner_front]
        front_lines = [geo.addLine(a, b) for a, b in zip(chain[:-1], chain[1:])]
        impact = [line for line, a in zip(front_lines, chain)
                  if a == front["impact_high"]]

        base = geo.addLine(foot_front, foot_rear)
        interface = geo.addLine(corner_front, corner_rear)  # shared by both bodies
        mound_lines = [base, geo.addLine(foot_rear, crest_rear),
                       geo.addLine(crest_rear, corner_rear), -interface,
                       geo.addLine(corner_front, crest_front),
                       geo.addLine(crest_front, berm_in), geo.addLine(berm_in, berm_out),
                       geo.addLine(berm_out, foot_front)]
        caisson_lines = [interface, geo.addLine(corner_rear, top_rear),
                         geo.addLine(top_rear, top_front), *front_lines]
        caisson = geo.addPlaneSurface([geo.addCurveLoop(caisson_lines)])
        mound = geo.addPlaneSurface([geo.addCurveLoop(mound_lines)])
        geo.synchronize()

        groups = {
            (2, "caisson"): [caisson], (2, "mound"): [mound],
            (1, "interface"): [interface], (1, "base"): [base], (1, "impact"): impact,
            (0, "gauge_top"): [front["gauge_top"]],
            (0, "gauge_bottom"): [front["gauge_bottom"]],
            (0, "corner_front"): [corner_front], (0, "corner_rear"): [corner_rear],
        }
        for (dim, name), entities in groups.items():
            gmsh.model.addPhysicalGroup(dim, entities, name=name)
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
    return path


(OUT / "berm").mkdir(parents=True, exist_ok=True)
berm_path = berm_mesh(OUT / "berm" / "berm.msh")
fig, ax = plt.subplots(figsize=(9, 3.5))
plot_mesh(berm_path, ax, "mound with a berm")
ax.legend(fontsize=7, loc="upper right")
fig.savefig(OUT / "berm" / "berm_mesh.png", dpi=120, bbox_inches="tight")
plt.show()

# %% [markdown]
# A case file takes the mesh: it `extends` the built-in case and changes only what
# differs (the mesh file is relative to the case file). The gravel is again the
# reference's. `python -m breakwater run berm.toml` would run it from the command
# line; here it runs for a few milliseconds only.

# %%
case_file = OUT / "berm" / "berm.toml"
case_file.write_text(f'''\
# Goda's caisson on a mound with a seaward berm (a user gmsh mesh).
extends = "goda"
name = "berm"

[mesh]
source = "berm.msh"  # named groups: caisson, mound, interface, base, impact, ...

[bodies.mound]
shear_modulus = {G!r}  # Pa: the gravel of the paper's case (calibrated there)

[calibration]
enabled = false
''')
BERM_END_TIME = min(END_TIME, 0.01)
berm = load_case(case_file, [*common("berm", figures=True, refine=False),
                             f"time.end_time={BERM_END_TIME}"])
print(f"mesh: {berm.mesh.source}")
print(f"K_x with the berm: {sway_stiffness(berm, G) / 1e3:.1f} kN/m "
      f"(paper's mound {K_ref / 1e3:.1f} kN/m)")
summary_berm = run(berm)

# %%
display(Image(filename=str(OUT / "berm" / "figures" / "static_pressure.png"), width=600))
display(Image(filename=str(OUT / "berm" / "figures" / "max_ux_deformed.png"), width=720))

# %% [markdown]
# The caisson on the berm mound carries the same weight: its mean static contact
# pressure is again $\rho g h$ = 4586 Pa. Every output of the built-in case (history,
# summary, fields for ParaView, figures) is there for the user's mesh too, in
# `<output>/berm/`.

# %% [markdown]
# ## 5. A measured pressure record
#
# A pressure record measured on a model (a transducer sampled in time) is a CSV file of
# `t, value` rows. A case reads it as a tabulated time function, `time_function =
# "table"` with `table.file` (relative to the case file), interpolated linearly between
# the samples; a header line and `#` comments are skipped. No measured record ships
# with breakwater: the cell below writes a synthetic one in its place, a "church-roof"
# breaking-wave history (impact peak, then the quasi-static hump of the crest) sampled
# at 2 kHz with transducer noise. To use your own, point `table.file` at it.

# %%
from breakwater.loads.tablefile import read_table
from breakwater.loads.wavepressure import goda_pressure

(OUT / "measured").mkdir(parents=True, exist_ok=True)
record = OUT / "measured" / "pressure_record.csv"
rng = np.random.default_rng(2011)
t = np.arange(0.0, 0.4, 5e-4)
p = 2100.0 * np.interp(t, [0, 0.01, 0.02, 0.03, 0.1, 0.25, 0.35],
                       [0, 2.5, 1.1, 0.9, 1.0, 1.0, 0]) + 20.0 * rng.standard_normal(len(t))
p[0] = 0.0  # the wave arrives after t = 0: no load in the initial static state
np.savetxt(record, np.column_stack([t, p]), delimiter=",", header="t (s),p (Pa)",
           comments="")

times, values = read_table(record)  # what the case reads: (t, value) tuples
print(f"{len(times)} samples from {times[0]} s to {times[-1]} s, peak {max(values):.0f} Pa")

# %% [markdown]
# The record is a point pressure. The case below spreads it over the seaward face with
# a shape: a `[profile]` of factors along the elevation y, 1 below the still water level
# (y = 0.32 m) and falling to 0 at the caisson's top, times the record in Pa. The
# impulse of the built-in case is switched off (`enabled = false`). For comparison,
# Goda's design pressure of a laboratory-scale wave (H_max = 0.18 m, T = 1.4 s, the
# `examples/goda_design_wave.toml` case) is drawn with it.

# %%
case_file = OUT / "measured" / "measured_wave.toml"
case_file.write_text(f'''\
extends = "goda"
name = "measured_wave"

[bodies.mound]
shear_modulus = {G!r}  # Pa: the gravel of the paper's case

[calibration]
enabled = false

[loads.impact]         # no pendulum
enabled = false

[loads.wave]
group = "caisson_front"
groups = ["impact"]    # the bolt's patch, a group of its own on the same face
time_function = "table"
table.file = "pressure_record.csv"
table.hold_last = true
# the shape along y (factors): 1 up to the still water level, 0 at the caisson top
profile = {{ points = [[0.19, 1.0], [0.32, 1.0], [0.392, 0.0]], axis = [0.0, 1.0] }}
''')
measured = load_case(case_file, common("measured_wave"))
wave = next(ld for ld in measured.loads if ld.name == "wave")
factor = wave.time_factor()
print(f"time function: {wave.kind}; at t = 0.01 s: {factor(0.01):.0f} Pa")
summary_measured = run(measured)

goda = goda_pressure(0.18, 1.4, depth=0.32, toe_depth=0.13, berm_depth=0.13,
                     crest_height=0.072)
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 3.5), width_ratios=[2, 1])
ax1.plot(times, values, lw=0.6, label="record (Pa)")
ax1.set_xlabel("t (s)")
ax1.set_ylabel("pressure at the still water level (Pa)")
ax1.grid(lw=0.3)
ax1.legend()
y = np.linspace(0.19, 0.392, 200)
ax2.plot([goda.front(v - 0.32) for v in y], y, label="Goda, H = 0.18 m")
ax2.plot(wave.profile.field().pressure(y) * goda.p1, y, "--", label="profile × p₁")
ax2.axhline(0.32, color="tab:blue", lw=0.5)
ax2.set_xlabel("p (Pa)")
ax2.set_ylabel("y (m)")
ax2.legend(fontsize=8)
fig.tight_layout()
fig.savefig(OUT / "measured" / "record_and_profile.png", dpi=120, bbox_inches="tight")
plt.show()
print(f"Goda: p1 = {goda.p1:.0f} Pa, p3 = {goda.p3:.0f} Pa, p4 = {goda.p4:.0f} Pa, "
      f"uplift {goda.uplift:.0f} Pa; P = {goda.force:.0f} N/m")
