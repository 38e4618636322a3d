"""Case files: the default Goda case, overrides, round trips, bad cases, loads, build."""

from __future__ import annotations

import concurrent.futures
import itertools
import math
import pathlib
import subprocess
import sys
import tempfile
import tomllib

import pytest
import tomli_w
from breakwater.meshes import GodaGeometry, generate
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mpi4py import MPI

from breakwater import cli
from breakwater.casefile.case import BUILTIN_CASES, Case, CaseError, case_reference, load_case
from breakwater.config.fields import schema_keys
from breakwater.loads.signals import Pulse, impact_velocity, pendulum_impulse
from breakwater.model.mesh import read_mesh

COMM = MPI.COMM_WORLD
BAD = pathlib.Path(__file__).parent / "bad_cases"
BAD_FILES = sorted(BAD.glob("*.toml"))


def expected(path: pathlib.Path) -> str:
    """The key phrase of a bad case's error, from its first line ``# expect: ...``."""
    first = path.read_bytes().decode("utf-8", "replace").splitlines()[0]  # c5: Latin-1
    assert first.startswith("# expect: "), path
    return first.removeprefix("# expect: ")


def write(path: pathlib.Path, data: dict) -> pathlib.Path:
    path.write_text(tomli_w.dumps(data))
    return path


# --- the default case -------------------------------------------------------------

def test_default_case_is_the_paper_case():
    case = load_case()
    assert case == load_case("goda") == load_case(BUILTIN_CASES / "goda.toml")
    assert case.name == "goda"
    caisson, mound = case.body("caisson"), case.body("mound")
    # Stickle et al. (2011) §5.3 / the paper's §5.
    assert (caisson.density, caisson.poisson, caisson.shear_modulus) == (2314.0, 0.2, 2e9)
    assert mound.poisson == 0.25 and mound.shear_modulus is None
    assert case.calibration.enabled and case.calibration.stiffness == 500e3
    (pair,) = case.contact
    assert (pair.name, pair.slave, pair.master) == ("interface", "caisson", "mound")
    assert (pair.penalty, pair.friction, pair.regularisation) == (5e8, 0.65, 1e-10)
    assert (case.damping.alpha, case.damping.beta) == (0.023, 0.023)
    assert (case.time.beta1, case.time.beta2, case.time.dt) == (0.6, 0.605, 1e-4)
    assert case.time.end_time > 0.032  # the paper's instant of maximum displacement
    assert [f.name for f in case.fixed] == ["base"]
    assert case.mesh.generated and case.mesh.goda == GodaGeometry()
    # Eq. 29: the paper prints I = 2.81 N s and 13.71 N s/m (= 2.81/0.205); the
    # unrounded I is 2.8056 N s, hence 13.686 N s/m: compare to the printed digits.
    (load,) = case.loads
    assert load.group == "impact" and load.direction == (1.0, 0.0)
    assert round(load.total_impulse, 2) == 2.81
    assert load.total_impulse / case.out_of_plane_length == pytest.approx(13.71, rel=2e-3)
    assert {p.name for p in case.output.probes} == {"gauge_top", "gauge_bottom"}
    assert {p.name for p in case.output.pair_probes} == {"corner_front", "corner_rear"}


def test_resolved_round_trip(tmp_path):
    case = load_case(None, ["time.dt=5e-5", "bodies.mound.density=1800"])
    data = case.resolved()
    text = tomli_w.dumps(data)  # TOML-serialisable (no None)
    assert tomllib.loads(text) == data
    again = load_case(write(tmp_path / "resolved.toml", data))
    assert again.resolved() == data
    assert again.time == case.time and again.bodies == case.bodies
    assert again.name == "goda"  # the name is written, not taken from the file name


def test_general_pair_master_of_several_groups_round_trip(tmp_path):
    """A general pair's master surface as a string or an array of groups, its
    integration and rotations: read, validated against the mesh, written back."""
    general = ['contact.interface.slave_surface="interface"', "output.pair_probes={}",
               "calibration.enabled=false", "bodies.mound.shear_modulus=2.3e6"]
    one = load_case(None, [*general, 'contact.interface.master_surface="interface"'])
    assert one.contact[0].master_surface == "interface"
    assert one.contact[0].integration == "segments" and one.contact[0].rotations == "finite"
    case = load_case(None, [*general, 'contact.interface.integration="nodes"',
                            'contact.interface.rotations="small"',
                            'contact.interface.master_surface=["interface", "mound_surface"]'])
    c = case.contact[0]
    assert c.master_surface == ("interface", "mound_surface")
    assert (c.integration, c.rotations) == ("nodes", "small")
    data = case.resolved()
    assert data["contact"]["interface"]["master_surface"] == ["interface", "mound_surface"]
    assert load_case(write(tmp_path / "r.toml", data)).resolved() == data


def test_resolved_user_mesh_round_trip(tmp_path):
    msh = generate(tmp_path / "m.msh", comm=MPI.COMM_SELF)
    case = load_case(None, [f'mesh.source="{msh}"'])
    data = case.resolved()
    assert data["mesh"]["source"] == str(msh.resolve()) and "goda" not in data["mesh"]
    assert load_case(write(tmp_path / "r.toml", data)).resolved() == data


# --- overrides --------------------------------------------------------------------

def test_overrides_by_name_index_and_table():
    case = load_case(None, ["contact.0.friction=0.5", "bodies.caisson.density=2400",
                            "time={dt=2e-4, end_time=0.01}", "name=variant",
                            "loads.impact.pendulum.mass=6", "loads.impact.shape=half-sine",
                            "gravity=[0, -10]"])
    assert case.contact[0].friction == 0.5
    assert case.body("caisson").density == 2400.0
    assert (case.time.dt, case.time.end_time, case.time.beta1) == (2e-4, 0.01, 0.6)
    assert case.name == "variant" and case.output_directory == pathlib.Path("results/variant")
    assert case.loads[0].pendulum.mass == 6.0 and case.loads[0].shape == "half-sine"
    assert case.gravity == (0.0, -10.0)


def test_override_mesh_path_is_relative_to_the_working_directory(tmp_path, monkeypatch):
    generate(tmp_path / "m.msh", comm=MPI.COMM_SELF)
    monkeypatch.chdir(tmp_path)
    case = load_case(None, ["mesh.source=m.msh"])
    assert pathlib.Path(case.mesh.source) == (tmp_path / "m.msh").resolve()


@pytest.mark.serial  # the parser alone (no MPI): once is enough
@pytest.mark.parametrize(("override", "phrase"), [
    ("time.dtt=1", "unknown key 'time.dtt' (did you mean 'dt'?)"),
    ("bodies.mond.density=1", "no entry 'mond' in bodies (did you mean 'mound'?)"),
    ("contact.7.friction=1", "no entry '7' in contact"),
    ("time.dt.x=1", "'time.dt' is not a table"),
    ("time.dt", "expected key=value"),
    ("time.dt=abc", "--set: time.dt: expected a number, got 'abc'"),
    ("bodies.mound.poisson=0.5", "--set: bodies.mound.poisson: Poisson's ratio"),
    ("dt=1e-4", "did you mean 'time.dt'?"),
    # Keys are case sensitive (refused) but suggested without case (was 'time', 'tolerance').
    ("DT=1e-4", "did you mean 'time.dt'?"),
    ("time.DT=1e-4", "did you mean 'time.dt'?"),
    # A check of two keys blames the --set of either (not the case file whose dt it is).
    ("time.end_time=5e-5", "--set: time.dt: must be smaller than end_time"),
    ("time.max_steps=10", "--set: time.end_time: end_time / dt"),
    ("time.beta1=0.7", "--set: time.beta2: beta2 = 0.605 < beta1 = 0.7"),
    # The mesh's size: its refinement, or a size in mesh.goda (was blamed on goda.toml).
    ("mesh.refinement=1e3", "--set: mesh.max_elements: refinement 1000 with the mesh.goda "
     "dimensions and element sizes makes about 6.01e+08 triangles"),
    ("mesh.goda.mound_element_size=1e-5", "--set: mesh.max_elements: refinement 1 with "
     "the mesh.goda dimensions and element sizes makes about 3.42e+09 triangles"),
])
def test_bad_overrides(override, phrase):
    with pytest.raises(CaseError) as info:
        load_case(None, [override])
    assert phrase in str(info.value)
    assert "\n" not in str(info.value)


# --- extends ------------------------------------------------------------------------

def test_extends_merges_tables(tmp_path):
    path = tmp_path / "soft.toml"
    path.write_text('extends = "goda"\n[contact.interface]\nfriction = 0.3\n')
    case = load_case(path)
    assert case.name == "soft" and case.contact[0].friction == 0.3
    assert case.contact[0].penalty == 5e8  # the rest of the table is goda's
    assert case.bodies == load_case().bodies


# --- bad cases --------------------------------------------------------------------

def test_enough_bad_cases():
    assert len(BAD_FILES) >= 20


@pytest.mark.serial  # the parser alone (no MPI): once is enough
@pytest.mark.parametrize("path", BAD_FILES, ids=lambda p: p.stem)
def test_bad_case_message(path):
    with pytest.raises(CaseError) as info:
        load_case(path)
    message = str(info.value)
    assert expected(path) in message
    assert "\n" not in message
    assert path.name in message.split(": ")[0]  # the file is named first


# show-case reads the case alone: the rank-dependent line on this path (the error printed by
# rank 0) runs on 2 ranks in tests/test_bad_runs.py, through the same cli.main.
@pytest.mark.serial
@pytest.mark.parametrize("path", BAD_FILES, ids=lambda p: p.stem)
def test_bad_case_through_main(path, capsys):
    assert cli.main(["show-case", str(path)]) == 2
    err = capsys.readouterr().err
    if COMM.rank == 0:
        assert err.count("\n") == 1 and expected(path) in err
        assert "Traceback" not in err


# One bad case of each kind also goes through a real ``python -m breakwater`` process
# (about 0.5 s each; every file goes through cli.main in test_bad_case_through_main).
SUBPROCESS_CASES = [BAD / f"{name}.toml" for name in (
    "01_unknown_top_key", "02_misspelt_body_key", "04_poisson_half", "12_dt_beyond_end",
    "14_beta1_below_half", "15_unknown_body_group", "16_mesh_file_missing",
    "18_wrong_type", "26_invalid_toml", "41_circular_extends")]


@pytest.mark.serial
def test_bad_cases_through_the_cli_subprocess():
    if COMM.size > 1:
        pytest.skip("subprocess CLI tests run serially")

    def run(path: pathlib.Path) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "breakwater", "show-case", str(path)],
                              capture_output=True, text=True, timeout=120)

    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        results = dict(zip(SUBPROCESS_CASES, pool.map(run, SUBPROCESS_CASES), strict=True))
    for path, r in results.items():
        assert r.returncode == 2, (path.name, r.stderr)
        assert expected(path) in r.stderr, (path.name, r.stderr)
        assert "Traceback" not in r.stderr and r.stderr.count("\n") == 1, r.stderr
        assert r.stdout == ""


def test_unreadable_mesh(tmp_path):
    bad = tmp_path / "broken.msh"
    bad.write_text("this is not a mesh\n")
    with pytest.raises(CaseError, match=r"--set: mesh.source: cannot read the mesh .*broken"):
        load_case(None, [f'mesh.source="{bad}"'])


def test_user_mesh_groups_are_checked(tmp_path):
    msh = generate(tmp_path / "user.msh", comm=MPI.COMM_SELF)
    case = load_case(None, [f'mesh.source="{msh}"'])
    assert case.mesh.source == str(msh.resolve())
    with pytest.raises(CaseError, match=r"no facet .* 'bottom' in .*user.msh .*it has: base"):
        load_case(None, [f'mesh.source="{msh}"', "fixed.bottom={components=[1]}"])


def test_geo_mesh_groups(tmp_path):
    geo = tmp_path / "blocks.geo"
    geo.write_text("""
Point(1) = {0, 0, 0, 0.1}; Point(2) = {1, 0, 0, 0.1}; Point(3) = {1, 1, 0, 0.1};
Point(4) = {0, 1, 0, 0.1}; Point(5) = {1, 2, 0, 0.1}; Point(6) = {0, 2, 0, 0.1};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Line(5) = {3, 5}; Line(6) = {5, 6}; Line(7) = {6, 4};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Curve Loop(2) = {-3, 5, 6, 7}; Plane Surface(2) = {2};
Physical Surface("ground") = {1}; Physical Surface("block") = {2};
Physical Curve("joint") = {3}; Physical Curve("floor") = {1};
""")
    data = {"mesh": {"source": "blocks.geo"},
            "bodies": {"block": {"density": 2000.0, "poisson": 0.2, "shear_modulus": 1e9},
                       "ground": {"density": 1800.0, "poisson": 0.3, "shear_modulus": 1e7}},
            "contact": {"joint": {"slave": "block", "master": "ground", "penalty": 1e9}},
            "fixed": {"floor": {}},
            "time": {"dt": 1e-4, "end_time": 1e-2}}
    case = load_case(write(tmp_path / "blocks.toml", data))
    assert case.name == "blocks" and case.fixed[0].components is None  # all
    data["fixed"] = {"flor": {}}
    with pytest.raises(CaseError, match=r"blocks.toml: fixed.flor: .*did you mean 'floor'"):
        load_case(write(tmp_path / "blocks.toml", data))


BLOCKS_GEO = """
Point(1) = {0, 0, 0, 0.25}; Point(2) = {1, 0, 0, 0.25}; Point(3) = {1, 1, 0, 0.25};
Point(4) = {0, 1, 0, 0.25}; Point(5) = {1, 2, 0, 0.25}; Point(6) = {0, 2, 0, 0.25};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Line(5) = {3, 5}; Line(6) = {5, 6}; Line(7) = {6, 4};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Curve Loop(2) = {-3, 5, 6, 7}; Plane Surface(2) = {2};
Physical Surface("ground") = {1}; Physical Surface("block") = {2};
Physical Curve("joint") = {3}; Physical Curve("floor") = {1};
"""


def test_geo_is_meshed_into_the_output_folder(shared_dir):
    # A .msh of the script's name beside the user's .geo is the user's file: meshing the
    # script writes into the output folder (mesh/) and leaves it alone.
    geo, toml, mine = (shared_dir / n for n in ("blocks.geo", "blocks.toml", "blocks.msh"))
    if COMM.rank == 0:
        geo.write_text(BLOCKS_GEO)
        mine.write_text("the user's own file\n")
        write(toml, {
            "mesh": {"source": "blocks.geo"},
            "bodies": {"block": {"density": 2000.0, "poisson": 0.2, "shear_modulus": 1e9},
                       "ground": {"density": 1800.0, "poisson": 0.3, "shear_modulus": 1e7}},
            "contact": {"joint": {"slave": "block", "master": "ground", "penalty": 1e9}},
            "fixed": {"floor": {}},
            "time": {"dt": 1e-3, "end_time": 1e-2},
            "output": {"directory": str(shared_dir / "out")}})
    COMM.barrier()
    case = load_case(toml)
    assert case.mesh_file(COMM) == shared_dir / "out" / "mesh" / "blocks.msh"
    data = case.read_mesh(COMM, shared_dir / "elsewhere")
    assert {"block", "ground", "joint", "floor"} <= set(data.physical_groups)
    assert (shared_dir / "elsewhere" / "mesh" / "blocks.msh").is_file()
    assert mine.read_text() == "the user's own file\n"
    # The library reader meshes a script into a temporary folder, also not beside it.
    COMM.barrier()  # every rank has read the file
    if COMM.rank == 0:
        mine.unlink()
    COMM.barrier()
    assert read_mesh(geo, COMM).physical_groups.keys() == data.physical_groups.keys()
    COMM.barrier()
    assert not mine.exists()


def test_non_conforming_interface_is_an_input_error(shared_dir, capsys):
    # The joint is meshed twice (lines 3 and 8 over the same points): the two bodies
    # share no facet. The groups all exist, so the case loads; building the model finds
    # it, and `run` reports it as an input error naming the mesh file (exit 2).
    geo, toml = shared_dir / "split.geo", shared_dir / "split.toml"
    if COMM.rank == 0:
        geo.write_text("""
Point(1) = {0, 0, 0, 0.25}; Point(2) = {1, 0, 0, 0.25}; Point(3) = {1, 1, 0, 0.25};
Point(4) = {0, 1, 0, 0.25}; Point(5) = {1, 2, 0, 0.25}; Point(6) = {0, 2, 0, 0.25};
Point(7) = {1, 1, 0, 0.25}; Point(8) = {0, 1, 0, 0.25};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Line(5) = {7, 5}; Line(6) = {5, 6}; Line(7) = {6, 8}; Line(8) = {8, 7};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Curve Loop(2) = {8, 5, 6, 7}; Plane Surface(2) = {2};
Physical Surface("ground") = {1}; Physical Surface("block") = {2};
Physical Curve("joint") = {3}; Physical Curve("floor") = {1};
""")
        write(toml, {
            "mesh": {"source": "split.geo"},
            "bodies": {"block": {"density": 2000.0, "poisson": 0.2, "shear_modulus": 1e9},
                       "ground": {"density": 1800.0, "poisson": 0.3, "shear_modulus": 1e7}},
            "contact": {"joint": {"slave": "block", "master": "ground", "penalty": 1e9}},
            "fixed": {"floor": {}},
            "time": {"dt": 1e-3, "end_time": 1e-2}})
    COMM.barrier()
    assert cli.main(["run", str(toml), "--out", str(shared_dir / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    if COMM.rank == 0:
        assert err.count("\n") == 1 and "Traceback" not in err, err
        assert ("split.geo: contact.joint: interface 'joint' has no facet shared by two cells: "
                "a conforming pair's name is a facet group between its two bodies (such "
                "groups here: none); for surfaces meshed apart give slave_surface and "
                "master_surface") in err, err


# --- property-based tests of the parser ----------------------------------------------

# Valid ranges of some numeric fields (all satisfy the physical checks; the goda case's
# pulse, 2 ms, must last longer than the time step of 1e-4 s: LoadCase.check_time).
NUMERIC = {
    # end_time 0.15 s: at most time.max_steps = 1e6 steps
    "time.dt": st.floats(1.5e-7, 1.9e-3),
    "time.end_time": st.floats(0.02, 10.0),
    "bodies.mound.density": st.floats(1.0, 1e5),
    "bodies.caisson.shear_modulus": st.floats(1.0, 1e12),
    "bodies.caisson.poisson": st.floats(-0.99, 0.49),
    "contact.interface.friction": st.floats(0.0, 5.0),
    "contact.interface.penalty": st.floats(1e-3, 1e15),
    "damping.beta": st.floats(0.0, 1.0),
    "loads.impact.duration": st.floats(1.1e-4, 1.0),
    "output.field_interval": st.integers(0, 10**6),
    "time.newton_max_it": st.integers(1, 1000),
}


def _get(data: dict, key: str):
    for part in key.split("."):
        data = data[part]
    return data


@pytest.mark.serial  # the parser alone (no MPI): once is enough
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(sorted(NUMERIC)).flatmap(lambda k: st.tuples(st.just(k), NUMERIC[k])))
def test_numeric_overrides_round_trip(item):
    key, value = item
    case = load_case(None, [f"{key}={value!r}"])
    data = case.resolved()
    assert _get(data, key) == value
    with tempfile.TemporaryDirectory() as folder:
        again = load_case(write(pathlib.Path(folder) / "c.toml", data))
    assert again.resolved() == data


SECTIONS = {"": Case, "time.": None, "damping.": None, "bodies.mound.": None,
            "contact.interface.": None, "output.": None, "mesh.goda.": None}
KNOWN = {k.rsplit(".", 1)[-1] for k in schema_keys(Case)} | {"name"}


@pytest.mark.serial  # the parser alone (no MPI): once is enough
@settings(max_examples=60, deadline=None)
@given(st.sampled_from(sorted(SECTIONS)),
       st.text("abcdefghijklmnopqrstuvwxyz_", min_size=1, max_size=16))
def test_unknown_keys_are_rejected_with_a_suggestion(section, key):
    if key in KNOWN or key == "extends":
        return  # a real key (somewhere in the schema): not unknown
    with pytest.raises(CaseError) as info:
        load_case(None, [f"{section}{key}=1"])
    message = str(info.value)
    assert "unknown key" in message and "did you mean '" in message
    # The same key in a file.
    table: dict = {"extends": "goda"}
    node = table
    for part in section.strip(".").split(".") if section else []:
        node = node.setdefault(part, {})
    node[key] = 1
    with tempfile.TemporaryDirectory() as folder, pytest.raises(CaseError) as info:
        load_case(write(pathlib.Path(folder) / "c.toml", table))
    assert "unknown key" in str(info.value) and "did you mean '" in str(info.value)


# --- loads ---------------------------------------------------------------------------

def test_pendulum_impulse_eq29():
    # Eq. 29 by hand: ω = s0 sqrt(g/l0), I = M ω (1 + e0).
    ω = 0.25 * math.sqrt(9.81 / 3.393)
    assert impact_velocity(3.393, 0.25) == pytest.approx(ω, rel=1e-15)
    assert pendulum_impulse(5.5, 3.393, 0.25, 0.2) == pytest.approx(5.5 * ω * 1.2, rel=1e-15)
    with pytest.raises(ValueError, match="restitution"):
        pendulum_impulse(5.5, 3.393, 0.25, 1.2)


def running_impulse(p: Pulse, t: float) -> float:
    """∫ from −∞ to t of the pulse, from the formulas of its shapes (areas)."""
    s = min(max((t - p.start) / p.duration, 0.0), 1.0)  # position in the pulse
    if p.shape == "rectangular":
        fraction = s
    elif p.shape == "half-sine":  # ∫₀ˢ (π/2) sin(πσ) dσ
        fraction = 0.5 * (1.0 - math.cos(math.pi * s))
    elif s <= p.peak:  # the rising triangle: (s/peak) × s × the peak value 2, halved
        fraction = s * s / p.peak if p.peak > 0 else 0.0
    else:  # one minus the falling triangle still to come
        fraction = 1.0 - (1.0 - s) ** 2 / (1.0 - p.peak)
    return p.impulse * fraction


@pytest.mark.serial  # arithmetic alone (no MPI): once is enough
@pytest.mark.parametrize("shape", ["triangular", "rectangular", "half-sine"])
@pytest.mark.parametrize("peak", [0.0, 0.3, 0.5, 1.0])
def test_pulse_integrates_to_the_impulse(shape, peak):
    p = Pulse(13.7, 2e-3, shape, start=1e-3, peak=peak)
    assert p(0.0) == 0.0 and p(3.5e-3) == 0.0
    assert running_impulse(p, 1.0) == pytest.approx(13.7, rel=1e-14)
    # Independent check: composite Simpson on a fine grid (the shapes are smooth between
    # the peak and the ends, which are grid points: error O(h^4) or exact).
    n = 6000
    h = p.duration / n
    ts = [p.start + i * h for i in range(n + 1)]
    w = [1 if i in (0, n) else 4 if i % 2 else 2 for i in range(n + 1)]
    simpson = h / 3 * sum(wi * p(t) for wi, t in zip(w, ts, strict=True))
    assert simpson == pytest.approx(13.7, rel=1e-6)  # rectangle: end jumps cost O(h)
    assert max(p(t) for t in ts) == pytest.approx(p.maximum, rel=1e-3)
    # The pulse is the derivative of the running integral of its formulas.
    t = p.start + 0.37 * p.duration
    m = 2000
    running = sum(p(p.start + (i + 0.5) * (t - p.start) / m) for i in range(m)) \
        * (t - p.start) / m
    assert running_impulse(p, t) == pytest.approx(running, rel=1e-5, abs=1e-9)


def test_triangular_trapezoid_is_exact_on_the_step_grid():
    # The stepper samples the load at step ends: the trapezoidal sum of a triangle whose
    # start, peak and end are step ends equals its integral (piecewise linear).
    dt, p = 1e-4, Pulse(13.7, 2e-3)
    samples = [p(k * dt) for k in range(41)]
    trapezoid = dt * (sum(samples) - 0.5 * (samples[0] + samples[-1]))
    assert trapezoid == pytest.approx(13.7, rel=1e-12)


def test_reference_lists_every_key():
    text = case_reference()
    for key in ("time.dt", "bodies.<name>.density", "contact.<name>.penalty",
                "loads.<name>.pendulum.restitution", "mesh.goda.bolt_height",
                "calibration.stiffness", "output.probes.<name>.group"):
        assert f"`{key}`" in text
    assert "| `time.dt` | number | s | required |" in text
    assert "| `bodies.<name>.density` | number | kg/m³ | required |" in text
    assert "| `contact.<name>.master_surface` | string or array of string | - | — |" in text


# --- build --------------------------------------------------------------------------

def test_build_without_calibration(shared_dir):
    case = load_case(None, ["bodies.mound.shear_modulus=2.3e6", "calibration.enabled=false",
                            f'output.directory="{shared_dir}"', "mesh.refinement=0.6"])
    model, time, output, extra = case.build(COMM)
    assert (shared_dir / "mesh" / "goda.msh").is_file()
    assert [b.spec.name for b in model.bodies] == ["caisson", "mound"]
    assert model.bodies[1].spec.material.G == 2.3e6
    assert model.damping.alpha == 0.023 and tuple(model.gravity.value) == (0.0, -9.81)
    assert time.dt == 1e-4 and time.beta2 == 0.605
    g = GodaGeometry()
    probes = {p.name: p for p in output.probes}
    assert probes["gauge_top"].point == pytest.approx(g.gauge_top, abs=1e-12)
    assert probes["gauge_bottom"].body == "caisson"
    pairs = {p.name: p for p in output.pair_probes}
    assert pairs["corner_front"].pair == 0
    assert pairs["corner_rear"].point == pytest.approx(g.corner_rear, abs=1e-12)
    assert output.directory == shared_dir and output.case_name == "goda"
    # The traction pulse: ∫ traction dt × patch length = I / out-of-plane length.
    info = extra["loads"]["impact"]
    assert info["patch_length"] == pytest.approx(g.impact_patch_height, rel=1e-12)
    (load,) = model.loads
    assert load.spec.direction == (1.0, 0.0)
    amplitude = load.spec.amplitude
    # The triangle is linear between its start, peak and end: trapezoids are exact.
    knots = [amplitude.start, amplitude.start + amplitude.peak * amplitude.duration,
             amplitude.end]
    integral = sum(0.5 * (b - a) * (amplitude(a) + amplitude(b))
                   for a, b in itertools.pairwise(knots))
    assert integral * info["patch_length"] == pytest.approx(
        case.loads[0].total_impulse / 0.205, rel=1e-12)
    assert extra["mesh"]["cells"]["caisson"] > 0 and "calibration" not in extra
    assert case.resolved()["calibration"]["enabled"] is False


EXAMPLES = pathlib.Path(__file__).resolve().parents[1] / "examples"


@pytest.mark.serial  # the parser alone (no MPI): once is enough
@pytest.mark.parametrize("path", sorted(EXAMPLES.rglob("*.toml")),
                         ids=lambda p: p.relative_to(EXAMPLES).as_posix())
def test_every_example_file_reads(path: pathlib.Path, tmp_path: pathlib.Path) -> None:
    # An example a user copies must be a valid case or study file (a study: its every
    # point's case read and validated, nothing run).
    from breakwater.studies.studyfile import check_points, load_study

    if "base" in tomllib.loads(path.read_text(encoding="utf-8")):
        points, cases = check_points(load_study(path), tmp_path)
        assert points and len(points) == len(cases)
    else:
        assert isinstance(load_case(path), Case)


def test_case_file_a_spreadsheet_saved(tmp_path: pathlib.Path) -> None:
    """A case file with a byte-order mark and CRLF lines (Notepad's or Excel's "UTF-8")
    reads as without them (it was refused: "invalid TOML: Invalid statement (at line 1,
    column 1)"); saved as UTF-16, it is refused naming the encoding."""
    text = 'extends = "goda3d"\r\nname = "sheet"\r\n[time]\r\ndt = 2.0e-5\r\n'
    path = tmp_path / "sheet.toml"
    path.write_bytes(b"\xef\xbb\xbf" + text.encode())
    case = load_case(path)
    assert (case.name, case.time.dt, len(case.gravity)) == ("sheet", 2.0e-5, 3)
    path.write_bytes(text.encode("utf-16"))
    with pytest.raises(CaseError, match=r"UTF-16 text .* save the file as UTF-8"):
        load_case(path)


def test_build_with_a_communicator_of_another_type_is_refused() -> None:
    """``case.build("x")`` (or a dict, a rank number) failed in dolfinx's mesh reading
    with ``AttributeError: 'str' object has no attribute 'size'``; now one line."""
    case = load_case("goda", ["time.end_time=0.002"])
    for comm in ("x", 0, {"comm": None}):
        with pytest.raises(TypeError, match=r"^build: comm: expected an MPI communicator "
                           rf"\(e\.g\. MPI\.COMM_WORLD, or None: every rank\), got "
                           rf"{type(comm).__name__}$"):
            case.build(comm)  # type: ignore[arg-type]
