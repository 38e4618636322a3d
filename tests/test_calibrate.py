"""Calibration of a shear modulus to a horizontal stiffness (breakwater.statics.calibrate)."""

from __future__ import annotations

import itertools
import pathlib

import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from blocks import two_rectangles

from breakwater.casefile.case import load_case
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, ContactPair, Fixed, Material
from breakwater.statics import calibrate as calibrate_module
from breakwater.statics.calibrate import (
    CalibrationError,
    HorizontalStiffness,
    calibrate_shear_modulus,
)
from breakwater.stepping.snesassembly import ConstantBulk

COMM = MPI.COMM_WORLD


# --- an exact reference: a shear layer under a block -----------------------------------
#
# Block a (width W, height h_a, shear modulus G_a) bonded on layer b (height H, shear
# modulus G) whose base is fixed; u_y = 0 on every side, so the fields are 1D: u_x(y).
# A uniform acceleration of a (body force ρ a per volume) gives the shear τ = ρ a h_a at
# the interface, constant through the layer, and τ(y) = ρ a (top − y) in the block.
# Displacement: layer top τ H / G; interface slip τ / k_t; the block's own shear adds
# ρ a h_a² / (3 G_a) to its mass-weighted mean. So (per metre out of plane)
#     K = H_force / ū = W / (H/G + 1/k_t + h_a / (3 G_a)),
# and quadratic u_x is exact in P2 elements: K is exact up to the solver tolerance.
W, H, H_A = 0.4, 0.2, 0.1
EPS_N, K_T_FACTOR = 1e9, 10.0
G_A = 1e9


def layer_stiffness(G: float) -> float:
    return W / (H / G + 1.0 / (K_T_FACTOR * EPS_N) + H_A / (3.0 * G_A))


@pytest.fixture(scope="module")
def layer_model(folder: pathlib.Path) -> ContactModel:
    path = two_rectangles(folder / "layer.msh", COMM, a=(W, H_A), b=(W, H), h=0.05)
    data = read_mesh(path, COMM)
    bodies = [Body("a", Material(2000.0, 0.3, shear_modulus=G_A)),
              Body("b", Material(1700.0, 0.25, shear_modulus=1e7))]
    fixed = [Fixed("b_bottom"), *(Fixed(g, (1,)) for g in ("b_left", "b_right", "a_left",
                                                           "a_right", "a_top"))]
    return ContactModel(data, bodies, [ContactPair("interface", "a", "b", EPS_N, 0.6)], fixed)


def test_stiffness_of_a_shear_layer(layer_model):
    problem = HorizontalStiffness(layer_model, "a", tangential_penalty=K_T_FACTOR)
    for G in (1e6, 1e7, 1e8):
        # Tolerance: the problem is linear and its solution exact in P2, so one LU solve
        # gives K to round-off (observed 4e-12 with the k_t = 1e10 penalty): 1e-9.
        assert problem.stiffness("b", G) == pytest.approx(layer_stiffness(G), rel=1e-9)


def test_solves_on_a_kept_factorisation(layer_model, monkeypatch):
    # Within REUSE_RATIO of the factorised G, K comes from CG preconditioned by the kept
    # LU factors; the closed form holds to the same 1e-9 as for a direct solve (CG's
    # rtol 1e-13 on an operator of condition ≤ 4). A G farther off factorises again, and
    # so does a CG that fails (one iteration allowed: it cannot reach 1e-13).
    problem = HorizontalStiffness(layer_model, "a", tangential_penalty=K_T_FACTOR)
    try:
        for G in (1e7, 1.5e7, 3.9e7, 3e6):  # within 4 of 1e7
            assert problem.stiffness("b", G) == pytest.approx(layer_stiffness(G), rel=1e-9)
        assert problem.factorised_at == 1e7 and problem.reused == 3
        assert problem.stiffness("b", 5e5) == pytest.approx(layer_stiffness(5e5), rel=1e-9)
        assert problem.factorised_at == 5e5 and problem.reused == 3
        monkeypatch.setattr(calibrate_module, "REUSE_MAX_IT", 1)
        assert problem.stiffness("b", 1e6) == pytest.approx(layer_stiffness(1e6), rel=1e-9)
        assert problem.factorised_at == 1e6 and problem.reused == 3
    finally:
        problem.destroy()


def test_the_scaled_stiffness_is_the_assembled_one(layer_model, monkeypatch):
    # After the first factorisation K(G) is K(G₀) + (G/G₀ − 1) K_b, not assembled: equal
    # to dolfinx's assembly at G to round-off. Its only error is the round-off of the
    # interface springs in K_b = K(G₀) − K(0) (1e-16 of k_t = 1e10 on the rows they
    # share with the layer), times |G/G₀ − 1| ≤ 99: 1e-13 of ‖K‖ (observed ≤ 2e-16, at G/G₀ = 99).
    # A calibration then assembles the cells twice (K(G₀) and K(0)), not once a solve.
    wholes = []
    whole = ConstantBulk.assemble_whole
    monkeypatch.setattr(ConstantBulk, "assemble_whole",
                        lambda self, J: (wholes.append(1), whole(self, J)))
    problem = HorizontalStiffness(layer_model, "a", tangential_penalty=K_T_FACTOR)
    try:
        problem.stiffness("b", 1e7)
        scaled = problem.scaled
        assert scaled is not None and scaled.G0 == 1e7 and len(wholes) == 2
        A = problem.solver.problem.A
        assembled, taken = A.duplicate(), A.duplicate()
        assembled.setLGMap(*A.getLGMap())
        for G in (3e6, 4e7, 1.01e5, 9.9e8):
            problem.set_shear_modulus("b", G)
            problem.solver.jacobian.assemble_whole(assembled)
            scaled.shear_modulus = G
            scaled(None, None, taken, None)
            taken.axpy(-1.0, assembled)
            assert taken.norm() <= 1e-13 * assembled.norm()
        problem.set_shear_modulus("b", 1e7)
        wholes.clear()
        for G in (3e6, 4e7, 5e5, 2e6):  # reused, reused, factorised again, reused
            assert problem.stiffness("b", G) == pytest.approx(layer_stiffness(G), rel=1e-9)
        assert problem.reused == 3 and problem.factorised_at == 5e5 and not wholes
        assert problem.scaled is scaled  # 5e5 is within its RATIO of G₀
        for M in (assembled, taken):
            M.destroy()
    finally:
        problem.destroy()


def test_calibration_of_a_shear_layer(layer_model):
    target = layer_stiffness(3.7e6)
    r = calibrate_shear_modulus(layer_model, "b", "a", target, tolerance=1e-6,
                                initial_guess=1e8, tangential_penalty=K_T_FACTOR)
    assert r.relative_error <= 1e-6
    # G from the closed form; K ~ G here (the soft layer dominates), so a relative
    # error 1e-6 on K is about 1e-6 on G (1e-5 with the solver round-off).
    assert r.shear_modulus == pytest.approx(3.7e6, rel=1e-5)
    assert r.iterations <= 8


def test_unreachable_target(layer_model):
    # K cannot exceed W / (1/k_t + h_a / (3 G_a)) however stiff the layer.
    ceiling = W / (1.0 / (K_T_FACTOR * EPS_N) + H_A / (3.0 * G_A))
    with pytest.raises(CalibrationError, match=r"out of reach|did not converge"):
        calibrate_shear_modulus(layer_model, "b", "a", 2.0 * ceiling, max_iterations=12,
                                initial_guess=1e7, tangential_penalty=K_T_FACTOR)


# --- the Goda case ------------------------------------------------------------------------

@pytest.fixture(scope="module")
def goda(folder: pathlib.Path):
    case = load_case(None, [f'output.directory="{folder / "goda"}"'])
    return case, case.read_mesh(COMM)


def test_goda_calibration_hits_the_target(goda):
    case, data = goda
    r = case.calibrate(data)
    target = 500e3 / 0.205  # Goda's K_x per metre of the 0.205 m block (the paper's §5)
    assert r.target == pytest.approx(target, rel=1e-14)
    assert r.relative_error <= case.calibration.tolerance <= 1e-3
    assert abs(r.stiffness - target) <= 1e-3 * target
    # The gravel modulus is a low-confinement one: a few MPa, far below the caisson's.
    assert 1e5 < r.shear_modulus < 1e8
    # Independent check: a new model built with the calibrated modulus.
    model = case.build_model(data, {"mound": r.shear_modulus}, dynamic=False)
    K = HorizontalStiffness(model, "caisson", case.calibration.tangential_penalty)()
    assert K == pytest.approx(target, rel=1e-3)
    # Monotone in G, and sublinear (soil in series with the stiffer caisson/interface).
    problem = HorizontalStiffness(model, "caisson", case.calibration.tangential_penalty)
    Gs = [0.25 * r.shear_modulus, 0.5 * r.shear_modulus, r.shear_modulus,
          2 * r.shear_modulus, 20 * r.shear_modulus]
    Ks = [problem.stiffness("mound", G) for G in Gs]
    assert all(k1 < k2 for k1, k2 in itertools.pairwise(Ks))
    assert all(k1 / g1 > k2 / g2
               for (k1, g1), (k2, g2) in itertools.pairwise(zip(Ks, Gs, strict=True)))


def test_build_calibrates_and_resolves(goda, tmp_path):
    case, _ = goda
    before = case.resolved()
    built = case.build(COMM)
    model, _, _, extra = built
    G = extra["calibration"]["shear_modulus"]
    assert model.body("mound").spec.material.G == G
    assert extra["calibration"]["relative_error"] <= 1e-3
    # The case as run carries the calibrated modulus; the case itself is unchanged.
    data = built.case.resolved()
    assert data["bodies"]["mound"]["shear_modulus"] == G
    assert data["calibration"]["enabled"] is False
    assert case.resolved() == before and case.body("mound").shear_modulus is None
    assert {**data, "bodies": before["bodies"], "calibration": before["calibration"]} == before


def test_a_long_calibration_reports_its_solves(layer_model, monkeypatch, caplog):
    # A phase longer than SlowPhase.AFTER (here 0 s) logs each unit of work at info, as
    # a 3D case's calibration and static state do after 10 s: each stiffness solve with
    # its G and K, and the Newton's iterations of each solve.
    import logging

    from breakwater.common.console import SlowPhase

    monkeypatch.setattr(SlowPhase, "AFTER", 0.0)
    monkeypatch.setattr(SlowPhase, "EVERY", 0.0)
    target = layer_stiffness(3.7e6)
    with caplog.at_level(logging.INFO, logger="breakwater"):
        r = calibrate_shear_modulus(layer_model, "b", "a", target, tolerance=1e-6,
                                    initial_guess=1e8, tangential_penalty=K_T_FACTOR)
    lines = [rec.getMessage() for rec in caplog.records]
    solves = [m for m in lines if m.startswith("calibrating the shear modulus of 'b': solve")]
    assert len(solves) == len(r.history) == r.iterations
    G, K = r.history[-1]
    assert f"solve {r.iterations}, G = {G:.6g} Pa: K = {K:.6g} N/m" in solves[-1]
    assert any(m.startswith("Newton of calibration: iteration 1, residual") for m in lines)


def test_a_case_without_time_calibrates(goda, shared_dir, capsys):
    """Goda's case without its ``[time]`` table (a case written for a calibration):
    ``calibrate`` takes it (exit 0), to the same G as the whole case (rel 1e-12: the
    same mesh, model and solves; the time step and the loads are not used; on several
    ranks 1e-9, as MUMPS's solves there differ from run to run in the last bits:
    6.4e-12 between the two calibrations in one CI run), while ``show-case`` and
    ``run`` refuse it in one line as before.

    Before: ``calibrate`` refused it too, ``time: missing required key``.
    """
    from breakwater import cli
    from breakwater.casefile.case import builtin_case

    case, data = goda
    text = builtin_case("goda").read_text()
    path = shared_dir / "calibration.toml"
    if COMM.rank == 0:
        path.write_text(text[:text.index("[time]\n")] + text[text.index("[output]\n"):])
    COMM.barrier()
    for command in ("show-case", "run"):
        assert cli.main([command, str(path)]) == 2
        err = capsys.readouterr().err
        if COMM.rank == 0:
            assert err == f"breakwater: error: {path}: time: missing required key\n", err
    assert cli.main(["calibrate", str(path), "--quiet"]) == 0
    static = load_case(path, static=True)
    assert not static.loads
    G = static.calibrate(static.read_mesh(COMM)).shear_modulus
    assert G == pytest.approx(case.calibrate(data).shear_modulus,
                              rel=1e-12 if COMM.size == 1 else 1e-9)
