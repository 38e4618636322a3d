"""Tests of a whole run (breakwater.run.simulation.run): outputs, cut-back, failure.

The model: block ``a`` (1 m x 0.5 m) resting on block ``b`` (2 m x 0.5 m, base fixed)
under gravity, with Coulomb friction μ = 0.6 (χ = 1e-10) on the interface and a short
triangular horizontal pulse on the left face of ``a``. Serial and under MPI.
"""

from __future__ import annotations

import contextlib
import json
import logging
import math
import pathlib
import re
import sys
import tomllib
from collections.abc import Iterator

import numpy as np
import pytest
from blocks import two_rectangles
from mpi4py import MPI

from breakwater.common.errors import BreakwaterError, CaseError, ConvergenceError, MeshError
from breakwater.config.runspec import InitialSpec, OutputSpec, PairProbeSpec, ProbeSpec, TimeSpec
from breakwater.energy.ledger import FIELDS
from breakwater.model.mesh import read_mesh
from breakwater.model.model import (
    Body,
    ContactModel,
    ContactPair,
    Damping,
    Fixed,
    Material,
    SurfaceLoad,
)
from breakwater.outputs.writers import read_history
from breakwater.run import simulation
from breakwater.stepping.gn22 import GN22

COMM = MPI.COMM_WORLD
WIDTH, HEIGHT = 1.0, 0.5   # block a (m)
BASE = (2.0, 0.5)          # block b (m)
RHO, G = 2000.0, 9.81      # density (kg/m³), gravity (m/s²)
DT = 2e-3                  # nominal step (s)
PULSE = 0.01               # pulse duration (s)


@pytest.fixture(scope="module")
def mesh_path(folder: pathlib.Path) -> pathlib.Path:
    return two_rectangles(folder / "stacked.msh", COMM, (WIDTH, HEIGHT), BASE, 0.25)


def _model(path: pathlib.Path, start: float = 0.0, peak: float = 2e4,
           damping: Damping | None = None) -> ContactModel:
    """The block on its base with a triangular pulse of ``peak`` Pa from ``start``."""

    def pulse(t: float) -> float:
        s = (t - start) / PULSE
        return peak * max(0.0, 1.0 - abs(2.0 * s - 1.0)) if 0.0 <= s <= 1.0 else 0.0

    material = Material(RHO, 0.2, young_modulus=1e8)
    return ContactModel(read_mesh(path, COMM), [Body("a", material), Body("b", material)],
                        [ContactPair("interface", "a", "b", penalty=1e10, friction=0.6,
                                     regularisation=1e-10)],
                        [Fixed("b_bottom")], [SurfaceLoad("a_left", (1.0, 0.0), pulse)],
                        gravity=(0.0, -G), damping=damping)


def _output(directory: pathlib.Path, **kwargs) -> OutputSpec:
    return OutputSpec(directory, probes=(ProbeSpec("top", "a", (-0.5 * WIDTH, 2 * HEIGHT)),),
                      pair_probes=(PairProbeSpec("corner", 0, (-0.5 * WIDTH, HEIGHT)),),
                      **{"progress": False, **kwargs})


def _columns() -> list[str]:
    return ["t", "dt", "newton_iterations", "top_ux", "top_uy", "corner_slip",
            "corner_opening", "interface_contact_length", "interface_normal_force",
            "interface_tangential_force", *FIELDS]


def test_run_outputs(mesh_path: pathlib.Path, shared_dir: pathlib.Path) -> None:
    steps = 5
    time = TimeSpec(dt=DT, end_time=steps * DT)
    resolved = {"case": {"name": "blocks"}, "time": {"dt": DT}}
    summary = simulation.run(_model(mesh_path), time,
                             _output(shared_dir, field_interval=2, case_name="blocks"),
                             resolved_case=resolved, extra_summary={"calibration": {"G": 1.5}})
    assert summary["finished"] is True
    for name in ("history.csv", "summary.json", "case.toml", "static.npz",
                 "snapshot_max_ux.npz", "fields_a.bp", "fields_b.bp"):
        assert (shared_dir / name).exists(), name
    figures = ("probes_ux", "pair_probes_ux", "pair_probes_uy", "energy", "contact",
               "static_uy", "static_syy", "static_pressure", "max_ux_deformed")
    for name in figures:
        assert (shared_dir / "figures" / f"{name}.png").is_file(), name
    assert tomllib.loads((shared_dir / "case.toml").read_text()) == resolved

    # The history: the static row, then one row per step ending exactly at end_time.
    h = read_history(shared_dir / "history.csv")
    assert set(_columns()) <= set(h)
    assert len(h["t"]) == steps + 1 == summary["solver"]["steps"] + 1
    assert h["t"][0] == 0.0 and h["t"][-1] == time.end_time
    np.testing.assert_allclose(np.diff(h["t"]), h["dt"][1:], rtol=1e-12)
    assert np.isfinite(h["balance_error"]).all()

    # The summary written is the one returned; the extra summary is merged in.
    written = json.loads((shared_dir / "summary.json").read_text())
    assert written["finished"] is True and written["calibration"] == {"G": 1.5}
    assert written["solver"]["steps"] == steps
    assert written["solver"]["cutbacks"] == 0
    for key in ("newton_iterations", "mean_newton_iterations", "max_newton_iterations",
                "failed_steps", "slip_guard_corrections", "round_off_accepts", "wall_time"):
        assert key in written["solver"], key
    for key in ("dolfinx", "petsc4py", "ufl", "basix", "ffcx", "gmsh", "python", "mpi_size"):
        assert key in written["versions"], key
    assert written["versions"]["mpi_size"] == COMM.size
    assert written["energy"]["max_balance_error"] == pytest.approx(
        np.abs(h["balance_error"]).max(), rel=1e-12)
    W = h["external_work"][-1]
    assert written["energy"]["numerical_dissipation"] == pytest.approx(
        h["numerical_dissipation"][-1], rel=1e-12)
    assert written["energy"]["numerical_dissipation_over_external_work"] == pytest.approx(
        h["numerical_dissipation"][-1] / abs(W), rel=1e-12)
    # The ledger closes (1e-8 of the work: Newton's tolerance, test_numerical_dissipation).
    assert written["energy"]["max_balance_error_over_external_work"] < 1e-8
    dyn = written["dynamic"]
    k = int(np.argmax(np.abs(h["top_ux"])))
    assert dyn["peak_ux"]["top"] == {"value": pytest.approx(h["top_ux"][k], rel=1e-12),
                                     "time": pytest.approx(h["t"][k], rel=1e-12)}
    assert dyn["time_of_max_ux"] == pytest.approx(h["t"][k], rel=1e-12)
    assert dyn["residual_ux"]["top"] == pytest.approx(h["top_ux"][-1], rel=1e-12)
    assert dyn["residual_slip"] == pytest.approx(h["corner_slip"][-1], rel=1e-12)
    assert dyn["max_uplift"] == pytest.approx(h["corner_opening"].max(), rel=1e-12)
    # The pulse pushes the block towards +x: the top moves and the corner slips that way.
    assert dyn["peak_ux"]["top"]["value"] > 0

    # Static state: the block's weight rests on the interface. Vertical equilibrium of
    # block a gives a contact resultant ρ g W H and a mean pressure ρ g H (the paper's §5.4, the
    # caisson's 2314 * 9.81 * 0.202 Pa); the static solve converges to rtol 1e-9, so
    # 1e-6 is a safe relative tolerance.
    static = written["static"]
    weight = RHO * G * WIDTH * HEIGHT
    assert static["weight"] == pytest.approx(weight, rel=1e-9)
    assert static["contact_resultant"] == pytest.approx(weight, rel=1e-6)
    assert static["mean_contact_pressure"] == pytest.approx(RHO * G * HEIGHT, rel=1e-6)
    # Like a rigid footing on an elastic base, the pressure peaks at the edges (Fig. 17).
    assert static["edge_pressure"] > static["mean_contact_pressure"] > 0
    assert static["center_pressure"] < static["edge_pressure"]
    assert h["interface_normal_force"][0] == pytest.approx(weight, rel=1e-6)
    assert h["interface_contact_length"][0] == pytest.approx(WIDTH, rel=1e-12)

    with np.load(shared_dir / "static.npz") as data:
        assert set(data["bodies"]) == {"a", "b"}
        assert data["a_triangles"].max() < len(data["a_x"])
        np.testing.assert_allclose(data["a_x"].min(axis=0), [-WIDTH / 2, HEIGHT], atol=1e-12)
        np.testing.assert_allclose(data["a_x"].max(axis=0), [WIDTH / 2, 2 * HEIGHT],
                                   atol=1e-12)
        assert list(data["contacts"]) == ["interface"]  # the pairs: contact_<name>_*
        assert data["contact_interface_pressure"].shape == (len(data["contact_interface_x"]),)

    # The contact fields for ParaView, read back (serially: a file written on several
    # ranks holds one block per rank).
    assert (shared_dir / "contact_interface.bp").exists()
    if COMM.size == 1:
        _check_contact_fields(shared_dir / "contact_interface.bp", h, weight)


def _check_contact_fields(path: pathlib.Path, h: dict[str, np.ndarray], weight: float) -> None:
    """At every written time, the interface integrals of the contact fields are the
    history's resultants: Simpson's rule on each P2 facet is the Gauss–Lobatto rule of
    the interface measure, so both are the same sum of the same nodal values, equal to
    round-off (1e-10 relative, of the weight where the resultant is zero at rest).
    """
    adios2 = pytest.importorskip("adios2")
    with adios2.FileReader(str(path)) as r:
        x = r.read("geometry")[:, :2]
        cells = r.read("connectivity")  # VTK Lagrange curves: count, two ends, midpoint
        ends, mid = cells[:, 1:3], cells[:, 3]
        length = np.linalg.norm(x[ends[:, 1]] - x[ends[:, 0]], axis=1)

        def simpson(f: np.ndarray) -> float:
            return float(np.sum(length / 6 * (f[ends[:, 0]] + 4 * f[mid] + f[ends[:, 1]])))

        assert r.num_steps() == 4  # t = 0, every 2 steps of 5, and the last step
        slid = False
        for k in range(r.num_steps()):
            t = float(r.read("step", step_selection=[k, 1])[0])
            j = int(np.argmin(np.abs(h["t"] - t)))
            assert h["t"][j] == pytest.approx(t, rel=1e-12)
            p = r.read("pressure", step_selection=[k, 1])[:, 0]
            traction = r.read("friction_traction", step_selection=[k, 1])[:, 0]
            v = r.read("slip_velocity", step_selection=[k, 1])[:, 0]
            assert simpson(p) == pytest.approx(h["interface_normal_force"][j], rel=1e-10)
            assert simpson(traction) == pytest.approx(h["interface_tangential_force"][j], rel=1e-10,
                                                      abs=1e-10 * weight)
            # Coulomb: where a node slides (|v_T| ≥ 1e6 χ, so that the regularised
            # sign differs from ±1 by χ²/2v_T² ≤ 5e-13) the traction is μp against v_T.
            sliding = np.abs(v) >= 1e6 * 1e-10
            slid |= bool(sliding.any())
            np.testing.assert_allclose(traction[sliding], -0.6 * p[sliding] * np.sign(v[sliding]),
                                       rtol=1e-9)
        assert slid  # the pulse (twice μN) makes the block slide


@contextlib.contextmanager
def _log_to_stderr() -> Iterator[None]:
    """The ``breakwater`` log on stderr, debug level, as the command line's --verbose."""
    logger = logging.getLogger("breakwater")
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(message)s"))
    saved = (logger.level, logger.propagate)
    logger.setLevel(logging.DEBUG)
    logger.addHandler(handler)
    logger.propagate = False
    try:
        yield
    finally:
        logger.removeHandler(handler)
        logger.setLevel(saved[0])
        logger.propagate = saved[1]


def _check_log_and_bar(err: str, steps: int) -> None:
    """The log lines are whole, and the bar is drawn after "time stepping to ...".

    The line "time stepping to ..." is written before the bar is drawn, and the log
    lines written while it is shown (a debug line per step, the cut-back warning, the
    step growing back) go through tqdm.write, each whole on its own line. The bar
    redraws itself with carriage returns: the pieces between line ends and carriage
    returns are checked. Only rank 0 logs and draws.
    """
    if COMM.rank > 0:
        assert err == ""
        return
    pieces = [p for p in re.split(r"[\r\n]", err) if p.strip()]
    start = [k for k, p in enumerate(pieces) if "time stepping" in p]
    bar = [k for k, p in enumerate(pieces) if p.startswith("blocks:") and "%|" in p]
    assert len(start) == 1 and bar, err
    assert re.fullmatch(r"time stepping to t = \S+ s with dt = 0\.002 s", pieces[start[0]])
    assert start[0] < bar[0]
    during = [k for k, p in enumerate(pieces) if p.startswith("t = ")]
    patterns = (r"t = \S+ s, dt = \S+ s, \d+ Newton iterations",
                r"t = \S+ s: .+; retrying with dt = 0\.001 s \(cut-back 1/4\)",
                r"t = \S+ s: step size back to dt = 0\.002 s")
    for k in during:
        assert any(re.fullmatch(p, pieces[k]) for p in patterns), pieces[k]
    assert [sum(bool(re.fullmatch(p, pieces[k])) for k in during) for p in patterns] == \
        [steps, 1, 1]
    assert bar[0] < during[0] and bar[-1] > during[-1]
    assert not logging.getLogger("breakwater.run.simulation").filters  # set up by run() only


@pytest.mark.parametrize("failure", ["diverged", "nan"])
def test_cutback_recovers(mesh_path: pathlib.Path, shared_dir: pathlib.Path,
                          monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str],
                          failure: str) -> None:
    # Steps starting in [2Δt, 3Δt) fail unless Δt is at most half the nominal step,
    # the same on every rank: Newton diverges, or "converges" to a NaN increment.
    # Expected: one cut-back, GROW_AFTER half steps, then the nominal step again, and
    # the end time reached exactly. The progress bar is on, with the log on stderr:
    # see _check_log_and_bar.
    solve = GN22.solve

    def flaky(self: GN22) -> int:
        t, dt = float(self.t.value), float(self.dt.value)
        if 2 * DT * (1 - 1e-9) <= t < 3 * DT * (1 - 1e-9) and dt > 0.6 * DT:
            if failure == "diverged":
                raise ConvergenceError("injected failure", -5, 3)
            its = solve(self)
            self.da[0].x.array[:] = np.nan
            return its
        return solve(self)

    monkeypatch.setattr(GN22, "solve", flaky)
    grow = simulation.GROW_AFTER
    end = 2 * DT + grow * DT / 2 + 2 * DT
    capsys.readouterr()
    with _log_to_stderr():
        summary = simulation.run(_model(mesh_path), TimeSpec(dt=DT, end_time=end),
                                 _output(shared_dir, field_interval=0, figures=False,
                                         progress=True, case_name="blocks"))
    _check_log_and_bar(capsys.readouterr().err, steps=2 + grow + 2)
    assert summary["finished"] is True
    assert summary["solver"]["cutbacks"] == 1
    assert summary["solver"]["failed_steps"] == 1
    if failure == "diverged":
        assert summary["solver"]["failed_newton_iterations"] == 3
    h = read_history(shared_dir / "history.csv")
    expected = [0.0, DT, DT, *[DT / 2] * grow, DT, DT]
    np.testing.assert_allclose(h["dt"], expected, rtol=1e-9)
    assert h["t"][-1] == end
    assert summary["solver"]["steps"] == len(expected) - 1


def test_failure_keeps_outputs(mesh_path: pathlib.Path, shared_dir: pathlib.Path) -> None:
    # From the frictionless static state, at rest a step takes 3-4 Newton iterations (the
    # state's residual noise gives slip velocities of order χ, where the friction law is
    # steep); once the pulse starts (at 3Δt) it needs 8 or more. With 5 iterations and no
    # cut-back allowed, the run must stop at the 4th step, keep the 3 converged steps and
    # say so. (From the frictional state, the default, the 4th step converges in 5.)
    time = TimeSpec(dt=DT, end_time=10 * DT, max_cutbacks=0, newton_max_it=5)
    model = _model(mesh_path, start=3 * DT)
    model.initial = InitialSpec(loading="frictionless")
    with pytest.raises(simulation.SimulationFailed) as info:
        simulation.run(model, time, _output(shared_dir, field_interval=0, figures=False))
    assert isinstance(info.value, BreakwaterError)
    written = json.loads((shared_dir / "summary.json").read_text())
    assert written["finished"] is False
    assert "did not converge" in written["error"]
    assert info.value.summary["finished"] is False
    steps = written["solver"]["steps"]
    assert steps == 3
    assert written["solver"]["failed_steps"] == 1
    h = read_history(shared_dir / "history.csv")
    assert len(h["t"]) == steps + 1
    assert h["t"][-1] == pytest.approx(written["time"]["reached"], rel=1e-12)
    assert np.isfinite(np.column_stack(list(h.values()))).all()


def test_contact_quality(mesh_path: pathlib.Path, shared_dir: pathlib.Path,
                         caplog: pytest.LogCaptureFixture,
                         capsys: pytest.CaptureFixture[str]) -> None:
    # The paper-like penalty: penetration far below both thresholds.
    E, ν = 1e8, 0.2
    summary = simulation.run(_model(mesh_path), TimeSpec(dt=DT, end_time=3 * DT),
                             _output(shared_dir / "stiff", field_interval=0, figures=False),
                             report=False)
    q = summary["contact_quality"]["interface"]
    h = read_history(shared_dir / "stiff" / "history.csv")
    # The interface (1 m) is split into 4 facets of the structured mesh (h = 0.25).
    assert q["element_size"] == pytest.approx(0.25, rel=1e-12)
    assert q["penalty_h_over_E"] == {"slave": pytest.approx(1e10 * 0.25 / E, rel=1e-12),
                                     "master": pytest.approx(1e10 * 0.25 / E, rel=1e-12)}
    # Penetration is the largest nodal ⟨−g_n⟩₊, the pressure ε_n ⟨−g_n⟩₊ at the same
    # nodes: the largest static pressure over ε_n (same numbers, round-off only).
    assert q["static_penetration"] == pytest.approx(
        summary["static"]["max_pressure"] / 1e10, rel=1e-12)
    assert h["interface_penetration"][0] == pytest.approx(q["static_penetration"], rel=1e-12)
    k = 1 + int(np.argmax(h["interface_penetration"][1:]))
    assert q["dynamic_penetration"] == pytest.approx(h["interface_penetration"][k], rel=1e-12)
    assert q["time_of_dynamic_penetration"] == pytest.approx(h["t"][k], rel=1e-12)
    # Settlement: a 1D (oedometric) estimate for base b under the block's pressure
    # ρ g H plus its own weight, s ≈ (ρ g H H_b + ρ g H_b²/2) / M with
    # M = E (1 − ν) / ((1 + ν)(1 − 2ν)). The 2D base is neither confined nor loaded
    # over its whole width (the load spreads, the free sides bulge): 30% is the
    # accuracy of such an estimate (measured: 10% below it).
    M = E * (1 - ν) / ((1 + ν) * (1 - 2 * ν))
    H_b = BASE[1]
    s_1d = (RHO * G * HEIGHT * H_b + RHO * G * H_b**2 / 2) / M
    assert q["static_settlement"] == pytest.approx(s_1d, rel=0.3)
    assert q["static_penetration_over_settlement"] == pytest.approx(
        q["static_penetration"] / q["static_settlement"], rel=1e-12)
    assert q["verdict"] == "ok" and q["warnings"] == []

    # A penalty 1e4 times softer: static penetration about ρ g H / ε_n = 1 cm, above
    # 1% of h (2.5 mm) and above 10% of the settlement: too soft, with a warning
    # (rank 0) and a line of the report.
    soft = ContactModel(read_mesh(mesh_path, COMM),
                        [Body("a", Material(RHO, ν, young_modulus=E)),
                         Body("b", Material(RHO, ν, young_modulus=E))],
                        [ContactPair("interface", "a", "b", penalty=1e6, friction=0.6,
                                     regularisation=1e-10)],
                        [Fixed("b_bottom")], gravity=(0.0, -G))
    caplog.set_level("WARNING", logger="breakwater")
    capsys.readouterr()
    summary = simulation.run(soft, TimeSpec(dt=DT, end_time=2 * DT),
                             _output(shared_dir / "soft", field_interval=0, figures=False))
    q = summary["contact_quality"]["interface"]
    assert q["static_penetration"] > 0.01 * 0.25
    assert q["verdict"] == "too soft"
    assert {"static_penetration_over_h", "penetration_over_settlement"} <= set(q["issues"])
    assert q["suggested_penalty"][0] > 1e6
    if COMM.rank == 0:
        warned = [r.getMessage() for r in caplog.records if "too soft" in r.getMessage()]
        assert warned and all("suggested ε_n" in w for w in warned)
        assert "contact 'interface'" in capsys.readouterr().out


def test_batch_log_shows_the_loop_progress(mesh_path: pathlib.Path, shared_dir: pathlib.Path,
                                           monkeypatch: pytest.MonkeyPatch,
                                           caplog: pytest.LogCaptureFixture) -> None:
    # Without the bar (a batch job: stderr not a terminal) the log has a line on the
    # loop's progress every HEARTBEAT seconds (here 0: every step), with t, the steps,
    # the mean Newton iterations and the time left; with the bar, none.
    monkeypatch.setattr(simulation, "HEARTBEAT", 0.0)
    caplog.set_level("INFO", logger="breakwater")
    end = 4 * DT
    for bar in (False, True):
        caplog.clear()
        summary = simulation.run(_model(mesh_path), TimeSpec(dt=DT, end_time=end),
                                 _output(shared_dir, field_interval=0, figures=False,
                                         progress=bar))
        lines = [r.getMessage() for r in caplog.records
                 if r.getMessage().startswith("time stepping: ")]
        if bar or COMM.rank > 0:  # the bar's run; only rank 0 logs
            assert lines == []
            continue
        steps = summary["solver"]["steps"]
        assert len(lines) == steps == 4
        pattern = (r"time stepping: t = (\S+) s of 0\.008 s \((\d+)%\), (\d+) steps, "
                   r"(\S+) Newton iterations per step; \d+ s elapsed, about \d+ s left")
        last = re.fullmatch(pattern, lines[-1])
        assert last is not None, lines[-1]
        assert float(last[1]) == end and last[2] == "100" and int(last[3]) == steps
        mean = summary["solver"]["newton_iterations"] / steps
        assert float(last[4]) == pytest.approx(mean, abs=0.005)
        assert lines[-1].endswith("about 0 s left")


def test_durations_read_as_time() -> None:
    assert simulation.duration(42.4) == "42 s"
    assert simulation.duration(185.0) == "3 min 05 s"
    assert simulation.duration(3725.0) == "1 h 02 min"
    assert simulation.duration(math.inf) == "?"


def test_probes_of_one_name_are_refused(tmp_path: pathlib.Path) -> None:
    # From Python two probes of one kind may share a name (a case file's tables cannot):
    # their history columns were written twice under one name (found by a user).
    a = ProbeSpec("top", "a", (0.0, 0.1))
    with pytest.raises(ValueError, match=r"^output: two probes named 'top'"):
        OutputSpec(tmp_path, probes=(a, ProbeSpec("top", "b", (0.0, 0.0))))
    pair = PairProbeSpec("corner", 0, (0.0, 0.0))
    with pytest.raises(ValueError, match=r"^output: two probes named 'corner'"):
        OutputSpec(tmp_path, pair_probes=(pair, pair))
    # A point probe and a pair probe may share a name: their columns differ.
    assert OutputSpec(tmp_path, probes=(ProbeSpec("corner", "a", (0.0, 0.1)),),
                      pair_probes=(pair,)).probes[0].name == "corner"


def test_a_probe_of_an_unknown_body_or_pair_is_refused(mesh_path: pathlib.Path,
                                               shared_dir: pathlib.Path) -> None:
    # From Python (a case file's probes are checked against its bodies): a KeyError
    # whose message was quoted (found by a user). One line, on every rank, before the
    # folder is touched: an earlier run's outputs there were cleared first.
    earlier = {"summary.json": '{"status": "finished", "finished": true, "process": {}}',
               "history.csv": "t\n0.0\n"}
    if COMM.rank == 0:
        for name, text in earlier.items():
            (shared_dir / name).write_text(text)
    COMM.barrier()
    time = TimeSpec(dt=DT, end_time=2 * DT)
    output = OutputSpec(shared_dir, probes=(ProbeSpec("top", "aa", (0.0, 0.1)),),
                        progress=False)
    with pytest.raises(CaseError, match=r"^probe 'top': no body named 'aa' \(did you mean "
                       r"'a'\?\) \(bodies: a, b\)$"):
        simulation.run(_model(mesh_path), time, output)
    # A pair probe naming a pair the model does not have: the run started and failed
    # (SimulationFailed "ValueError: pair probe 'q': no contact pair 5"), a crash.
    output = OutputSpec(shared_dir, pair_probes=(PairProbeSpec("q", 5, (0.0, 0.0)),),
                        progress=False)
    with pytest.raises(CaseError, match=r"^pair probe 'q': no contact pair 5 in model\.pairs "
                       r"\(indices 0 to 0\)$"):
        simulation.run(_model(mesh_path), time, output)
    output = OutputSpec(shared_dir, pair_probes=(PairProbeSpec("q", "interfac", (0.0, 0.0)),),
                        progress=False)
    with pytest.raises(CaseError, match=r"^pair probe 'q': no general contact pair 'interfac' "
                       r"\(the model has none\)$"):
        simulation.run(_model(mesh_path), time, output)
    # A point outside its body: refused once the run had cleared the folder.
    output = OutputSpec(shared_dir, probes=(ProbeSpec("top", "a", (0.0, 5.0)),),
                        progress=False)
    with pytest.raises(MeshError, match=r"^probe 'top': point \(0\.0, 5\.0\) is not in "
                       r"body 'a'$"):
        simulation.run(_model(mesh_path), time, output)
    left = COMM.bcast({name: (shared_dir / name).read_text() if (shared_dir / name).exists()
                       else None for name in earlier} if COMM.rank == 0 else None)
    assert left == earlier  # the earlier run's outputs, as they were


def test_case_toml_holds_the_time_and_output_settings_run(
        mesh_path: pathlib.Path, shared_dir: pathlib.Path,
        caplog: pytest.LogCaptureFixture) -> None:
    # A notebook runs a built model again with dataclasses.replace(time, dt=...) and the
    # same built.case.resolved(): the run took the new Δt while case.toml (what
    # `python -m breakwater run case.toml` and --resume go by) said the old one.
    from dataclasses import replace

    from breakwater.config.fields import to_toml

    folder = shared_dir / "as_run"
    given = TimeSpec(dt=DT, end_time=2 * DT)
    resolved = {"name": "blocks", "time": to_toml(given),
                "output": {"directory": str(shared_dir / "elsewhere"), "field_interval": 10,
                           "figures": True, "checkpoint_interval": 0}}
    time = replace(given, dt=DT / 2, min_dt=DT / 8)
    with caplog.at_level(logging.WARNING, logger="breakwater.run.simulation"):
        summary = simulation.run(_model(mesh_path), time,
                                 _output(folder, figures=False, field_interval=0),
                                 resolved_case=resolved, report=False)
    assert summary["solver"]["steps"] == 4
    written = on_rank_zero_read(folder / "case.toml")
    assert written["time"] == {**to_toml(given), "dt": DT / 2, "min_dt": DT / 8}
    assert written["output"] == {"directory": str(folder), "field_interval": 0,
                                 "figures": False, "checkpoint_interval": 0}
    assert resolved["time"]["dt"] == DT  # the caller's mapping is left as it was
    lines = [r.getMessage() for r in caplog.records if r.getMessage().startswith("case.toml")]
    # (another folder, field interval or figures switch: written in without a word)
    assert lines == ([] if COMM.rank else [
        "case.toml: written with the settings run() was given, not resolved_case's: "
        f"time.dt = {DT / 2:g} (resolved_case: {DT:g}), time.min_dt = {DT / 8:g} "
        "(resolved_case: unset) (to keep them in step, pass dataclasses.replace(built.case, "
        "time=time, damping=...).resolved())"])


def test_damping_set_on_a_built_model_is_the_damping_run(
        mesh_path: pathlib.Path, shared_dir: pathlib.Path) -> None:
    # A notebook sets model.damping on a built model: the fast solver took it (it reads
    # the dataclass), the forms kept the constants of the damping built with (the
    # reference solver, the ledger's Rayleigh dissipation). Goda's case: u_x 0.5893 mm
    # for the 0.5882 mm of a model built with that damping. Now the same run, and
    # case.toml says it.
    with pytest.raises(ValueError, match=r"^damping alpha must be a number >= 0 \(got -1.0\)$"):
        Damping(alpha=-1.0)  # as the case's [damping]: it ran, feeding energy in
    damping = Damping(alpha=20.0, beta=1e-3)
    time = TimeSpec(dt=DT, end_time=3 * DT, solver="reference")
    built = _model(mesh_path)
    built.damping = damping
    assert (float(built.α.value), float(built.β.value)) == (20.0, 1e-3)
    given = {"damping": {"alpha": 0.0, "beta": 0.0}, "gravity": [0.0, -1.0]}
    simulation.run(built, time, _output(shared_dir / "set", figures=False, field_interval=0),
                   resolved_case=given, report=False)
    simulation.run(_model(mesh_path, damping=damping), time,
                   _output(shared_dir / "built", figures=False, field_interval=0), report=False)
    a = read_history(shared_dir / "set" / "history.csv")
    b = read_history(shared_dir / "built" / "history.csv")
    assert b["rayleigh_dissipation"][-1] > 0
    # Bit for bit serially; on 2 ranks two runs of one model differ by round-off in the
    # parallel sums (4e-20 m in a slip of 1.5e-9 m, 3e-14 of the largest), the bug by
    # 40 % (u_x 2.04e-5 m for 1.45e-5 m).
    for key in ("top_ux", "corner_slip", "rayleigh_dissipation", "kinetic"):
        tol = 0.0 if COMM.size == 1 else 1e-10 * float(np.abs(b[key]).max())
        np.testing.assert_allclose(a[key], b[key], rtol=0, atol=tol, err_msg=key)
    written = on_rank_zero_read(shared_dir / "set" / "case.toml")
    assert written["damping"] == {"alpha": 20.0, "beta": 1e-3}
    assert written["gravity"] == [0.0, -G]  # (model.gravity.value, settable alike)


def on_rank_zero_read(path: pathlib.Path) -> dict:
    """A TOML file written by rank 0, read on every rank once it is there."""
    COMM.barrier()
    return tomllib.loads(path.read_text(encoding="utf-8"))
