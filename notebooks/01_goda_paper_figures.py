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
# # Goda's pendulum test: the figures of Stickle, de la Fuente & Oteo (2011)
#
# This notebook reproduces, through breakwater's Python API, the numerical experiment of
# Stickle, de la Fuente & Oteo (2011), *Mecánica de Contacto de Cuerpos Deformables.
# Interacción suelo-estructura*, Revista de Investigación Pensamiento Matemático,
# section 5: Goda's (1994) laboratory test, in which a pendulum strikes a scale concrete
# caisson resting on a gravel mound. The caisson and the mound are two deformable bodies
# in frictional contact: the impact makes the caisson sway, lift off at its heel, slide
# on the mound and settle again under its own weight.
#
# 1. the model, with the paper's equation numbers (sections 2-4 of the paper);
# 2. the case (section 5), read with `breakwater.casefile.case.load_case`;
# 3. the mound's shear modulus, calibrated to Goda's horizontal stiffness $K_x$;
# 4. the run, `breakwater.run.simulation.run`;
# 5. the paper's Figs. 16-22, drawn from the run's output files with
#    `breakwater.outputs.figures`;
# 6. the paper's headline numbers next to the run's.
#
# The same run from the command line is `python -m breakwater run` (the default case).
# The notebook reads three environment variables (the test suite sets them for a run of
# a few milliseconds, the documentation build for a shortened run); with the defaults
# the run takes about a minute on one core.
#
# | environment variable | default | meaning |
# |---|---|---|
# | `BREAKWATER_NOTEBOOK_END_TIME` | `0.15` | final time (s); by 0.15 s the caisson has about come to rest |
# | `BREAKWATER_NOTEBOOK_REFINEMENT` | `1.0` | element sizes are divided by it (1: the paper's mesh) |
# | `BREAKWATER_NOTEBOOK_OUTPUT` | `results/notebook_goda` | output folder, relative to the working directory |

# %%
import os
import pathlib

# Short values make a quick run (the tests and the documentation build set them).
END_TIME = float(os.environ.get("BREAKWATER_NOTEBOOK_END_TIME", "0.15"))  # s
REFINEMENT = float(os.environ.get("BREAKWATER_NOTEBOOK_REFINEMENT", "1.0"))
OUT = pathlib.Path(os.environ.get("BREAKWATER_NOTEBOOK_OUTPUT",
                                  "results/notebook_goda"))
print(f"end time {END_TIME} s, refinement {REFINEMENT}, output folder {OUT}")

# %%
import json
import math

import breakwater  # first: it loads the PETSc of the dolfinx wheel (when installed)
import matplotlib.pyplot as plt
import numpy as np
from IPython.display import Image, Markdown, display
from mpi4py import MPI

from breakwater import meshes
from breakwater.casefile.case import load_case
from breakwater.outputs import figures
from breakwater.outputs.writers import read_history
from breakwater.run import simulation
from breakwater.statics.calibrate import HorizontalStiffness

# %% [markdown]
# ## 1. The model
#
# ### Kinematics (paper §2)
#
# Two bodies under small strains, with displacements $\mathbf u = \mathbf x - \mathbf X$:
# the master $\mathcal B^1$ (the mound) and the slave $\mathcal B^2$ (the caisson). A point
# $\mathbf x^2$ of the slave's surface and its closest-point projection $\bar{\mathbf x}^1$
# on the master's surface (5)-(6), with the master's outward normal
# $\bar{\mathbf n}^1$, define the normal gap, which may not be negative:
#
# $$ g_n = (\mathbf x^2 - \bar{\mathbf x}^1)\cdot\bar{\mathbf n}^1 \ \ge\ 0. \qquad (7)$$
#
# In stick the relative tangential slip does not change, $\dot g_T = 0$ (8); in slip,
# $g_T$ is the time integral of the relative tangential velocity (9)-(10). The interface
# of the case is conforming (the caisson base and the mound crest share their nodes) and
# initially closed, so, as in the paper, contact is node to node: at interface node $i$
#
# $$ g_{n,i} = (\mathbf u^2_i - \mathbf u^1_i)\cdot\mathbf n^1_i, \qquad
#    g_{T,i} = (\mathbf u^2_i - \mathbf u^1_i)\cdot\mathbf t^1_i. $$
#
# ### The interface law (paper §3)
#
# Normal contact obeys the Hertz-Signorini-Moreau conditions (11),
# $g_n \ge 0$, $\sigma_n \le 0$, $\sigma_n g_n = 0$, regularised by a penalty: the contact
# pressure is
#
# $$ p = \varepsilon_n \langle -g_n \rangle_+ , $$
#
# non-zero only where the bodies overlap, by $p/\varepsilon_n$ (about 9 µm under the
# caisson's weight with $\varepsilon_n = 5\cdot 10^8$ N/m³). Coulomb's law (13),
# $\|\mathbf t_T\| \le \mu |\sigma_n|$ with the tangential traction opposing the slip, is
# regularised as (14)-(15)
#
# $$ \mathbf t_T = -\mu\,|\sigma_n|\,\varphi(\dot g_T), \qquad
#    \varphi(v) = \frac{v}{\sqrt{v^2 + \chi^2}}, $$
#
# which tends to Coulomb's law as $\chi \to 0$; the paper's $\chi = 10^{-10}$ m/s resolves
# stick and slip (a large $\chi$ would make the block creep instead of stick).
#
# ### Finite elements and time integration (paper §4)
#
# Each body obeys the balance of momentum (16), with isotropic linear elasticity (17)
# (bulk modulus $K$, shear modulus $G$) in plane strain:
#
# $$ \nabla\cdot\boldsymbol\sigma - \rho\,\ddot{\mathbf u} + \rho\,\mathbf b = \mathbf 0,
#    \qquad \boldsymbol\sigma = K\,\mathrm{tr}\,\boldsymbol\varepsilon\,\mathbf I
#    + 2G\,\mathrm{dev}\,\boldsymbol\varepsilon . $$
#
# Both bodies are meshed with six-node (quadratic) triangles. The semi-discrete system
# (20)-(22), with Rayleigh damping, is
#
# $$ \mathbf M\ddot{\mathbf u} + \mathbf C\dot{\mathbf u} + \mathbf K\mathbf u
#    = \mathbf f + \mathbf f_c, \qquad \mathbf C = \alpha\mathbf M + \beta\mathbf K, $$
#
# where the contact forces (23) sum over the interface nodes $i$ with tributary areas
# $A_i$ (active where $g_{n,i} < 0$):
#
# $$ \mathbf f_c^1 = \sum_i \Big( \varepsilon_n g_{n,i} A_i\,\mathbf n^1_i
#    - \mu\,\varphi(\dot g_{T,i})\,|\varepsilon_n g_{n,i}|\,A_i\,\mathbf t^1_i \Big),
#    \qquad \mathbf f_c^2 = -\mathbf f_c^1 . $$
#
# breakwater writes (23) as an integral over the interface, evaluated with a nodal
# (Gauss-Lobatto) quadrature: that is the paper's nodal sum.
#
# Time integration (24)-(28) is GN22, the generalised Newmark scheme of Katona &
# Zienkiewicz (1985). The unknown of a step is the acceleration increment
# $\Delta\mathbf a$:
#
# $$ \mathbf a_{n+1} = \mathbf a_n + \Delta\mathbf a, \quad
#    \mathbf v_{n+1} = \mathbf v_n + \Delta t\,\mathbf a_n + \beta_1\Delta t\,\Delta\mathbf a,
#    \quad
#    \mathbf u_{n+1} = \mathbf u_n + \Delta t\,\mathbf v_n + \tfrac12\Delta t^2\mathbf a_n
#    + \tfrac12\beta_2\Delta t^2\,\Delta\mathbf a . $$
#
# It is unconditionally stable for $\beta_2 \ge \beta_1 \ge \frac12$; the paper's
# $\beta_1 = 0.6$, $\beta_2 = 0.605$ damp the highest frequencies. Contact makes each
# step nonlinear: Newton-Raphson solves (27) for $\Delta\mathbf a$. (The printed (26) and
# (28) carry typesetting errors; the update above is the scheme.) Before the impact the
# caisson is placed on the mound: a static frictionless solve under gravity gives the
# initial state (Figs. 16-17).

# %% [markdown]
# ## 2. The case (paper §5)
#
# | | Goda's scale model (paper §5.1-5.3) |
# |---|---|
# | mound | gravel ($d_{50}$ = 15 mm) on a concrete floor: 190 mm high, 400 mm crest, side slopes 1:2 (V:H); base fixed |
# | caisson | concrete block 202 mm high, 205 mm wide, 205 mm long; $\rho$ = 2314 kg/m³, $G = 2\cdot10^9$ Pa, $\nu$ = 0.2 |
# | mound material | $\nu$ = 0.25; $G$ not printed: the one giving Goda's horizontal stiffness $K_x \approx$ 500 kN/m; density not printed |
# | pendulum | $M$ = 5.5 kg, cord $l_0$ = 3.393 m, released $s_0$ = 250 mm from the block, restitution $e_0$ = 0.2; strikes the bolt 168 mm above the block base |
# | gauges | on the struck face, 41 mm below the top and 41 mm above the bottom |
# | contact | $\varepsilon_n = 5\cdot10^8$ N/m³, $\mu$ = 0.65, $\chi = 10^{-10}$ m/s |
# | damping, GN22 | $\alpha$ = 0.023 1/s, $\beta$ = 0.023 s; $\beta_1$ = 0.6, $\beta_2$ = 0.605 |
# | mesh | 156 six-node triangles in the caisson, 558 in the mound |
#
# The pendulum's impulse (29) is
#
# $$ \omega = s_0\sqrt{g/l_0}, \qquad I = M\,\omega\,(1 + e_0) = 2.81\ \mathrm{N\,s}, $$
#
# divided by the block's length (0.205 m) for plane strain: 13.71 N s/m, applied as a
# triangular force pulse (Fig. 15) on the bolt. The built-in case
# `breakwater/cases/goda.toml` holds these data; the values the paper does not print
# (the mound's density, 1650 kg/m³, and the pulse duration, 2 ms) are chosen and
# justified in its comments. `load_case(None, overrides)` reads it and applies
# `key=value` overrides, the `--set` options of the command line.

# %%
overrides = [
    f"time.end_time={END_TIME}",
    f"mesh.refinement={REFINEMENT}",
    f"output.directory={json.dumps(OUT.as_posix())}",
    "output.figures=false",  # drawn below with breakwater.outputs.figures
]
case = load_case(None, overrides)

g = case.mesh.goda  # the dimensions: a breakwater.meshes.GodaGeometry
caisson, mound = case.body("caisson"), case.body("mound")
impact = next(load for load in case.loads if load.name == "impact")
pendulum = impact.pendulum
contact = case.contact[0]
L = case.out_of_plane_length
print(f"caisson: {g.caisson_width * 1e3:.0f} x {g.caisson_height * 1e3:.0f} mm, "
      f"ρ = {caisson.density:g} kg/m³, G = {caisson.shear_modulus:.3g} Pa, "
      f"ν = {caisson.poisson:g}")
print(f"mound: {g.mound_height * 1e3:.0f} mm high, crest {g.crest_width * 1e3:.0f} mm, "
      f"slopes 1:{g.slope:g}, base {g.base_width * 1e3:.0f} mm, "
      f"ρ = {mound.density:g} kg/m³, ν = {mound.poisson:g}")
print(f"contact '{contact.name}': ε_n = {contact.penalty:.3g} N/m³, "
      f"μ = {contact.friction:g}, χ = {contact.regularisation:g} m/s")
print(f"eq. 29: ω = {pendulum.velocity:.4f} m/s, I = {impact.total_impulse:.3f} N s "
      f"(paper 2.81), I / {L} m = {impact.total_impulse / L:.2f} N s/m (paper 13.71); "
      f"{impact.shape} pulse of {impact.duration * 1e3:g} ms at "
      f"{g.bolt_height * 1e3:g} mm")
print(f"GN22 β1 = {case.time.beta1}, β2 = {case.time.beta2}, Δt = {case.time.dt:g} s, "
      f"end time {case.time.end_time:g} s; outputs in {case.output_directory}")


# %% [markdown]
# ### The mesh
#
# The built-in generator (`breakwater.meshes`, gmsh) builds the model from
# `case.mesh.goda`: the caisson base and the middle of the crest are one curve, so the
# interface is conforming. Every boundary, body and point the case refers to is a named
# gmsh physical group: cells `caisson`, `mound`; facets `interface`, `base`, `impact` (the
# 10 mm struck patch on the bolt); points `gauge_top`, `gauge_bottom`, `corner_front`,
# `corner_rear`. The struck face is the left one ($x < 0$); the pendulum pushes in $+x$.

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

mesh_path = case.mesh_file(MPI.COMM_WORLD)  # writes <output>/mesh/goda.msh
fig, ax = plt.subplots(figsize=(9, 3.5))
plot_mesh(mesh_path, ax, "Goda's model")
ax.legend(fontsize=7, loc="upper right")
plt.show()

# %% [markdown]
# ## 3. The mound's stiffness
#
# `case.build()` reads the mesh, calibrates the mound's shear modulus (the case's
# `[calibration]` table, `breakwater.statics.calibrate`) and builds the contact model with its
# loads, gravity and damping. The calibration follows Goda's mass-spring model: the
# caisson's horizontal stiffness $K_x$ is the inertial load of a uniform horizontal
# acceleration of the caisson over its mean displacement, the interface bonded (at small
# amplitude it sticks and stays closed); secant iterations on $G$ bring $K_x$ to
# 500 kN/m over 0.205 m.

# %%
comm = MPI.COMM_WORLD
built = case.build(comm)  # built.case is the case as run, the calibrated G written in
model, time_spec, output_spec, extra = built
cal = extra["calibration"]
G = cal["shear_modulus"]
print(f"mesh: {extra['mesh']['cells']} six-node triangles (paper: caisson 156, mound 558)")
print(f"calibrated mound G = {G:.4g} Pa in {cal['iterations']} stiffness solves:")
for G_i, K_i in cal["history"]:
    print(f"    G = {G_i:10.4g} Pa -> K_x = {K_i * L / 1e3:8.2f} kN/m")
print(f"K_x = {cal['stiffness'] * L / 1e3:.2f} kN/m (target "
      f"{case.calibration.stiffness / 1e3:g} kN/m, relative error "
      f"{cal['relative_error']:.1e})")

# %% [markdown]
# A check: a new model built with this $G$ (no calibration) has the same stiffness.
# Goda's mass-spring model then gives the caisson's sway period
# $T = 2\pi\sqrt{m/K_x}$ and, for that mode, the Rayleigh damping ratio
# $\zeta = \alpha/2\omega + \beta\omega/2$.

# %%
check_model = case.build_model(case.read_mesh(comm), {"mound": G}, dynamic=False)
K_x = HorizontalStiffness(check_model, "caisson",
                          case.calibration.tangential_penalty)() * L
m = caisson.density * g.caisson_width * g.caisson_height * L
ω = math.sqrt(K_x / m)
ζ = case.damping.alpha / (2 * ω) + case.damping.beta * ω / 2
print(f"check: K_x = {K_x / 1e3:.2f} kN/m with G = {G:.4g} Pa")
print(f"caisson mass {m:.2f} kg: sway period T = {2 * math.pi / ω * 1e3:.1f} ms, "
      f"damping ratio ζ = {ζ:.2f}")

# %% [markdown]
# ## 4. The run
#
# `simulation.run` solves the static equilibrium, steps with GN22 to the end time
# (halving the step when Newton fails) and writes, in the output folder:
# `history.csv` (one row per step: probes, interface slip and opening, contact
# resultants, energies), `summary.json` (the headline numbers), `static.npz` and
# `snapshot_max_ux.npz` (the fields at rest and at the largest horizontal
# displacement), `fields_<body>.bp` and `contact_<pair>.bp` (ParaView) and
# `case.toml`, the resolved case, which `python -m breakwater run case.toml` runs
# again. While it runs, one line below the cell shows how far it is (the simulated
# time, the steps, the time left), updated in place every second;
# `dataclasses.replace(output_spec, progress=False)` turns it off.

# %%
summary = simulation.run(model, time_spec, output_spec, resolved_case=built.case.resolved(),
                         extra_summary=extra)
print(sorted(p.name for p in OUT.iterdir()))

# %% [markdown]
# ## 5. The paper's figures
#
# `figures.make_figures(folder)` draws every figure of a run from its output files only
# (so it can be redone later, e.g. `python -m breakwater.outputs.figures results/goda`), into
# `<folder>/figures/`. Below, each figure of the paper next to the run's.

# %%
drawn = figures.make_figures(OUT)
print([p.name for p in drawn])


def show(name):
    display(Image(filename=str(OUT / "figures" / name), width=720))


history = read_history(OUT / "history.csv")
t = history["t"]
t_max = summary["dynamic"]["time_of_max_ux"]
static_state = np.load(OUT / "static.npz")
snapshot = np.load(OUT / "snapshot_max_ux.npz")

# %% [markdown]
# ### Fig. 16: static vertical displacement
#
# After the caisson is placed on the mound, the vertical displacement is continuous
# across the interface: the bodies are in contact, neither apart nor overlapping
# (beyond the penalty's micrometres).

# %%
show("static_uy.png")

# %% [markdown]
# ### Fig. 17: static vertical stress and contact pressure
#
# The vertical stress under the caisson is that of a rigid footing: largest at the
# edges, smallest at the centre, with the mean equal to the caisson's weight per unit
# area, $\rho g h$ = 2314 · 9.81 · 0.202 = 4586 Pa.

# %%
show("static_syy.png")

x, p = static_state["contact_interface_x"][:, 0], static_state["contact_interface_pressure"]
order = np.argsort(x)
fig, ax = plt.subplots(figsize=(7, 3.5))
ax.plot(1e3 * x[order], p[order], "o-", ms=3, label="interface nodes")
ax.axhline(summary["static"]["mean_contact_pressure"], color="C1",
           label=f"mean: {summary['static']['mean_contact_pressure']:.0f} Pa")
ax.axhline(4586.0, color="k", ls="--", lw=0.8, label="paper: ρgh = 4586 Pa")
ax.set_xlabel("x along the caisson base (mm)")
ax.set_ylabel("contact pressure (Pa)")
ax.set_title("Static contact pressure (Fig. 17)")
ax.grid(lw=0.3)
ax.legend()
fig.savefig(OUT / "figures" / "notebook_static_pressure.png", dpi=120,
            bbox_inches="tight")
plt.show()

# %% [markdown]
# ### Fig. 18: horizontal displacement at the gauges
#
# The two gauges on the struck face. The top one moves more than the bottom one: the
# caisson does not only sway as Goda's mass-spring model, it rocks, lifting off the
# mound at its heel. After the impact both gauges keep the same residual displacement:
# the caisson has slid, not tilted. The paper's numerical peak comes at $t$ = 0.032 s
# (dotted).

# %%
fig, ax = plt.subplots(figsize=(7, 3.5))
for name in ("gauge_top", "gauge_bottom"):
    ax.plot(t, 1e3 * history[f"{name}_ux"], label=name)
ax.axvline(0.032, color="k", ls=":", lw=0.8, label="paper: t = 0.032 s")
ax.axvline(t_max, color="C3", ls="--", lw=0.8, label=f"run: t = {t_max:.4f} s")
ax.set_xlabel("t (s)")
ax.set_ylabel("$u_x$ (mm)")
ax.set_title("Horizontal displacement at the gauges (Fig. 18)")
ax.grid(lw=0.3)
ax.legend()
fig.savefig(OUT / "figures" / "notebook_gauges.png", dpi=120, bbox_inches="tight")
plt.show()

# %% [markdown]
# ### Fig. 19: horizontal displacement of the caisson corner and of the mound under it
#
# The struck-side bottom corner of the caisson (`slave`) and the coincident mound node
# (`master`); their difference is the slip. After the impact the caisson stays
# displaced relative to the mound: the paper's residual slip is about 0.4 mm.

# %%
show("pair_probes_ux.png")

# %% [markdown]
# ### Figs. 20 and 22: deformed shape and vertical stress at the largest displacement
#
# The deformed shape, magnified 20 times, coloured by $\sigma_{yy}$, at the instant of
# the largest horizontal displacement of the top gauge (paper: $t$ = 0.032 s): the
# caisson rocks on its rear corner, the struck side lifts off the mound (partial loss
# of contact) and the vertical stress concentrates under the corner it rocks on. The
# plot below it is the normal gap along the interface at that instant: open ($> 0$)
# under the lifted part, closed under the rear corner, where the penalty lets the
# bodies overlap by $p/\varepsilon_n$ (larger under the concentrated corner pressure
# than at rest; it vanishes only as $\varepsilon_n \to \infty$).

# %%
show("max_ux_deformed.png")

x, gap = snapshot["contact_interface_x"][:, 0], snapshot["contact_interface_gap"]
order = np.argsort(x)
fig, ax = plt.subplots(figsize=(7, 3))
ax.plot(1e3 * x[order], 1e3 * gap[order], "o-", ms=3)
ax.axhline(0.0, color="k", lw=0.6)
ax.set_xlabel("x along the caisson base (mm)")
ax.set_ylabel("normal gap $g_n$ (mm)")
ax.set_title(f"Interface gap at t = {float(snapshot['time']):.4f} s (Fig. 20)")
ax.grid(lw=0.3)
fig.savefig(OUT / "figures" / "notebook_gap_at_max_ux.png", dpi=120,
            bbox_inches="tight")
plt.show()

# %% [markdown]
# ### Fig. 21: vertical displacement of the caisson corner and of the mound under it
#
# The impact lifts the struck-side corner off the mound (the opening is positive);
# afterwards the caisson's weight closes the interface again, without noticeable
# interpenetration.

# %%
show("pair_probes_uy.png")

# %% [markdown]
# ### Not in the paper: energy and contact resultants
#
# The energy ledger (kinetic, strain and penalty energies, Rayleigh and friction
# dissipation, work of the loads, and GN22's numerical dissipation computed from the
# scheme's discrete energy identity) closes to the Newton tolerance (the lower panel);
# the contact length shows the loss and recovery of contact.

# %%
show("energy.png")
show("contact.png")

# %% [markdown]
# ## 6. The paper's numbers
#
# The paper's headline results (its section 5.4) next to the run's `summary.json`. The
# residual slip is the change of the corner's slip from the static state (placing the
# caisson already shears the interface a little). With a short end time (a test or
# documentation run) the caisson is still moving at the end, and the dynamic rows are
# not comparable.

# %%
static, dynamic = summary["static"], summary["dynamic"]
peak, residual = dynamic["peak_ux"], dynamic["residual_ux"]
front = dynamic["pair_probes"]["corner_front"]
opening = history["corner_front_opening"]
overlap = max(0.0, -opening[np.argmax(opening):].min())  # after the lift-off
top, bottom = residual["gauge_top"], residual["gauge_bottom"]
rows = [
    ("mean static contact pressure", "4586 Pa (= ρgh)",
     f"{static['mean_contact_pressure']:.1f} Pa"),
    ("static pressure along the base", "maxima at the edges, minimum at the centre",
     f"edges {static['edge_pressure']:.0f} Pa, centre {static['center_pressure']:.0f} Pa"),
    ("time of the largest horizontal displacement", "0.032 s",
     f"{dynamic['time_of_max_ux']:.4f} s"),
    ("peak $u_x$ at the gauges", "within 8 % of Goda's measurement (Fig. 18)",
     f"top {peak['gauge_top']['value'] * 1e3:.3f} mm, "
     f"bottom {peak['gauge_bottom']['value'] * 1e3:.3f} mm"),
    ("residual $u_x$ at the two gauges", "no noticeable difference (no rocking)",
     f"top {top * 1e3:.3f} mm, bottom {bottom * 1e3:.3f} mm "
     f"({200 * abs(top - bottom) / abs(top + bottom):.0f} % apart)"),
    ("residual slip of the caisson corner", "about 0.4 mm",
     f"{front['slip_change'] * 1e3:.3f} mm"),
    ("separation at the heel", "yes (Figs. 20-21)",
     f"{front['max_opening'] * 1e3:.3f} mm at t = {front['time_of_max_opening']:.4f} s"),
    ("contact restored at the heel", "yes, by the self weight, without noticeable "
     "interpenetration",
     f"residual opening {front['residual_opening'] * 1e6:.0f} µm (at rest "
     f"{opening[0] * 1e6:.0f} µm); largest overlap after the lift-off "
     f"{overlap * 1e6:.0f} µm (the penalty's p/ε_n)"),
]
table = ["| quantity | paper | this run |", "|---|---|---|"]
table += [f"| {q} | {paper} | {run} |" for q, paper, run in rows]
note = ""
if summary["time"]["reached"] < 0.1:
    note = (f"\n\n*The run ends at t = {summary['time']['reached']:g} s, before the "
            "caisson comes to rest: set BREAKWATER_NOTEBOOK_END_TIME=0.15 for the "
            "paper's comparison.*")
display(Markdown("\n".join(table) + note))

# %% [markdown]
# ## 7. The fields in pyvista
#
# The fields written for ParaView (`fields_<body>.bp`, `contact_<pair>.bp`: ADIOS2 files,
# which pyvista does not read) are read back by
# `breakwater.outputs.fieldgrids.read_fields(folder, name, time)` as a
# `pyvista.UnstructuredGrid` of the body (or the pair's interface) in its reference
# configuration, with the fields as point data: `displacement`, `velocity`, `stress`
# (3 × 3), `von_mises`, `stress_yy`. The time read is the written one nearest to the one
# asked for (every `output.field_interval` steps; `field_times(folder, name)` lists
# them). `pyvista.OFF_SCREEN = True` renders without a window, to an image.

# %%
import pyvista

from breakwater.outputs.fieldgrids import field_times, read_fields

pyvista.OFF_SCREEN = True
t_max = summary["dynamic"]["time_of_max_ux"]
grids = {body: read_fields(OUT, body, time=t_max) for body in ("mound", "caisson")}
t_read = grids["caisson"].field_data["time"][0]
print(f"{len(field_times(OUT, 'caisson'))} times written; read t = {t_read:.4f} s "
      f"(largest u_x at {t_max:.4f} s)")
print(grids["caisson"])

top = max(float(g.point_data["von_mises"].max()) for g in grids.values())
plotter = pyvista.Plotter(window_size=(1000, 420))
for grid in grids.values():
    plotter.add_mesh(grid.warp_by_vector("displacement", factor=20), scalars="von_mises",
                     clim=(0.0, top), cmap="viridis",
                     scalar_bar_args={"title": "von Mises (Pa)"})
plotter.add_text(f"t = {t_read:.4f} s, displacements x 20", font_size=10)
plotter.view_xy()
plotter.screenshot(OUT / "figures" / "notebook_pyvista_von_mises.png")
plotter.close()
display(Image(filename=str(OUT / "figures" / "notebook_pyvista_von_mises.png"),
              width=800))

# %% [markdown]
# The notebook `02_user_variant.py` changes the case (another mound slope, another
# bolt) and builds a mound of its own with gmsh.
