"""Goda's wave pressure on 3D meshes: the same p(y) across the face's width.

The meshes are :func:`blocks3d.block_pair`'s: block ``a`` (W × AH) on block ``b`` (W × BH)
in 2D (quadrilaterals), extruded along z over T (hexahedra) or meshed with tetrahedra.
The Goda table is :mod:`test_loads`'s (Goda 1974/2000: the formula of
:mod:`breakwater.loads.wavepressure`) on the front face ``a_left`` (x = −W/2, y = BH to
BH + AH), with its uplift under ``a`` on ``interface``. Element size 0.025 m: every
kink of the profile (its base SWL − h', the SWL, its crest) is on a node of the hexahedra,
so that the facet quadrature integrates it exactly there.
"""

from __future__ import annotations

import logging
import pathlib
import sys
import time
from typing import Any

import numpy as np
import pytest
import ufl
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)
from breakwater.casefile.case import CaseError, load_case
from breakwater.casefile.godaface import (
    check_goda_face,
    facet_triangles,
    goda_applied,
    section_integrals,
)
from breakwater.casefile.meshloads import load_summary
from breakwater.model.mesh import read_mesh
from breakwater.model.model import ContactModel
from breakwater.stepping.gn22 import GN22, GN22Parameters, solve_static

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from blocks3d import block_pair, slab_against_2d

COMM = MPI.COMM_WORLD

W, AH, BH, SIZE = 0.2, 0.1, 0.05, 0.025  # blocks' width, heights and element size (m)
T = 0.05                                 # thickness of the 3D block (m)
SWL = 0.125                              # still water level (y): h' = 0.075, h_c = 0.025


def _goda(swl: float = SWL, toe: float = SWL - BH, crest: float = BH + AH - SWL,
          rise: float = 5e-4) -> str:
    return f'''
[loads.wave]
group = "a_left"
time_function = "ramp"
rise = {rise}
[loads.wave.goda]
wave_height = 0.04
period = 1.0
depth = 0.1
toe_depth = {toe}
berm_depth = {min(toe, 0.06)}
crest_height = {crest}
still_water_level = {swl}
uplift_group = "interface"
'''


def _case(folder: pathlib.Path, mesh: pathlib.Path, name: str, loads: str, dim: int = 3,
          density: float = 2000.0, end_time: float = 1e-3) -> pathlib.Path:
    """A case of block a on b (friction 0.5, b_bottom fixed); 3D: u_z held on the sides."""
    gravity = "[0.0, -9.81, 0.0]" if dim == 3 else "[0.0, -9.81]"
    sides = '[fixed.a_sides]\ncomponents = [2]\n[fixed.b_sides]\ncomponents = [2]\n' \
        if dim == 3 else ""
    path = folder / f"{name}.toml"
    if COMM.rank == 0:
        path.write_text(f'''name = "{name}"
gravity = {gravity}
mesh.source = "{mesh}"
mesh.degree = 2
[bodies.a]
density = {density}
poisson = 0.25
young_modulus = 1e8
[bodies.b]
density = 2000.0
poisson = 0.25
young_modulus = 1e9
[contact.interface]
slave = "a"
master = "b"
penalty = 1e12
friction = 0.5
[fixed.b_bottom]
{sides}[time]
dt = 1e-4
end_time = {end_time}
[output]
directory = "{folder / name}"
{loads}
''')
    COMM.barrier()
    return path


@pytest.fixture(scope="module")
def hexahedra(folder: pathlib.Path) -> pathlib.Path:
    return block_pair(folder / "hex.msh", COMM, W, (AH, BH), SIZE, thickness=T, layers=2)


def _resultants(model: ContactModel, k: int, about: tuple[float, float]
                ) -> tuple[np.ndarray, float]:
    """Force (x, y, z) and moment about the z-parallel line through ``about`` (x, y),
    counter-clockwise, of model load k at unit amplitude."""
    ld = model.loads[k]
    x = ufl.SpatialCoordinate(model.mesh)
    t = ld.unit
    force = np.array([model.assemble(model.form(t[i] * ld.ds)) for i in range(3)])
    arm = (x[0] - about[0], x[1] - about[1])
    m = model.assemble(model.form((arm[0] * t[1] - arm[1] * t[0]) * ld.ds))
    return force, m


def test_section_integrals_of_tilted_triangles() -> None:
    # ∫ p(s) ℓ(s) ds = ∫ p |∇s| dA over a plane triangle (∇s the gradient of s in its
    # plane): for p = 1 the area times |∇s|, for p = s that times the centroid's s (the
    # mean of a linear function over a triangle), and the moment about s = c of p = 1,
    # the same times (s̄ − c). Random triangles in 3D, s = y, the profile wider than them;
    # 1e-12 of the value (round-off of a few operations).
    rng = np.random.default_rng(25)
    tri = rng.uniform(-1.0, 1.0, (50, 3, 3))
    s = tri[:, :, 1]
    flat = ((-5.0, 1.0), (5.0, 1.0))
    ramp = ((-5.0, -5.0), (5.0, 5.0))
    for t, st in zip(tri, s, strict=True):
        n = np.cross(t[1] - t[0], t[2] - t[0])
        area = 0.5 * np.linalg.norm(n)
        grad = np.sqrt(1.0 - (n[1] / np.linalg.norm(n)) ** 2)  # |∇y| in the plane
        mean = st.mean()
        f, m = section_integrals(t[None], st[None], flat, 0.3)
        assert f == pytest.approx(area * grad, rel=1e-12)
        assert m == pytest.approx(area * grad * (mean - 0.3), rel=1e-12, abs=1e-14)
        f, _ = section_integrals(t[None], st[None], ramp, 0.0)
        assert f == pytest.approx(area * grad * mean, rel=1e-12, abs=1e-14)
    # A triangle with a horizontal edge (two vertices at the same s) and a horizontal one.
    t = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 2.0], [0.0, 1.0, 0.0]])
    assert section_integrals(t[None], t[None, :, 1], flat, 0.0)[0] == pytest.approx(1.0)
    t[:, 1] = 0.5
    assert section_integrals(t[None], t[None, :, 1], flat, 0.0) == (0.0, 0.0)
    # A profile's end an ulp off a vertex: on the goda3d mesh the face's top at y − SWL =
    # 0.392 − 0.32 = 0.07200000000000001 m, the crest h_c = 0.072 m, an interval of an
    # ulp whose midpoint rounds to its top, a horizontal edge: once a division by zero.
    top = 0.392 - 0.32
    t = np.array([[0.0, top, 0.0], [0.0, top, 1.0], [0.0, 0.0, 0.0]])
    f, _ = section_integrals(t[None], t[None, :, 1], ((-1.0, 1.0), (0.072, 1.0)), 0.0)
    assert 0.072 < top and f == pytest.approx(0.5 * top, rel=1e-12)


def test_goda_resultants_on_a_hexahedral_block(hexahedra: pathlib.Path,
                                               folder: pathlib.Path) -> None:
    # The Goda front on the block's seaward face (W across, T deep) and the uplift under
    # it: the assembled resultants are T × Goda's per-metre P, M_P (about the face's
    # base, y = SWL − h'), U and M_U (about the heel, x = +W/2), to round-off (1e-12:
    # the facet quadrature is exact, the kinks on nodes), pushing +x into the block and
    # lifting it; goda_applied and the summary report the same.
    case = load_case(_case(folder, hexahedra, "resultants", _goda()))
    data = case.read_mesh(COMM, folder / "out")
    model = case.build_model(data)
    assert len(model.loads) == 2 and model.gdim == 3
    g = case.loads[0].goda.pressure()
    assert g.eta_star == pytest.approx(0.06) and g.p4 > 0  # the crest is below η*
    force, m = _resultants(model, 0, (-W / 2, BH))
    assert force[0] == pytest.approx(T * g.force, rel=1e-12)
    assert np.abs(force[1:]).max() < 1e-12 * force[0]
    assert -m == pytest.approx(T * g.moment, rel=1e-12)
    force, m = _resultants(model, 1, (W / 2, BH))
    assert force[1] == pytest.approx(T * g.uplift_force(W), rel=1e-12)
    assert abs(force[0]) + abs(force[2]) < 1e-12 * force[1]
    assert -m == pytest.approx(T * g.uplift_moment(W), rel=1e-12)
    applied = goda_applied(case.loads[0], data)
    assert applied.force == pytest.approx(T * g.force, rel=1e-12)
    assert applied.moment == pytest.approx(T * g.moment, rel=1e-12)
    assert applied.fraction == pytest.approx(1.0, rel=1e-12)
    assert applied.width == pytest.approx(T, rel=1e-12)
    assert applied.face == pytest.approx((BH, BH + AH), rel=1e-12)
    summary = load_summary(case.loads[0], data, case.out_of_plane_length)
    assert summary["horizontal_force_per_length"] == applied.force  # N: see whole_body_keys
    assert summary["goda_force_per_metre"] == g.force
    assert summary["goda_moment_per_metre"] == g.moment
    assert "goda_force_per_length" not in summary
    assert summary["face_width"] == applied.width
    assert summary["uplift_force_per_length"] == pytest.approx(T * g.uplift_force(W),
                                                               rel=1e-12)
    assert summary["uplift_moment_per_length"] == pytest.approx(T * g.uplift_moment(W),
                                                                rel=1e-12)
    # The quadrilateral facets are split along their diagonal (dolfinx's vertex order
    # (0, 0), (1, 0), (0, 1), (1, 1)): the two halves of a facet turn the same way.
    tri = facet_triangles(data, ("a_left",))
    half = len(tri) // 2
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert (np.einsum("ij,ij->i", normal[:half], normal[half:]) > 0).all()


def test_goda_applied_on_tetrahedra(folder: pathlib.Path) -> None:
    # Unstructured triangles on the face, the profile's kinks inside them: goda_applied
    # still integrates the profile exactly over the facets, T × P and T × M_P (1e-12).
    mesh = block_pair(folder / "tet.msh", COMM, W, (AH, BH), 0.03, thickness=T,
                      tetrahedra=True)
    case = load_case(_case(folder, mesh, "tetrahedra", _goda()))
    data = read_mesh(mesh, COMM)
    g = case.loads[0].goda.pressure()
    applied = goda_applied(case.loads[0], data)
    assert applied.force == pytest.approx(T * g.force, rel=1e-12)
    assert applied.moment == pytest.approx(T * g.moment, rel=1e-12)
    assert applied.fraction == pytest.approx(1.0, rel=1e-12)


def test_goda_on_the_builtin_goda3d_mesh(folder: pathlib.Path) -> None:
    # docs/loads.md's design wave on the built-in Goda meshes, 2D and 3D (the 205 mm
    # block across the flume; its front face caisson_front and the bolt's patch impact,
    # the crest an ulp off the face's top): the 3D face receives the 2D one's force,
    # moment and uplift per metre times the block's length, 0.205 m (1e-12), the whole
    # profile (fraction 1), its width 0.205 m.
    goda = """
[loads.impact]
enabled = false
[loads.wave]
group = "caisson_front"
groups = ["impact"]
time_function = "ramp"
rise = 0.05
[loads.wave.goda]
wave_height = 0.18
period = 1.4
depth = 0.32
toe_depth = 0.13
berm_depth = 0.13
crest_height = 0.072
still_water_level = 0.32
uplift_group = "interface"
"""
    out = {}
    for base in ("goda", "goda3d"):
        path = folder / f"builtin_{base}.toml"
        if COMM.rank == 0:
            path.write_text(f'extends = "{base}"\n{goda}')
        COMM.barrier()
        case = load_case(path)
        data = case.read_mesh(COMM, folder / f"builtin_{base}")
        load = next(ld for ld in case.loads if ld.name == "wave")
        out[base] = load_summary(load, data, case.out_of_plane_length)
    two, three = out["goda"], out["goda3d"]
    for key in ("horizontal_force", "horizontal_moment", "uplift_force", "uplift_moment"):
        ratio = three[f"{key}_per_length"] / two[f"{key}_per_length"]
        assert ratio == pytest.approx(0.205, rel=1e-12), key
    assert three["applied_fraction"] == pytest.approx(1.0, rel=1e-12)
    assert three["face_width"] == pytest.approx(0.205, rel=1e-12)
    assert three["goda_force_per_metre"] == two["goda_force_per_length"]


def test_slab_is_the_2d_model_under_goda(hexahedra: pathlib.Path,
                                         folder: pathlib.Path) -> None:
    # The 2D mesh extruded into the 3D slab, u_z = 0 on both its faces z = 0 and T: the
    # 2D solution, constant in z, is the 3D discrete one (tests/test_threed.py
    # test_plane_strain_slab_is_the_2d_model), so the same Goda table (front and uplift,
    # ramped in over 0.5 ms) gives the 2D history to Newton's tolerance: 1e-6 of the
    # largest value, as there (measured 2e-11 in u, 4e-11 in v). Block a is light (200
    # kg/m³: μ W' = 20 N/m against P = 45 N/m less the uplift), so that it slides.
    two = block_pair(folder / "slab2d.msh", COMM, W, (AH, BH), SIZE)
    steppers = []
    for dim, mesh in ((2, two), (3, hexahedra)):
        case = load_case(_case(folder, mesh, f"slab{dim}", _goda(), dim, density=200.0))
        model = case.build_model(case.read_mesh(COMM, folder / "out"))
        u, _ = solve_static(model)
        stepper = GN22(model, 1e-4, GN22Parameters())
        stepper.initialise(u)
        steppers.append(stepper)

    worst, slide = slab_against_2d(steppers[0], steppers[1], 12)
    if COMM.rank == 0:
        print(f"\nGoda slab: slide {slide:.4e} m; 3D vs 2D, relative: {worst}")
    # It slid: sticking, the regularised law (χ = 1e-10 m/s) lets the interface's sides
    # move apart by less than χ t = 1.2e-13 m.
    assert slide > 1e-7
    for field, error in worst.items():
        assert error <= 1e-6, field


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
def test_part_of_the_profile_on_the_face(hexahedra: pathlib.Path, folder: pathlib.Path,
                                         swl: float, toe: float, crest: float, percent: str,
                                         beyond: list[str], caplog: pytest.LogCaptureFixture
                                         ) -> None:
    # As tests/test_goda_validity.py in 2D (the same percentages: the face is a
    # rectangle, its width T): the summary is what the mesh receives (1e-12), the
    # fraction is the part of P between the face's elevations (Goda's formula
    # integrated by hand below), warned once when below 1.
    name = f"part_{swl}_{toe}_{crest}"
    case = load_case(_case(folder, hexahedra, name, _goda(swl, toe, crest)))
    data = case.read_mesh(COMM, folder / "out")
    model = case.build_model(data)
    g = case.loads[0].goda.pressure()
    force, m = _resultants(model, 0, (-W / 2, swl - toe))
    summary = load_summary(case.loads[0], data, case.out_of_plane_length)
    assert summary["horizontal_force_per_length"] == pytest.approx(force[0], rel=1e-12)
    assert summary["horizontal_moment_per_length"] == pytest.approx(-m, rel=1e-12)
    # The part of the profile between y = BH and BH + AH, by hand: the trapezoid below
    # the SWL (from max(BH, SWL − h')) plus the one above (to min(top, SWL + h_c*)).
    def p(z: float) -> float:
        return g.p1 + (g.p3 - g.p1) * (-z / toe) if z < 0 else g.p1 * (1 - z / g.eta_star)
    lo, hi = max(BH - swl, -toe), min(BH + AH - swl, g.wetted_crest)
    part = 0.5 * (p(lo) + g.p1) * -lo + 0.5 * (g.p1 + p(hi)) * hi
    assert summary["applied_fraction"] == pytest.approx(part / g.force, rel=1e-12)
    assert force[0] == pytest.approx(T * part, rel=1e-12)
    with caplog.at_level(logging.WARNING, logger="breakwater"):
        check_goda_face(case.loads[0], data)
    messages = [r.getMessage() for r in caplog.records]
    warned = [w for w in messages if "of Goda's horizontal" in w]
    if percent == "100":
        assert force[0] == pytest.approx(T * g.force, rel=1e-12) and not warned
    else:
        assert len(warned) == 1 and f"only {percent}% of Goda's horizontal force" in warned[0]
        assert warned[0].startswith("loads.wave.goda: ") and " N, " in warned[0]
    assert sorted(w.split(":")[0] for w in messages if "is not loaded" in w) == sorted(
        f"loads.wave.goda.{k}" for k in beyond)


def test_profile_off_the_face_is_refused(hexahedra: pathlib.Path,
                                         folder: pathlib.Path) -> None:
    # The still water level 10 m above the block: the profile misses its face (one line).
    path = _case(folder, hexahedra, "off", _goda(swl=10.0))
    with pytest.raises(CaseError) as info:
        load_case(path).build(COMM)
    message = str(info.value)
    assert "loads.wave.goda.still_water_level: the pressure profile" in message
    assert "\n" not in message


def test_a_3d_goda_case_runs(hexahedra: pathlib.Path, folder: pathlib.Path) -> None:
    # The user path: a 3D case file with a [goda] table runs; its summary gives the
    # whole face's force (N) as applied, the formula's P per metre, no per-length key;
    # the force applied at the last step end (the ramp at 1) is T × P (1e-12).
    from breakwater.run import simulation

    path = _case(folder, hexahedra, "run3d", _goda(), end_time=6e-4)
    built = load_case(path).build(COMM)
    summary = simulation.run(built.model, built.time, built.output,
                             extra_summary=built.extra, report=False)
    assert summary["finished"] and summary["dimension"] == 3
    wave = summary["loads"]["wave"]
    g = load_case(path).loads[0].goda.pressure()
    assert wave["horizontal_force"] == pytest.approx(T * g.force, rel=1e-12)
    assert wave["goda_force_per_metre"] == g.force
    assert wave["uplift_force"] == pytest.approx(T * g.uplift_force(W), rel=1e-12)
    assert not any(k.endswith("_per_length") for k in wave) and "warnings" not in wave
    final = wave["applied"]["final_force"]
    assert final[0] == pytest.approx(T * g.force, rel=1e-12)
    assert final[1] == pytest.approx(T * g.uplift_force(W), rel=1e-12)
    # The bodies' own sizes (N, kg, m³: nothing per metre): block a is W × AH × T of
    # 2000 kg/m³, b W × BH × T; the static contact carries a's weight ρ g V (1e-12:
    # the boxes' volumes are exact in any quadrature).
    sizes = summary["mesh"]["bodies"]
    for name, height in (("a", AH), ("b", BH)):
        assert sizes[name]["extent"] == pytest.approx([W, height, T], rel=1e-12)
        assert sizes[name]["volume"] == pytest.approx(W * height * T, rel=1e-12)
        assert sizes[name]["mass"] == pytest.approx(2000.0 * W * height * T, rel=1e-12)
    static = summary["static"]
    assert static["weight"] == pytest.approx(9.81 * 2000.0 * W * AH * T, rel=1e-12)
    assert static["contact_resultant"] == pytest.approx(static["weight"], rel=1e-9)


# --- a storm in 3D -----------------------------------------------------------------------
#
# Each wave's load made here from Goda's pressures, as tests/test_stormload.py does: the
# front shape Goda's profile / p₁, p₁(τ) a triangle 0 → p₁ → 0 over 50 ms, p_u(τ) likewise.

STORM_SITE = f'''
depth = 0.1
toe_depth = {SWL - BH}
berm_depth = 0.06
crest_height = {BH + AH - SWL}
still_water_level = {SWL}
uplift_group = "interface"
'''
PULSE = 0.05


def _wave_loads(storm: Any, base_width: float) -> tuple[Any, ...]:
    """StormCase.wave_loads's stand-in: each wave's Goda shape, p₁ and p_u triangles."""
    from breakwater.loads.signals import Table
    from breakwater.loads.wavepressure import goda_pressure
    from breakwater.storms.waves import WaveLoad

    out = []
    for w in storm.waves_train.waves:
        λ1, λ2, λ3 = storm.factors
        g = goda_pressure(w.height, w.period, storm.depth, storm.toe_depth, storm.berm_depth,
                          storm.crest_height, storm.angle, storm.breaking_depth,
                          (λ1, λ2, λ3), storm.density, storm.gravity)
        out.append(WaveLoad(w, tuple((z, p / g.p1) for z, p in g.front_points()),
                            Table((0.0, 0.5 * PULSE, PULSE), (0.0, g.p1, 0.0)),
                            Table((0.0, 0.5 * PULSE, PULSE), (0.0, g.uplift, 0.0)), PULSE))
    return tuple(out)


@pytest.mark.timeout(300)
def test_storm_on_the_slab_is_the_2d_storm(hexahedra: pathlib.Path, folder: pathlib.Path,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    # Two waves through the storm path on the 2D model and on its 3D slab (u_z = 0 on both
    # faces; H ≥ 0.017 m: η* = 1.5 H above the crest, so that every kink of the front
    # shapes is on a node and both quadratures are exact; Δt = 5 ms, 10 steps per
    # wave's force): the slab's solution is the 2D one, constant in z, so the base's pair probes
    # (in 3D on the base's mid-plane z = T/2) give the 2D history, and the per-wave record
    # (sliding, rocking, contact pressure, the peak force per metre, the rigid block's
    # sliding from M and W' per metre of the caisson's length T) the 2D one: 1e-6 of each
    # column's largest value (Newton's tolerance, as test_slab_is_the_2d_model_under_goda).
    # The front force per unit p₁ is T times the 2D one (1e-12), the fractions the same.
    # A light block (g = 0.5 m/s², μ = 0.1) so that the small waves slide it.
    from breakwater.casefile.stormcase import StormCase
    from breakwater.common.files import read_history
    from breakwater.outputs.stormrecord import read_waves
    from breakwater.run import simulation

    monkeypatch.setattr(StormCase, "wave_loads", _wave_loads)
    two = block_pair(folder / "storm2d.msh", COMM, W, (AH, BH), SIZE)
    storm = (f"[loads.wave]\ngroup = \"a_left\"\n[loads.wave.storm]\n{STORM_SITE}"
             "waves = [[0.02, 0.3], [0.018, 0.3]]\n")
    out = {}
    for dim, mesh in ((2, two), (3, hexahedra)):
        name = f"storm{dim}"
        path = _case(folder, mesh, name, storm, dim, end_time=0.6)
        g = "[0.0, -0.5]" if dim == 2 else "[0.0, -0.5, 0.0]"
        built = load_case(path, ["time.dt=5e-3", f"gravity={g}", "output.figures=false",
                                 "contact.interface.friction=0.1"]).build(COMM)
        cpu = time.process_time()
        summary = simulation.run(built.model, built.time, built.output,
                                 extra_summary=built.extra, report=False)
        if COMM.rank == 0:
            print(f"\n{dim}D storm: {time.process_time() - cpu:.1f} s CPU")
        assert summary["finished"] and summary["storm"]["waves_finished"] == 2
        out[dim] = (summary, read_history(folder / name / "history.csv"),
                    read_waves(folder / name / "waves.csv"))
    (s2, h2, w2), (s3, h3, w3) = out[2], out[3]
    for a, b in zip(s2["loads"]["wave"]["storm"]["waves"], s3["loads"]["wave"]["storm"]["waves"],
                    strict=True):
        assert b["front_force_per_p1"] == pytest.approx(T * a["front_force_per_p1"], rel=1e-12)
        for key in ("face_fraction", "profile_fraction"):
            assert b[key] == pytest.approx(a[key], rel=1e-12)
    assert s3["loads"]["wave"]["storm"]["record"]["breakwater_length"] == pytest.approx(T)
    probes = [c for c in h2 if c.startswith("wave_base_")]
    assert len(probes) == 18 and all(c in h3 for c in probes)  # 3 × (slip, opening, u)

    def column(h: dict[str, np.ndarray], c: str) -> np.ndarray:
        # A 3D pair probe's slip is the tangential slip's magnitude; the 2D one's signed.
        return np.abs(h[c]) if c.endswith("_slip") else h[c]

    worst = {c: float(np.abs(column(h3, c) - column(h2, c)).max() / np.abs(h2[c]).max())
             for c in probes}
    for c in ("sliding", "cumulative_sliding", "rocking", "max_contact_pressure",
              "peak_force_per_length", "rigid_sliding"):
        worst[c] = float(np.abs(w3[c] - w2[c]).max() / np.abs(w2[c]).max())
    if COMM.rank == 0:
        print(f"\nstorm slab: sliding {w2['cumulative_sliding'][-1]:.3e} m (rigid "
              f"{s2['storm']['rigid']['total_sliding']:.3e}); worst 3D vs 2D: "
              f"{max(worst.values()):.2e} ({max(worst, key=worst.get)})")
    assert w2["cumulative_sliding"][-1] > 1e-6 and s2["storm"]["rigid"]["total_sliding"] > 0
    for c, error in worst.items():
        assert error <= 1e-6, c
