"""A general pair's outputs in one compiled pass against the NumPy law (recordkernels).

:func:`breakwater.contact.recordkernels.pair_record` sums the history row's resultant,
contact length and penetration and the ledger's penalty energy and friction power. The
reference is the law of :mod:`forms.contact` on NumPy arrays, as the pair evaluated
them before (restated here): on random points, and on a block pushed over a wider one
at every accepted step. Sums in another order: equal to 1e-13 of each quantity's scale.
"""

from __future__ import annotations

import gc
import pathlib

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from blocks import two_rectangles

from breakwater import forms  # type: ignore[attr-defined]
from breakwater.contact.recordkernels import RECORD, pair_record
from breakwater.contact.surfaces import SurfacePair
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Fixed, Material, SurfaceLoad
from breakwater.stepping.gn22 import GN22

COMM = MPI.COMM_WORLD
RTOL = 1e-13  # of each quantity's scale: the same terms summed in another order


def _law(eps: float, mu: float, chi: float) -> forms.ContactLaw:
    return forms.ContactLaw(forms.PenaltyContact(eps), forms.RegularisedCoulomb(mu, chi))


def _reference(law, index, gap, all_weight, forces, ns, k, lam, v_T, friction):  # type: ignore[no-untyped-def]
    """The NumPy path: the points' state as SurfaceContact.state() builds it, the law."""
    full = np.full(len(all_weight), np.nan)
    full[index] = gap
    closed = full <= 0
    energy = np.sum(all_weight[closed] * law.normal.energy(full[closed]))
    power = np.sum(law.friction.power(lam[k], v_T)) if len(k) else 0.0
    normal = -forces[:, :ns].sum(axis=(0, 1))
    return np.array([energy, power, all_weight[closed].sum(),
                     -full[closed].min(initial=0.0), *normal, *friction.sum(axis=0)])


def _check(got: np.ndarray, ref: np.ndarray, scales: np.ndarray) -> None:
    for name, g, r, s in zip(RECORD, got, ref, scales, strict=True):
        assert abs(g - r) <= RTOL * s, (name, g, r)


@pytest.mark.parametrize("seed", range(5))
def test_random_points(seed: int) -> None:
    """Points open, closed and without a projection; friction nodes sliding and sticking."""
    rng = np.random.default_rng(seed)
    eps, mu, chi, ns = 1e10, 0.4, 1e-5, 3
    n_all, n_nodes = 60, 25
    index = np.sort(rng.choice(n_all, 45, replace=False))
    gap = 1e-6 * rng.normal(size=len(index))
    all_weight = rng.uniform(1e-3, 1e-2, n_all)
    forces = rng.normal(size=(len(index), ns + 3, 2))
    lam = rng.uniform(0, 1e3, n_nodes)
    k = np.sort(rng.choice(n_nodes, 12, replace=False))
    v_T = chi * rng.normal(size=(len(k), 2)) * rng.choice([1e-3, 1.0, 1e3], size=(len(k), 1))
    friction = rng.normal(size=(len(k), 2))
    law = _law(eps, mu, chi)
    got = pair_record(index, gap, all_weight, forces, ns, eps, k, lam, v_T, friction, mu, chi)
    ref = _reference(law, index, gap, all_weight, forces, ns, k, lam, v_T, friction)
    scales = np.array([ref[0], ref[1], ref[2], ref[3], *[np.abs(forces).sum()] * 2,
                       *[np.abs(friction).sum()] * 2])
    _check(got, ref, scales)
    # Nothing closed, no friction node: zeros.
    none = pair_record(index, np.abs(gap) + 1e-9, all_weight, forces[:0], ns, eps,
                       k[:0], lam, v_T[:0], friction[:0], mu, chi)
    np.testing.assert_array_equal(none, np.zeros(len(RECORD)))


def test_a_sliding_block_records_what_the_law_gives(folder: pathlib.Path) -> None:
    """At every accepted step of a block pushed into sliding, the pair's measures and
    energies through the compiled record equal the NumPy law's on the pair's state."""
    mesh = two_rectangles(folder / "record_slide.msh", COMM, (0.5, 0.25), (1.5, 0.5), 0.125)
    material = Material(density=2000.0, poisson=0.25, young_modulus=1e9)
    P, mu = 1e5, 0.3
    pair_spec = SurfacePair("c", "a", "b", "interface", ("interface", "b_top_free"), 1e10, mu)
    model = ContactModel(
        read_mesh(mesh, COMM), [Body("a", material), Body("b", material)], [],
        fixed=[Fixed("b_bottom")],
        loads=[SurfaceLoad("a_top", (0.0, -P), lambda t: 1.0),
               SurfaceLoad("a_left", (1.5 * mu * P * 2, 0.0),
                           lambda t: float(np.clip((t - 2e-3) / 5e-3, 0, 1)))],
        surface_pairs=[pair_spec])
    stepper = GN22(model, 5e-4)
    try:
        stepper.initialise()
        pair = stepper.surfaces[-1]
        law = pair.law
        sliding = 0
        for _ in range(20):
            stepper.step()
            with pair.recording():
                got = np.array([*pair.energies(), *pair.measure().values()])
                normal, friction = pair.resultants()
                state = pair.state()
                u0, u1, v1 = pair._state(accepted=True)
                lam = pair._normal(u1)["lam"]
                fr = pair._friction(u0, v1, lam, accepted=True)
            closed = state["gap"] <= 0
            power = 0.0 if fr is None else np.sum(law.friction.power(lam[fr["k"]], fr["v_T"]))
            force = normal + friction
            energy = np.sum(state["weight"][closed] * law.normal.energy(state["gap"][closed]))
            ref = np.array([energy, power, force[0], force[1], state["weight"][closed].sum(),
                            -state["gap"][closed].min(initial=0.0)])
            scales = np.array([ref[0], max(ref[1], 1e-30), *[np.abs(force).max()] * 2,
                               ref[4], max(ref[5], 1e-30)])
            assert np.all(np.abs(got - ref) <= RTOL * scales), (got, ref)
            # The resultant's parts are the friction's and the points' forces.
            expected_friction = np.zeros(2) if fr is None else fr["force"].sum(axis=0)
            np.testing.assert_allclose(friction, expected_friction, rtol=0,
                                       atol=RTOL * np.abs(force).max())
            sliding += power > 0
        assert sliding > 5  # the block slides: the friction power is not trivially zero
    finally:
        stepper.destroy()
        gc.collect()
        COMM.barrier()
