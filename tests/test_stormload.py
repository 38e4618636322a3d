"""A storm as a load of the FE model: a field that changes at given times (issue 24).

The front pressure of a storm changes its shape from wave to wave
(:class:`~breakwater.loads.fields.StagedProfile`): the model sets the profile's points
(a ``fem.Constant``) at each stage's start, the fast solver assembles its load vector
again then, the reference solver's forms read the same Constant, and the energy
ledger's external work takes each step's start traction with the start's points. The
references here are computed in the tests: the fixed-profile load of the same shape
(:class:`~breakwater.loads.fields.PressureProfile`), the exact resultant of a
piecewise-linear pressure, the energy balance of GN22 at β₁ = β₂ = ½.
"""

from __future__ import annotations

import itertools
import pathlib

import numpy as np
import pytest
from blocks import two_rectangles
from mpi4py import MPI

from breakwater.energy.ledger import EnergyLedger
from breakwater.loads.fields import PressureProfile, StagedProfile
from breakwater.loads.signals import Table
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Material, SurfaceLoad
from breakwater.outputs.applied import AppliedLoads
from breakwater.stepping.gn22 import GN22, GN22Parameters

COMM = MPI.COMM_WORLD

# Block a (0.2 × 0.1 m) on b (0.2 × 0.05 m), the front face a_left at x = −0.1 from
# y = 0.05 to 0.15. P2 triangles of 0.025 m: the profiles' kinks below are on nodes
# (y = 0.05, 0.1, 0.125, 0.15), so the facet quadrature integrates them exactly.
AW, AH, BH, SIZE = 0.2, 0.1, 0.05, 0.025
SWL = 0.1
WAVE_1 = ((-0.05, 0.8), (0.0, 1.0), (0.05, 0.0))   # (z above the SWL, p/p₁): crest 0.15
WAVE_2 = ((-0.05, 0.6), (0.0, 1.0), (0.025, 0.0))  # a smaller η*: 0.125
DT = 1e-4


@pytest.fixture(scope="module")
def stacked(folder: pathlib.Path) -> pathlib.Path:
    return two_rectangles(folder / "stacked.msh", COMM, a=(AW, AH), b=(AW, BH), h=SIZE)


def _area(points) -> float:
    """∫ p ds of a piecewise-linear profile (trapezoids: exact)."""
    return sum(0.5 * (p0 + p1) * (s1 - s0)
               for (s0, p0), (s1, p1) in itertools.pairwise(points))


def _block(stacked: pathlib.Path, load: SurfaceLoad, solver: str) -> tuple[GN22, EnergyLedger]:
    """Block a alone (no gravity, no contact) under one load, from rest."""
    data = read_mesh(stacked, COMM)
    model = ContactModel(data, [Body("a", Material(2000.0, 0.25, young_modulus=1e9))], [],
                         [], [load])
    stepper = GN22(model, DT, GN22Parameters(beta1=0.5, beta2=0.5), solver=solver)
    stepper.initialise(u0=None)
    return stepper, EnergyLedger(stepper)


# Two waves: p₁ a triangle over each (0 → 1000 Pa → 0 over 1 ms, then 0.5 ms at rest);
# the second wave starts at 1.5 ms + DT/2 (inside a step, where p₁ is 0) ...
P1 = Table((0.0, 5e-4, 1e-3, 1.5e-3 + 0.5 * DT, 2.0e-3 + 0.5 * DT, 2.5e-3 + 0.5 * DT),
           (0.0, 1000.0, 0.0, 0.0, 1000.0, 0.0), hold_last=True)
STARTS = (0.0, 1.5e-3 + 0.5 * DT)
# ... and a load whose amplitude is not 0 where its shape changes (the ledger's start
# traction must be the first shape's): a ramp held through the change at 0.75 ms.
HELD = Table((0.0, 5e-4, 1.0), (0.0, 1000.0, 1000.0))


def _staged(amplitude=P1, starts=STARTS) -> SurfaceLoad:
    field = StagedProfile((WAVE_1, WAVE_2), starts, (0.0, 1.0), (0.0, SWL))
    return SurfaceLoad("a_left", (), amplitude, field, name="storm")


@pytest.mark.parametrize("solver", ["fast", "reference"])
def test_one_stage_equals_the_fixed_profile(stacked, solver):
    # The staged field in its first stage is the fixed profile of the same points:
    # the same forms (the points read from a Constant instead of literals), hence the
    # same displacements to round-off (1e-12 of the largest).
    fixed = SurfaceLoad("a_left", (), P1, PressureProfile(WAVE_1, (0.0, 1.0), (0.0, SWL)))
    staged = _staged(starts=(0.0, 1.0))  # the second stage after the run
    u = []
    for load in (fixed, staged):
        stepper, _ = _block(stacked, load, solver)
        for _ in range(12):
            stepper.step()
        u.append(stepper.u[0].x.array.copy())
    scale = COMM.allreduce(float(np.abs(u[0]).max()), op=MPI.MAX)
    diff = COMM.allreduce(float(np.abs(u[0] - u[1]).max()) if len(u[0]) else 0.0, op=MPI.MAX)
    assert scale > 0 and diff <= 1e-12 * scale


@pytest.mark.parametrize("solver", ["fast", "reference"])
@pytest.mark.parametrize("amplitude,starts", [(P1, STARTS), (HELD, (0.0, 7.5e-4))],
                         ids=["between_waves", "under_load"])
def test_two_stages_force_and_ledger(stacked, solver, amplitude, starts):
    # Each stage's resultant (AppliedLoads: the unit resultant assembled again at the
    # change) is A(t) ∫ p ds along +x (a_left pushed inwards), the trapezoids of its
    # points: 1e-12. The ledger
    # (β₁ = β₂ = ½, no contact, no damping) closes to round-off, also when the shape
    # changes under load: measured 1e-16 of the work; 1e-9 far below the work of a
    # step (≈ 1e-2 of the total); the new shape as the start traction left 2e-3.
    stepper, ledger = _block(stacked, _staged(amplitude, starts), solver)
    applied = AppliedLoads(stepper.model, 0.5, {})
    rows = [ledger.record()]
    for _ in range(30):
        stepper.step()
        rows.append(ledger.record())
        t = float(stepper.t.value)
        applied.record(t)
        wave = WAVE_1 if t < starts[1] else WAVE_2
        fx = applied.forces()[0][0]
        assert fx == pytest.approx(amplitude(t) * _area(wave), rel=1e-12, abs=1e-9)
    assert stepper.model.loads[0].stage == 1
    work = rows[-1].external_work
    error = max(abs(r.balance_error) for r in rows)
    if COMM.rank == 0:
        print(f"\n{solver}: work {work:.6e} J/m, max |balance error| {error:.2e}")
    assert work > 0 and error < 1e-9 * work


def test_two_stages_fast_equals_reference(stacked):
    # The fast solver's re-assembled vector and the reference solver's forms (the same
    # Constant): the same displacements to the Newton tolerance (1e-8 of the largest).
    u = []
    for solver in ("fast", "reference"):
        stepper, _ = _block(stacked, _staged(HELD, (0.0, 7.5e-4)), solver)
        for _ in range(20):
            stepper.step()
        u.append(stepper.u[0].x.array.copy())
    scale = COMM.allreduce(float(np.abs(u[1]).max()), op=MPI.MAX)
    diff = COMM.allreduce(float(np.abs(u[0] - u[1]).max()) if len(u[0]) else 0.0, op=MPI.MAX)
    assert diff <= 1e-8 * scale
