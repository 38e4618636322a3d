"""Energy balance of GN22 runs with the trapezoidal parameters β1 = β2 = ½.

With β1 = β2 = ½, GN22 is Newmark's average-acceleration rule: for linear terms the
discrete energy identity is exact (Hughes, *The Finite Element Method*, §9.3), so the
ledger's (:class:`breakwater.energy.ledger.EnergyLedger`) numerical dissipation is only its
contact share: what the contact nonlinearity (penalty switching on and off within a
step, stick-slip transitions) leaves. The balance, with that entry, closes to the
Newton tolerance (more β₁, β₂ in test_numerical_dissipation.py).
"""

from __future__ import annotations

import pathlib
import sys

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)
from breakwater.energy.ledger import EnergyLedger
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
from breakwater.stepping.gn22 import GN22, GN22Parameters, solve_static

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from blocks import two_rectangles

COMM = MPI.COMM_WORLD
TRAPEZOIDAL = GN22Parameters(beta1=0.5, beta2=0.5)


def test_frictionless_impact_conserves_energy(folder):
    # Two identical bars, a (left) at v0 striking b at rest (as in test_impact.py), no
    # gravity, no damping, μ = 0: total energy kinetic + strain + penalty is conserved.
    L, H, E, ρ, v0 = 1.0, 0.1, 1e9, 1000.0, 1.0
    T_contact = 2.0 * L / np.sqrt(E / ρ)
    path = two_rectangles(folder / "bars.msh", COMM, a=(L, H), b=(L, H), h=0.025,
                          layout="side")
    mat = Material(ρ, 0.0, young_modulus=E)
    # Penalty resolved by the step: the interface stress rises in ρc/(2ε_n) = 5e-6 s =
    # 0.2 Δt. A stiffer, unresolved penalty is not energy-stable with β1 = β2 = ½: the
    # undamped penalty mode makes the contact open and close step after step, and each
    # switch injects energy (ε_n = 1e13 with Δt = 2L/c/160 ends with 2.9 K0).
    model = ContactModel(read_mesh(path, COMM), [Body("a", mat), Body("b", mat)],
                         [ContactPair("interface", "a", "b", penalty=1e11)])
    stepper = GN22(model, T_contact / 80, TRAPEZOIDAL)
    v_init = model.functions("v0")
    v_init[0].interpolate(lambda x: np.vstack([np.full(x.shape[1], v0), np.zeros(x.shape[1])]))
    stepper.initialise(u0=None, v0=v_init)
    ledger = EnergyLedger(stepper)
    first = ledger.record()
    K0 = 0.5 * ρ * L * H * v0**2  # J/m
    # The ledger's kinetic energy of the interpolated uniform velocity is exact.
    assert first.kinetic == pytest.approx(K0, rel=1e-12)
    assert first.strain == 0.0 and first.penalty == 0.0
    rows = [first]
    for _ in range(120):  # 1.5 × the contact duration: through contact and separation
        stepper.step()
        rows.append(ledger.record())
    error = np.array([r.stored for r in rows]) / K0 - 1.0
    balance = np.array([r.balance_error for r in rows]) / K0
    D_num = np.array([r.numerical_dissipation for r in rows]) / K0
    peak_strain = max(r.strain for r in rows) / K0
    if COMM.rank == 0:
        print(f"\nK0 = {K0} J/m; max |E/K0 − 1| = {np.abs(error).max():.2e}, final "
              f"{error[-1]:.2e}; numerical dissipation (contact) {D_num[-1]:.2e} K0; "
              f"max |balance error| {np.abs(balance).max():.1e} K0; peak strain energy "
              f"{peak_strain:.3f} K0")
    # The energy is really exchanged: at mid-contact half of it is strain energy.
    assert peak_strain > 0.45
    # No external work, no dissipation.
    assert all(r.external_work == 0.0 and r.rayleigh_dissipation == 0.0
               and r.friction_dissipation == 0.0 for r in rows)
    # 1e-3 K0: only the steps where the penalty switches (closing, opening) break the
    # exact trapezoidal energy identity; measured 1.3e-4 K0.
    assert np.abs(error).max() < 1e-3
    # That loss is the numerical entry's contact share (its bulk share vanishes at ½,
    # ½), and with it the balance closes to Newton's tolerance (measured 6e-13 K0).
    assert all(r.numerical_dissipation == r.numerical_dissipation_contact for r in rows)
    assert np.abs(D_num).max() > 1e-5
    assert np.abs(balance).max() < 1e-9


def test_friction_and_damping_balance(folder):
    # A block (W × H) on a base fixed at the bottom, under gravity, pushed by a
    # triangular traction pulse on its left face peaking at 3μN: it slides (friction
    # dissipation) and vibrates (Rayleigh dissipation); the pulse and gravity do work.
    W, H, E, ρ, μ, g = 0.2, 0.05, 1e9, 2000.0, 0.5, 9.81
    N = ρ * W * H * g
    T = 4e-3
    path = two_rectangles(folder / "block.msh", COMM, a=(W, H), b=(W, H), h=0.025)
    mat = Material(ρ, 0.25, young_modulus=E)
    # α = 20 1/s and β = 1e-4 s: both parts of the Rayleigh dissipation count (the β
    # part is 10 % of it); stiffness damping also keeps the undamped trapezoidal scheme
    # from chattering at the interface (with β = 0 the balance error is 70 % of D_R).
    model = ContactModel(
        read_mesh(path, COMM), [Body("a", mat), Body("b", mat)],
        [ContactPair("interface", "a", "b", penalty=1e11, friction=μ, regularisation=1e-10)],
        [Fixed("b_bottom")],
        [SurfaceLoad("a_left", (1.0, 0.0),
                     lambda t: 3.0 * μ * N / H * max(0.0, 1.0 - abs(2.0 * t / T - 1.0)))],
        gravity=(0.0, -g), damping=Damping(alpha=20.0, beta=1e-4))
    u, _ = solve_static(model)
    stepper = GN22(model, T / 40, TRAPEZOIDAL)
    stepper.initialise(u)
    ledger = EnergyLedger(stepper)
    nodes = stepper.nodes[0]

    def slip() -> float:
        s, m = nodes.gather(stepper.u[0].x.array, stepper.u[1].x.array)
        return float(np.mean(s[:, 0] - m[:, 0]))

    s0 = slip()
    rows = [ledger.record()]
    for _ in range(80):  # the pulse lasts 40 steps, the (rigid) block stops at 63
        stepper.step()
        rows.append(ledger.record())
    sliding = slip() - s0
    D_R = np.array([r.rayleigh_dissipation for r in rows])
    D_F = np.array([r.friction_dissipation for r in rows])
    error = np.array([r.balance_error for r in rows])
    D_num = np.array([r.numerical_dissipation for r in rows])
    W_ext = rows[-1].external_work
    if COMM.rank == 0:
        print(f"\nD_R = {D_R[-1]:.4e}, D_F = {D_F[-1]:.4e}, W = {W_ext:.4e} J/m; "
              f"max |numerical dissipation| = {np.abs(D_num).max():.3e} J/m "
              f"({np.abs(D_num).max() / D_R[-1]:.2e} D_R); max |balance error| "
              f"{np.abs(error).max() / W_ext:.1e} W; D_F / μN·slip = "
              f"{D_F[-1] / (μ * N * sliding):.5f}")
    # Both dissipations positive and growing: D_R strictly at every step (the block
    # moves throughout), D_F never decreasing and strictly while the block slides.
    assert np.all(np.diff(D_R) > 0.0)
    assert np.all(np.diff(D_F) >= 0.0)
    assert np.all(np.diff(D_F[8:55]) > 0.0)  # sliding from t = T/6 (step 7) to ~1.5 T
    assert D_R[-1] > 0.0 and D_F[-1] > 0.0
    # The work done is dissipated (the final stored energy differs little from the
    # static one): a balance that holds trivially with W = 0 would fail here.
    assert W_ext > 0.9 * (D_R[-1] + D_F[-1])
    # Friction dissipation of a block sliding as a whole under the constant normal
    # force N: D_F = μN·slip. 1 %: the elastic fluctuations of N; measured 0.03 %.
    assert D_F[-1] == pytest.approx(μ * N * sliding, rel=0.01)
    # The numerical dissipation (all of it the contact share at ½, ½) within 1 % of the
    # smaller dissipation (measured 1.1e-3 D_R): the ledger integrates the friction
    # power by the trapezoidal rule, which is not the scheme's exact discrete work at
    # the stick-slip transitions, and the penalty switches are not energy-exact either.
    assert np.abs(D_num).max() < 0.01 * min(D_R[-1], D_F[-1])
    assert np.any(D_num != 0.0)
    # With it the balance closes to Newton's tolerance (measured 9e-13 W, 1.3e-12 W on
    # 2 ranks).
    assert np.abs(error).max() < 1e-8 * W_ext


def test_report_measures_the_balance_by_the_energy_that_moved(folder) -> None:
    # A block launched by its initial velocity and stopped by friction: the external
    # work is ~0 and the energy the run moves is its initial kinetic energy (20 J/m),
    # so the report quotes the balance error against that (it printed "1.7e+04 of the
    # external work"); a pushed run keeps the external work.
    from breakwater.outputs.summary import energy_summary, format_report

    def rows(work: float, kinetic: float) -> list[dict[str, float]]:
        return [{"t": float(k), "external_work": work * k, "kinetic": kinetic * (2 - k),
                 "strain": 0.0, "penalty": 0.0, "balance_error": 2.8e-4 * k,
                 "numerical_dissipation": 2e-5 * k} for k in (0, 1, 2)]

    launched = {"energy": energy_summary(rows(8e-9, 10.0))}
    line = next(x for x in format_report(launched, folder).splitlines() if "energy:" in x)
    assert "(2.8e-05 of the run's largest energy, 20 J/m)" in line
    assert "(0.0002% of that energy)" in line
    pushed = {"energy": energy_summary(rows(1.0, 0.0))}
    line = next(x for x in format_report(pushed, folder).splitlines() if "energy:" in x)
    assert "(0.00028 of the external work)" in line and "largest energy" not in line
