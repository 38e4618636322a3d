"""A conforming pair's per-step outputs from nodal sums against its assembled UFL forms.

:class:`breakwater.contact.pairkernels.NodalPairSums` evaluates the history's resultants
(contact length, normal and tangential resultants, largest nodal penetration) and the
ledger's interface terms (penalty energy, friction power, the interface numerical
dissipation) as compiled sums over the interface nodes, the points of the pair's
Gauss–Lobatto quadrature. They must be the assembled forms
(:meth:`ConformingPair.measure_forms`, :meth:`ConformingEnergy.local_forms`, kept as the
reference) to round-off, at random states with open and closed nodes, sticking and
slipping ones (|v_T| around χ), on the Goda case and on the three stacked blocks (two
pairs, a body in both, one with an initial gap; tilted, so that no normal is along an
axis), serially and on 2 ranks. Tolerance: 1e-12 of each term's scale (measured
~1e-15); the dissipation, a sum of terms of both signs, 1e-11 of its own size.
"""

from __future__ import annotations

import pathlib

import numpy as np
from blocks import THREE_HEIGHTS, THREE_WIDTH, stacked_blocks, three_blocks
from mpi4py import MPI

from breakwater.casefile.case import load_case
from breakwater.contact.pairstate import ConformingPair
from breakwater.stepping.gn22 import GN22

COMM = MPI.COMM_WORLD


def _random(fns, scale: float, rng: np.random.Generator) -> None:
    for f in fns:
        f.x.array[:] = scale * rng.standard_normal(len(f.x.array))
        f.x.scatter_forward()


def _compare(stepper: GN22) -> None:
    pairs = [p for p in stepper.contacts if isinstance(p, ConformingPair)]
    assert pairs and all(p.nodal_sums() is not None for p in pairs)
    for seed in range(3):
        rng = np.random.default_rng(seed + 10 * COMM.rank)
        energies = [p.energy_terms(stepper.model.functions("u0"),
                                   stepper.model.functions("v0")) for p in pairs]
        for e in energies:
            _random(e.u0, 1e-6, rng)
            _random(e.v0, (1e-10, 1e-9, 1e-7)[seed], rng)
        _random(stepper.u, 1e-6, rng)
        _random(stepper.v, (1e-10, 1e-9, 1e-7)[seed], rng)
        stepper.dt.value = 1e-4
        for pair, e in zip(pairs, energies, strict=True):
            got, ref = pair.measure(), pair.measure_forms()
            assert got.keys() == ref.keys()
            assert ref[f"{pair.name}_normal_force"] > 0
            assert 0 < ref[f"{pair.name}_contact_length"]
            for k in ref:
                assert abs(got[k] - ref[k]) <= 1e-12 * max(abs(ref[k]), 1e-300), k
            for step in (False, True):
                got_e = stepper.model.reduce(e.local(step))
                ref_e = stepper.model.reduce(e.local_forms(step))
                scale = np.abs(ref_e).max()
                assert scale > 0 and np.all(ref_e[:2] > 0)
                np.testing.assert_allclose(got_e, ref_e, rtol=0, atol=1e-12 * scale)
                assert abs(got_e[2] - ref_e[2]) <= 1e-11 * max(abs(ref_e[2]), 1e-300) \
                    or not step


def test_goda_nodal_sums_equal_forms() -> None:
    model, *_ = load_case(None, ["mesh.refinement=0.7"]).build(COMM)
    stepper = GN22(model, 1e-4)
    try:
        _compare(stepper)
    finally:
        stepper.destroy()


def test_blocks_nodal_sums_equal_forms(folder: pathlib.Path) -> None:
    path = stacked_blocks(folder / "three.msh", COMM, THREE_WIDTH, THREE_HEIGHTS, h=0.05)
    # Tilted by 0.3 rad: the normals and tangents have two nonzero components each.
    model = three_blocks(path, COMM, young_modulus=1e11, penalty=1e13, gap=2e-7, tilt=0.3)
    stepper = GN22(model, 1e-4)
    try:
        _compare(stepper)
    finally:
        stepper.destroy()
