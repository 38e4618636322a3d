"""Goda's formula inside its range, for any period and depth, and loads as applied (issue 20).

- the linear dispersion relation ω² = g k tanh(k h) solved for any period and depth
  (T = 0.1 s at h = 1000 m: no overflow), against itself (the residual), its deep- and
  shallow-water limits and Fenton & McKee's (1990) approximation (within its stated
  1.7 %);
- Goda's formula (:mod:`breakwater.loads.wavepressure`) refused outside its range of validity
  (h_b >= d, 0 < d <= h' <= h, h_c >= 0, λ₁ > 0, H_max <= Goda's breaking limit), each
  refusal naming the input and the range; accepted at the bounds; deep water without
  overflow (α₁ = 0.6, α₃ = 1 − h'/h, p₂ = 0, α_I = 0);
- the part of the profile on a face (:meth:`GodaPressure.part`) against the trapezoidal
  rule; on a mesh, the summary's force and moment equal the load the mesh receives
  when the crest height or the still water level puts part of the profile off the
  face (with a warning giving the fraction), and a profile off the face is refused;
- a study of a Goda case: a point the mesh refuses fails alone, the others (one in
  1000 m of water, which raised OverflowError before any case ran) run.
"""

from __future__ import annotations

import csv
import logging
import math
import pathlib

import numpy as np
import pytest
import ufl
from blocks import two_block_case, two_rectangles
from mpi4py import MPI
from petsc4py import PETSc

from breakwater import cli
from breakwater.casefile.case import CaseError, load_case
from breakwater.casefile.godaface import check_goda_face
from breakwater.casefile.meshloads import load_summary
from breakwater.loads.wavepressure import (
    GodaRangeError,
    breaking_height,
    goda_pressure,
    wavelength,
)
from breakwater.studies.sweep import TABLE

COMM = MPI.COMM_WORLD
G = 9.81


# --- the dispersion relation --------------------------------------------------------------

PERIODS = (0.1, 0.5, 1.4, 10.0, 100.0, 1.0e4)
DEPTHS = (1.0e-3, 0.32, 10.0, 1000.0, 1.0e5)


def test_dispersion_relation_for_any_period_and_depth():
    for T in PERIODS:
        for h in DEPTHS:
            L = wavelength(T, h)
            k, omega2 = 2 * math.pi / L, (2 * math.pi / T) ** 2
            # The relation itself, to round-off (ω²h/g from 4e-9 to 4e7 here; Newton's
            # method ends within a few ulps of y tanh y = K).
            assert G * k * math.tanh(k * h) == pytest.approx(omega2, rel=1e-14), (T, h)
            # Fenton & McKee (1990, Coastal Eng. 14, 499-513): L = (gT²/2π)
            # tanh((2π√(h/g)/T)^(3/2))^(2/3), exact in both limits and within 1.7 %
            # between them (their stated accuracy).
            fm = G * T**2 / (2 * math.pi) * math.tanh(
                (2 * math.pi * math.sqrt(h / G) / T) ** 1.5) ** (2 / 3)
            assert abs(L / fm - 1) <= 0.017, (T, h, L, fm)


def test_dispersion_limits_and_known_values():
    # Deep water, T = 0.1 s at h = 1000 m (kh = 4e5: its cosh overflows): tanh(kh) = 1 in
    # floating point, so L = gT²/2π to round-off.
    assert wavelength(0.1, 1000.0) == pytest.approx(G * 0.01 / (2 * math.pi), rel=1e-15)
    # Shallow water, T = 1e4 s at h = 1 cm: L/(T√(gh)) = √(tanh y / y) = 1 − y²/6 +
    # O(y⁴) with y = kh = 2e-6 here (the O(y⁴) term is 19y⁴/360).
    T, h = 1.0e4, 0.01
    L = wavelength(T, h)
    y = 2 * math.pi * h / L
    assert abs(L / (T * math.sqrt(G * h)) - (1 - y**2 / 6)) <= y**4 + 1e-15
    # Tables of the dispersion relation: L(10 s, 10 m) = 92.37 m; the design-wave
    # example's L(1.4 s, 0.32 m) = 2.21 m (examples/goda_design_wave.toml).
    assert wavelength(10.0, 10.0) == pytest.approx(92.37, abs=0.01)
    assert wavelength(1.4, 0.32) == pytest.approx(2.21, abs=0.005)
    with pytest.raises(ValueError, match="floating point"):
        wavelength(1e-200, 1.0)


# --- Goda's range of validity -------------------------------------------------------------

# The design-wave example's wave (examples/goda_design_wave.toml).
WAVE = dict(wave_height=0.18, period=1.4, depth=0.32, toe_depth=0.13, berm_depth=0.13,
            crest_height=0.072)


@pytest.mark.parametrize(("change", "key", "phrase"), [
    ({"breaking_depth": 0.1}, "breaking_depth", "α₂ = -0.192 < 0 would put suction on "
     "the front (range h_b >= d)"),
    ({"wave_height": 3.2}, "wave_height", "exceeds the breaking limit H_b = 0.2947 m at the "
     "depth 0.32 m for T = 1.4 s (Goda's breaker index, bottom slopes up to 1/10): range "
     "0 < H_max <= 0.2947 m"),
    ({"period": 0.1}, "wave_height", "range 0 < H_max <= 0.002654 m"),
    ({"wave_height": 0.38, "breaking_depth": 0.5}, "wave_height", "H_b = 0.3793 m at the "
     "depth 0.5 m"),
    ({"factors": (0.0, 1.0, 1.0)}, "factors", "λ₁ > 0"),
    ({"crest_height": -0.05}, "crest_height", "must be >= 0"),
    ({"berm_depth": 0.2}, "berm_depth", "range 0 < d <= h' <= h"),
    ({"toe_depth": 0.4}, "toe_depth", "range 0 < d <= h' <= h"),
    ({"period": 1e-200}, "period", "out of the range of floating point"),
], ids=["hb_below_d", "ten_times_depth", "short_period", "limit_at_hb", "lambda1",
        "crest", "berm", "toe", "tiny_period"])
def test_goda_refused_outside_its_range(change, key, phrase):
    with pytest.raises(GodaRangeError) as info:
        goda_pressure(**{**WAVE, **change})
    assert info.value.key == key
    assert phrase in str(info.value)


def test_goda_accepted_at_the_bounds():
    # h_b = d: α₂ = 0 (no effect of the mound), the bound itself.
    assert goda_pressure(**WAVE, breaking_depth=0.13).alpha2 == 0.0
    # The breaking limit itself, and between the limits at h and at h_b > h (the design
    # wave is the wave at h_b, Goda 2000 §4.2).
    limit = breaking_height(1.4, 0.32)
    goda_pressure(**{**WAVE, "wave_height": limit})
    goda_pressure(**{**WAVE, "wave_height": 0.35}, breaking_depth=0.5)
    assert limit < 0.35 < breaking_height(1.4, 0.5)


def test_breaking_limit_in_deep_and_shallow_water():
    # Goda's breaker index, H_b = 0.17 L₀ (1 − exp(−1.5 π h/L₀ (1 + 15 tan^(4/3) θ))):
    # deep water, the steepness limit 0.17 L₀; shallow water, 0.17 · 1.5π (1 + 15 ·
    # 0.1^(4/3)) h = 1.359 h (tan θ = 1/10; relative error x/2, x = 1.5π h/L₀ (1 + ...) =
    # 5e-8 at T = 1000 s, h = 1 cm).
    L0 = G / (2 * math.pi)
    assert breaking_height(1.0, 1000.0) == pytest.approx(0.17 * L0, rel=1e-15)
    shallow = 0.17 * 1.5 * math.pi * (1 + 15 * 0.1 ** (4 / 3))
    assert breaking_height(1000.0, 0.01) / 0.01 == pytest.approx(shallow, rel=1e-7)
    assert 1.35 < shallow < 1.36
    # Goda's (2000) p. 140 example (H_max = 8.05 m, T = 11.4 s, h = 10.1 m, h_b = 10.4 m)
    # is inside it; a flat-bottom limit (tan θ = 0, 7.2 m) would have refused it.
    assert breaking_height(11.4, 10.4) > 8.05 > breaking_height(11.4, 10.1, slope=0.0)


def test_goda_in_deep_water_without_overflow():
    # T = 0.1 s at h = 1000 m (kh = 4e5; cosh, sinh of it overflow): α₁ = 0.6, α₃ = 1 −
    # h'/h and p₂ = 0 exactly; the extended formula's α_I = 0 (B_M/L = 6.4e4: 1/cosh δ₁
    # with δ₁ ≈ 9e5), so α* = α₂.
    g = goda_pressure(0.002, 0.1, 1000.0, 0.13, 0.13, 0.072)
    assert (g.alpha1, g.p2) == (0.6, 0.0)
    assert g.alpha3 == pytest.approx(1 - 0.13 / 1000, rel=1e-15)
    assert math.isfinite(g.force) and g.force > 0
    e = goda_pressure(0.002, 0.1, 1000.0, 0.13, 0.13, 0.072, impulsive=True,
                      berm_width=1000.0)
    assert e.alpha_impulsive == 0.0 and e.alpha_star == e.alpha2
    # Shallow water the other way, T = 1e4 s at h = 1 m: α₁ → 1.1 − x²/6 with x = 4πh/L =
    # 4e-4 (2.7e-8 off), α₃ → 1 − (h'/h) x²/8 (1e-8 off).
    s = goda_pressure(0.1, 1.0e4, 1.0, 0.5, 0.4, 0.2)
    assert s.alpha1 == pytest.approx(1.1, abs=4e-8) and s.alpha3 == pytest.approx(1, abs=2e-8)


def test_part_of_the_profile():
    # The exact integrals of the piecewise-linear profile over parts of the face, against
    # the trapezoidal rule on 2e5 intervals (exact for the force with the kinks on nodes;
    # the moment's quadratic integrand: O(Δz²) ≈ 1e-11 relative).
    g = goda_pressure(**WAVE)
    h1, top = g.toe_depth, g.wetted_crest
    assert g.part(-h1, top) == pytest.approx((g.force, g.moment), rel=1e-14)
    assert g.part(-1.0, 1.0) == pytest.approx((g.force, g.moment), rel=1e-14)
    assert g.part(top, 1.0) == (0.0, 0.0) and g.part(-1.0, -h1) == (0.0, 0.0)
    for lo, hi in [(-0.1, 0.05), (0.01, 0.5), (-0.2, -0.03)]:
        a, b = max(lo, -h1), min(hi, top)  # the profile is 0 off [−h', h_c*]
        z = np.union1d(np.linspace(a, b, 200001), [0.0] if a < 0 < b else [])
        p = np.array([g.front(v) for v in z])
        force, moment = g.part(lo, hi)
        assert np.trapezoid(p, z) == pytest.approx(force, rel=1e-9)
        assert np.trapezoid(p * (z + h1), z) == pytest.approx(moment, rel=1e-9)


# --- the summary reports the load the mesh receives ---------------------------------------

# Block a (0.2 × 0.1 m) on base b (0.2 × 0.05 m), the front face a_left at x = −0.1 from
# y = 0.05 to 0.15; P2 triangles of 0.025 m: every kink of the profiles below (the still
# water level, the base, the face's top) is on a node, so the facet quadrature is exact.
AW, AH, BH, SIZE = 0.2, 0.1, 0.05, 0.025


@pytest.fixture(scope="module")
def stacked(folder: pathlib.Path) -> pathlib.Path:
    return two_rectangles(folder / "stacked.msh", COMM, a=(AW, AH), b=(AW, BH), h=SIZE)


def _case(folder: pathlib.Path, mesh: pathlib.Path, name: str, swl: float, crest: float,
          toe: float = 0.075, height: float = 0.04):
    toml = f'''
[loads.wave]
group = "a_left"
time_function = "ramp"
rise = 0.01
[loads.wave.goda]
wave_height = {height}
period = 1.0
depth = 0.1
toe_depth = {toe}
berm_depth = {min(toe, 0.06)}
crest_height = {crest}
still_water_level = {swl}
'''
    path = folder / f"{name}.toml"
    if COMM.rank == 0:
        path.write_text(two_block_case(mesh, "mesh.degree = 2\nout_of_plane_length = 0.5",
                                       toml))
    COMM.barrier()
    return load_case(path)


def _applied(model, about_y: float) -> tuple[float, float]:
    """Horizontal force and its moment (clockwise, about (−AW/2, about_y)) of load 0."""
    ld = model.loads[0]
    x = ufl.SpatialCoordinate(model.mesh)
    fx = model.assemble(model.form(ld.unit[0] * ld.ds))
    m = model.assemble(model.form((x[1] - about_y) * ld.unit[0] * ld.ds))
    return fx, m


@pytest.mark.parametrize(("swl", "toe", "crest", "percent", "beyond"), [
    # the face: SWL − h' = 0.05 to SWL + h_c = 0.15, the whole profile on it
    (0.125, 0.075, 0.025, "100", []),
    # h_c above the face's top: the profile to η* = 0.06 m, cut at 0.025 m
    (0.125, 0.075, 0.1, "89.7", []),
    # the still water level 0.025 m up: the top 0.025 m of the profile off the face, and
    # the face's lowest 0.025 m below the profile's base
    (0.15, 0.075, 0.025, "77.8", ["toe_depth"]),
    # h' and h_c short of the face's ends: the whole profile on the face, the face's
    # lowest and top 0.025 m unloaded
    (0.1, 0.025, 0.025, "100", ["toe_depth", "crest_height"]),
], ids=["whole", "crest_above_face", "swl_up", "face_beyond_profile"])
def test_summary_is_the_load_the_mesh_receives(stacked, folder, swl, toe, crest, percent,
                                               beyond, caplog):
    case = _case(folder, stacked, f"goda_applied_{swl}_{toe}_{crest}", swl, crest, toe)
    data = case.read_mesh(COMM, folder / "out")
    model = case.build_model(data)
    g = case.loads[0].goda.pressure()
    fx, m = _applied(model, swl - g.toe_depth)
    summary = load_summary(case.loads[0], data, case.out_of_plane_length)
    # What the mesh receives, to round-off (the quadrature is exact: kinks on nodes).
    assert summary["horizontal_force_per_length"] == pytest.approx(fx, rel=1e-12)
    assert summary["horizontal_moment_per_length"] == pytest.approx(m, rel=1e-12)
    assert summary["goda_force_per_length"] == g.force
    assert summary["applied_fraction"] == pytest.approx(fx / g.force, rel=1e-12)
    with caplog.at_level(logging.WARNING, logger="breakwater"):
        check_goda_face(case.loads[0], data)
    messages = [r.getMessage() for r in caplog.records]
    warned = [w for w in messages if "of Goda's horizontal" in w]
    if percent == "100":
        assert fx == pytest.approx(g.force, rel=1e-12) and not warned
    else:
        assert fx < 0.9 * g.force
        assert len(warned) == 1 and f"only {percent}% of Goda's horizontal force" in warned[0]
        assert warned[0].startswith("loads.wave.goda: ")
    # A face beyond the profile's ends: one line naming the key that stops the profile.
    assert sorted(w.split(":")[0] for w in messages if "is not loaded" in w) == sorted(
        f"loads.wave.goda.{k}" for k in beyond)


def _vector_sum(model, component: int, about_y: float | None = None) -> float:
    """Σ over a component's nodes of load 0's vector b = ∫ t · w ds as the run assembles
    it (w the body's test functions): the force it applies; with ``about_y``, its moment
    Σ b_k (y_k − about_y) about that elevation (the nodal forces at their nodes)."""
    from dolfinx.fem import petsc as fem_petsc

    ld = model.loads[0]
    b = fem_petsc.assemble_vector(model.form(ufl.dot(ld.unit, model.w[ld.body]) * ld.ds))
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    owned = b.getLocalSize() // model.gdim
    nodal = b.array.reshape(-1, model.gdim)[:owned, component]
    if about_y is not None:
        y = model.bodies[ld.body].V.tabulate_dof_coordinates()[:owned, 1]
        nodal = nodal * (y - about_y)
    b.destroy()
    return COMM.allreduce(float(nodal.sum()), op=MPI.SUM)


@pytest.mark.parametrize(("swl", "toe", "crest", "height", "warned"), [
    # The still water level (y = 0.1125) and the crest (0.1375, below η* = 0.06 m
    # above the SWL: the profile ends there with a jump) halfway along 25 mm facets.
    # Measured: force 0.9997, moment 0.9990 of the exact; not warned.
    (0.1125, 0.0625, 0.025, 0.04, False),
    # A small wave: η* = 9 mm above the SWL (on a node), inside a 25 mm facet: the
    # profile's peak and its end in one facet. Measured 1.013 (force), 1.032 (moment):
    # warned, naming the worse.
    (0.1, 0.05, 0.05, 0.006, True),
], ids=["jump_at_the_crest", "small_wave"])
def test_summary_is_what_the_facets_apply_with_kinks_inside_facets(
        stacked, folder, caplog, swl, toe, crest, height, warned):
    # The run's load vectors integrate a kink or a jump of the profile inside a facet
    # with their facet quadrature, not exactly. The summary reports what they apply (the
    # sum of the assembled vector's x entries, and its nodal moment about SWL − h', to
    # 1e-12: the same quadrature), the exact integrals beside it (goda_applied), and
    # the ratios; a ratio off 1 by more than 1 % is warned about when the case is built.
    from breakwater.casefile.godaface import goda_applied

    case = _case(folder, stacked, f"goda_kinks_{height}", swl, crest, toe, height)
    with caplog.at_level(logging.WARNING, logger="breakwater"):
        built = case.build(COMM)
    info = built.extra["loads"]["wave"]
    model = built.model
    exact = goda_applied(case.loads[0], model.mesh_data)
    fx = _vector_sum(model, 0)
    m = _vector_sum(model, 0, exact.profile[0])
    assert info["horizontal_force_per_length"] == pytest.approx(abs(fx), rel=1e-12)
    assert info["horizontal_moment_per_length"] == pytest.approx(abs(m), rel=1e-12)
    assert info["exact_force_per_length"] == exact.force
    assert info["exact_moment_per_length"] == exact.moment
    assert info["face_fraction"] == pytest.approx(abs(fx) / exact.force, rel=1e-12)
    assert info["face_moment_fraction"] == pytest.approx(abs(m) / exact.moment, rel=1e-12)
    worst = max(abs(info["face_fraction"] - 1), abs(info["face_moment_fraction"] - 1))
    assert worst > 1e-4  # the quadrature is not exact here
    lines = [w for w in info.get("warnings", []) if "of the profile over the loaded face" in w]
    assert (worst > 0.01) == warned and len(lines) == int(warned)
    if warned:
        assert lines[0].startswith("loads.wave.goda: the facets apply 103.2% of the moment")


def test_profile_off_the_face_is_refused(stacked, folder):
    # Still water at y = 0.5: the profile (0.425 to 0.45) misses the face (0.05 to 0.15).
    case = _case(folder, stacked, "goda_off", 0.5, 0.025)
    data = case.read_mesh(COMM, folder / "out")
    with pytest.raises(CaseError, match=r"^loads\.wave\.goda\.still_water_level: the "
                       r"pressure profile \(y = 0\.425 to 0\.525 m.*misses the loaded face "
                       r"\(a_left: y = 0\.05 to 0\.15 m\): no wave load"):
        case.build_model(data)


# --- a study of a Goda case ---------------------------------------------------------------

STUDY_CASE = '''extends = "goda"
name = "goda_wave_study"
calibration.enabled = false
bodies.mound.shear_modulus = 2.28e6
mesh.refinement = 0.5
[loads.impact]
enabled = false
[loads.wave]
group = "caisson_front"
groups = ["impact"]
time_function = "ramp"
rise = 0.01
[loads.wave.goda]
wave_height = 0.18
period = 1.4
depth = 0.32
toe_depth = 0.13
berm_depth = 0.13
crest_height = 0.072
still_water_level = 0.32
[time]
end_time = 2e-4
[output]
field_interval = 0
figures = false
'''

STUDY = '''base = "wave.toml"
[zip]
"loads.wave.goda.depth" = [0.32, 1000.0, 0.32]
"loads.wave.goda.still_water_level" = [0.32, 0.32, 1.5]
'''


def test_study_runs_the_other_points(shared_dir, capsys):
    # 1000 m of water raised OverflowError while the study read its points (a traceback,
    # no case ran); the still water level 1.5 m puts the profile off the caisson's face,
    # which only the mesh shows: those points fail alone, with their one-line error.
    if COMM.rank == 0:
        (shared_dir / "wave.toml").write_text(STUDY_CASE)
        (shared_dir / "study.toml").write_text(STUDY)
    COMM.barrier()
    out = shared_dir / "out"
    assert cli.main(["sweep", str(shared_dir / "study.toml"), "--out", str(out), "-q"]) == 1
    assert "Traceback" not in capsys.readouterr().err
    with open(out / TABLE, newline="") as f:
        rows = list(csv.DictReader(f))
    status = {(float(r["loads.wave.goda.depth"]), float(r["loads.wave.goda.still_water_level"])):
              (r["status"], r["error"]) for r in rows}
    assert {k: s for k, (s, _) in status.items()} == {
        (0.32, 0.32): "finished", (1000.0, 0.32): "finished", (0.32, 1.5): "failed"}
    error = status[(0.32, 1.5)][1]
    assert "loads.wave.goda.still_water_level: the pressure profile" in error
    assert "\n" not in error
