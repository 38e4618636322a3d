"""The command line (breakwater.cli): mesh, show-case, calibrate, run, errors."""

from __future__ import annotations

import subprocess
import sys
import tomllib
from typing import Any

import pytest
from mpi4py import MPI

import breakwater  # (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater.meshes import PHYSICAL_GROUPS, read

from breakwater import cli
from breakwater.casefile.case import load_case
from breakwater.config.runspec import OutputSpec, TimeSpec
from breakwater.run import simulation

COMM = MPI.COMM_WORLD


def test_mesh_to_vtu(shared_dir, capsys):
    out = shared_dir / "goda.vtu"
    assert cli.main(["mesh", "--out", str(out), "--set", "mesh.refinement=0.8"]) == 0
    assert out.is_file()
    if COMM.rank == 0:
        assert f"wrote {out}" in capsys.readouterr().out
    mesh = read(out)
    tags = {int(t) for block in mesh.cell_data["gmsh:physical"] for t in block}
    assert {PHYSICAL_GROUPS[g][1] for g in ("caisson", "mound", "interface", "impact")} <= tags


def test_mesh_bad_suffix(shared_dir, capsys):
    assert cli.main(["mesh", "--out", str(shared_dir / "goda.xyz")]) == 2
    if COMM.rank == 0:
        assert "unknown mesh file suffix" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["run", "mesh", "show-case"])
def test_a_mesh_given_as_the_case(shared_dir, capsys, command):
    # A user's own .geo given where the case file goes (python -m breakwater run my.geo):
    # it was read as TOML, "invalid TOML: Invalid statement (at line 1, column 1)".
    geo = shared_dir / "block.geo"
    if COMM.rank == 0:
        geo.write_text('SetFactory("OpenCASCADE");\nBox(1) = {0, 0, 0, 1, 1, 1};\n')
    COMM.barrier()
    out = ["--out", str(shared_dir / ("out.msh" if command == "mesh" else "out"))]
    assert cli.main([command, str(geo), *(out if command != "show-case" else [])]) == 2
    if COMM.rank == 0:
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "TOML" not in err, err
        assert "block.geo: a mesh, not a case file: name it in a case file (mesh.source = " \
               '"block.geo"' in err


def test_show_case_prints_the_resolved_case(capsys):
    assert cli.main(["show-case", "--set", "time.dt=5e-5"]) == 0
    if COMM.rank == 0:
        data = tomllib.loads(capsys.readouterr().out)
        assert data == load_case(None, ["time.dt=5e-5"]).resolved()
        assert data["time"]["dt"] == 5e-5


def test_show_case_says_it_did_not_check_the_probe_points(capsys):
    """show-case does not mesh (goda3d's mesh takes 8 s): a probe point outside the bodies
    was printed as if accepted, run refusing it only once meshed. The output now says,
    in TOML comments above the case, that the points were not checked."""
    far = 'output.probes.far={body="caisson",point=[50.0,50.0,0.0]}'
    assert cli.main(["show-case", "goda3d", "--set", far]) == 0
    if COMM.rank == 0:
        out = capsys.readouterr().out
        assert out.startswith(cli.UNMESHED_PROBES)
        assert "not checked" in out.splitlines()[1]
        data = tomllib.loads(out)  # still TOML: the note is comments
        assert data == load_case("goda3d", [far]).resolved()
        assert data["output"]["probes"]["far"]["point"] == [50.0, 50.0, 0.0]


def test_show_case_reference(capsys):
    assert cli.main(["show-case", "--reference"]) == 0
    if COMM.rank == 0:
        assert "| `time.dt` | number | s | required |" in capsys.readouterr().out


def test_bad_key_exit_2(capsys):
    assert cli.main(["show-case", "--set", "time.dtt=1e-4"]) == 2
    if COMM.rank == 0:
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "did you mean 'dt'" in err


def test_usage_error_exit_2(capsys):
    assert cli.main(["frobnicate"]) == 2
    assert cli.main(["--version"]) == 0


def test_usage_errors_help_and_version_print_once(capsys):
    """Under mpiexec every rank parses the command line: a usage error, --help and
    --version were printed by every rank (3 times on 3 ranks), a usage error on two
    lines (the usage, then the error). Now rank 0 prints, a usage error in one line."""
    assert cli.main(["study", "x.toml"]) == 2
    error = capsys.readouterr()
    assert cli.main(["mesh"]) == 2  # a subcommand's: --out is required
    mesh = capsys.readouterr()
    assert cli.main(["run", "--help"]) == 0
    usage = capsys.readouterr()
    assert cli.main(["--version"]) == 0
    version = capsys.readouterr()
    if COMM.rank == 0:
        assert error.err == ("python -m breakwater: error: argument COMMAND: invalid choice: "
                             "'study' (choose from 'run', 'mesh', 'calibrate', 'sweep', "
                             "'show-case') (see python -m breakwater --help)\n")
        assert mesh.err == ("python -m breakwater mesh: error: the following arguments are "
                            "required: --out (see python -m breakwater mesh --help)\n")
        assert usage.out.startswith("usage: python -m breakwater run")
        assert version.out == f"breakwater {breakwater.__version__}\n"
    else:
        assert [error, mesh, usage, version] == [("", "")] * 4


def test_calibrate_command(capsys):
    assert cli.main(["calibrate", "--set", "mesh.refinement=0.6"]) == 0
    if COMM.rank == 0:
        out = capsys.readouterr().out
        assert "G        =" in out and "check    K_x = 2.439" in out
    # --quiet prints G alone; a doubled target gives a stiffer mound.
    assert cli.main(["calibrate", "--quiet", "--set", "mesh.refinement=0.6"]) == 0
    G1 = float(capsys.readouterr().out) if COMM.rank == 0 else 0.0
    assert cli.main(["calibrate", "--quiet", "--target", "1e6", "--set",
                     "mesh.refinement=0.6"]) == 0
    if COMM.rank == 0:
        G2 = float(capsys.readouterr().out)
        assert G2 > 2 * G1  # K grows less than linearly with G


class FakeRun:
    """Records the arguments of simulation.run (or raises)."""

    def __init__(self, error: Exception | None = None) -> None:
        self.calls: list[dict[str, Any]] = []
        self.error = error

    def __call__(self, model, time, output, resolved_case=None, extra_summary=None,
                 report=True, resume=False):
        self.calls.append({"model": model, "time": time, "output": output,
                           "resolved_case": resolved_case, "extra": extra_summary,
                           "resume": resume})
        if self.error is not None:
            raise self.error
        return {"finished": True}


def test_run_passes_the_case_to_the_run_layer(shared_dir, monkeypatch):
    fake = FakeRun()
    monkeypatch.setattr(simulation, "run", fake)
    out = shared_dir / "run"
    assert cli.main(["run", "--out", str(out), "--no-progress", "--quiet",
                     "--set", "mesh.refinement=0.6", "--set", "time.end_time=0.01"]) == 0
    (call,) = fake.calls
    assert isinstance(call["time"], TimeSpec) and call["time"].end_time == 0.01
    output: OutputSpec = call["output"]
    assert output.directory == out and output.progress is False
    assert [p.name for p in output.probes] == ["gauge_top", "gauge_bottom"]
    G = call["extra"]["calibration"]["shear_modulus"]
    assert call["model"].body("mound").spec.material.G == G
    case = call["resolved_case"]
    assert case["bodies"]["mound"]["shear_modulus"] == G
    assert case["output"]["directory"] == str(out)
    assert (out / "mesh" / "goda.msh").is_file()
    assert call["resume"] is False


def test_failed_run_exit_1(shared_dir, monkeypatch, capsys):
    monkeypatch.setattr(simulation, "run",
                        FakeRun(simulation.SimulationFailed("step failed at t = 0.01 s")))
    args = ["run", "--out", str(shared_dir / "r"), "--set", "mesh.refinement=0.6",
            "--set", "calibration.enabled=false", "--set", "bodies.mound.shear_modulus=2e6"]
    assert cli.main(args) == 1
    if COMM.rank == 0:
        err = capsys.readouterr().err
        assert "step failed at t = 0.01 s" in err and "Traceback" not in err
    with pytest.raises(simulation.SimulationFailed):
        cli.main([*args, "--debug"])


def test_run_out_is_a_file_exit_2(shared_dir, capsys):
    taken = shared_dir / "results.txt"
    if COMM.rank == 0:
        taken.write_text("not a folder\n")
    COMM.barrier()
    assert cli.main(["run", "--out", str(taken), "--quiet"]) == 2
    err = capsys.readouterr().err
    if COMM.rank == 0:
        assert err == f"breakwater: error: --out {taken}: not a folder (a file of that " \
            "name exists)\n"
    assert taken.read_text() == "not a folder\n"


@pytest.mark.serial
def test_subprocess_errors_and_show_case(tmp_path):
    if COMM.size > 1:
        pytest.skip("subprocess CLI tests run serially")

    def run(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "breakwater", *args], cwd=tmp_path,
                              capture_output=True, text=True, timeout=120)

    r = run("show-case", "--set", "contact.interface.frction=0.5")
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.count("\n") == 1 and "did you mean 'friction'" in r.stderr
    assert "Traceback" not in r.stderr
    r = run("show-case", "--set", "contact.interface.frction=0.5", "--debug")
    assert r.returncode != 0 and "Traceback" in r.stderr and "CaseError" in r.stderr
    r = run("show-case", "goda", "--set", "time.dt=2e-4")
    assert r.returncode == 0 and tomllib.loads(r.stdout)["time"]["dt"] == 2e-4
    r = run("mesh", "--out", "goda.vtu", "--set", "mesh.refinement=0.6")
    assert r.returncode == 0 and (tmp_path / "goda.vtu").is_file()
