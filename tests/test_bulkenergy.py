"""The energy ledger's whole-mesh terms from the fast solver's cached M and K.

On the fast solver the ledger (:class:`breakwater.energy.ledger.EnergyLedger`) takes the
kinetic ½v·Mv, strain ½u·Ku, Rayleigh power v̄·(αM + βK)v̄, external work f·Δu and the
bulk numerical dissipation (:func:`breakwater.energy.dissipation.bulk_coefficients`) from the
cached M, K and unit load vectors (:mod:`breakwater.energy.bulkenergy`); the reference solver
assembles the UFL forms of ``forms/``. Both are the same quadratic and linear forms with
the same quadrature, so they differ by round-off only: two ledgers on the same run, one
of each source, agree column by column at every step to 1e-10 of the ledger's energy
scale (its largest entry). The round-off is that of u·Ku (and v̄·Kv̄) with u dominated by
smooth, nearly rigid motion, whose products cancel: its bound ε Σ|u_i||K_ij||u_j| is
1e-9 of the strain energy on the Goda mesh (Σ|u||K||u| = 1e7 × ½u·Ku), the errors of
the products being random it is ~1e-11 in practice (u·Ku against an extended-precision
evaluation: 1.3e-11 from the matrix, 3.4e-12 from the form). Measured: 8.5e-12 of the
scale on the Goda run (1.4e-11 on 2 ranks; the strain and the Rayleigh columns), 2e-12
on the blocks. A wrong term fails by far: the work at the end amplitudes only, or
v̄ = v₁, changes a column by 0.1 and 6e-3 J/m on the Goda run (checked by hand).
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
from blocks import THREE_HEIGHTS, THREE_WIDTH, stacked_blocks, three_blocks
from mpi4py import MPI

from breakwater.casefile.case import load_case
from breakwater.energy import dissipation as numerical
from breakwater.energy.bulkenergy import TERMS
from breakwater.energy.ledger import FIELDS, EnergyLedger
from breakwater.model.mesh import read_mesh
from breakwater.model.model import (
    Body,
    ContactModel,
    ContactPair,
    Fixed,
    Material,
)
from breakwater.statics.initial import initial_state
from breakwater.stepping.gn22 import GN22, GN22Parameters
from breakwater.stepping.solver import NewtonOptions
from breakwater.stepping.stateproducts import StateProducts

COMM = MPI.COMM_WORLD
RTOL = 1e-10  # of the ledger's energy scale (see the module docstring)


def _both_ledgers(stepper: GN22, steps: int) -> dict[str, np.ndarray]:
    """Every ledger column of ``steps`` steps, from the matrices and from the forms."""
    ledgers = {source: EnergyLedger(stepper, source) for source in ("matrices", "forms")}
    assert type(ledgers["matrices"].bulk).__name__ == "MatrixTerms"
    assert type(EnergyLedger(stepper).bulk).__name__ == "MatrixTerms"  # the default
    rows: dict[str, list[list[float]]] = {k: [] for k in ledgers}
    for k in range(steps + 1):
        if k:
            stepper.step()
        for source, ledger in ledgers.items():
            row = ledger.record().as_dict()
            rows[source].append([row[f] for f in FIELDS])
    for ledger in ledgers.values():
        ledger.destroy()
    return {k: np.array(v) for k, v in rows.items()}


def _same(rows: dict[str, np.ndarray], nonzero: tuple[str, ...]) -> float:
    """The two ledgers agree to RTOL of the scale; returns the largest difference / scale."""
    a, b = rows["matrices"], rows["forms"]
    scale = np.abs(b).max()
    for k, name in enumerate(FIELDS):
        np.testing.assert_allclose(a[:, k], b[:, k], rtol=0, atol=RTOL * scale, err_msg=name)
    for name in nonzero:  # compared where the entry is not zero
        assert np.abs(b[:, FIELDS.index(name)]).max() > 1e-6 * scale, name
    return float(np.abs(a - b).max() / scale)


def test_goda_ledger_from_matrices_equals_forms(shared_dir: pathlib.Path) -> None:
    # The Goda case on a coarse mesh, 60 steps of 0.1 ms through the 2 ms pendulum pulse
    # (the load's work), with the case's Rayleigh damping and β₁ = 0.6, β₂ = 0.605 (the
    # bulk numerical dissipation), frictional contact sliding at the corner.
    case = load_case(None, ["mesh.refinement=0.7", "time.end_time=0.006",
                            f"output.directory={(shared_dir / 'goda').as_posix()}"])
    model, spec, _, _ = case.build(COMM)
    model.set_time(0.0)
    init = initial_state(model)
    stepper = GN22(model, spec.dt, GN22Parameters(spec.beta1, spec.beta2),
                   newton=NewtonOptions(rtol=spec.newton_rtol, atol=spec.newton_atol,
                                        max_it=spec.newton_max_it))
    stepper.initialise(init.u, init.v)
    rows = _both_ledgers(stepper, 60)
    error = _same(rows, ("kinetic", "strain", "rayleigh_dissipation", "external_work",
                         "numerical_dissipation"))
    if COMM.rank == 0:
        print(f"\nGoda: largest difference {error:.1e} of the ledger's scale")
    stepper.destroy()


@pytest.mark.parametrize("betas", [(0.6, 0.605), (0.5, 0.5)])
def test_blocks_ledger_from_matrices_equals_forms(folder: pathlib.Path,
                                                  betas: tuple[float, float]) -> None:
    # Three stacked blocks (two frictional pairs, the top block sliding on joint1 under a
    # pulse, the base fixed: Dirichlet rows), Rayleigh damping with both coefficients;
    # at β₁ = β₂ = ½ the bulk numerical dissipation vanishes and MΔa is not formed.
    path = stacked_blocks(folder / "three.msh", COMM, THREE_WIDTH, THREE_HEIGHTS, h=0.05)
    model = three_blocks(path, COMM, young_modulus=1e11, penalty=1e13)
    model.set_time(0.0)
    init = initial_state(model)
    stepper = GN22(model, 1e-4, GN22Parameters(*betas))
    stepper.initialise(init.u, init.v)
    rows = _both_ledgers(stepper, 60)
    nonzero = ("kinetic", "strain", "rayleigh_dissipation", "external_work",
               "friction_dissipation")
    error = _same(rows, (*nonzero, "numerical_dissipation") if betas[0] != 0.5 else nonzero)
    if betas == (0.5, 0.5):
        col = FIELDS.index("numerical_dissipation")
        assert np.array_equal(rows["matrices"][:, col],
                              rows["matrices"][:, FIELDS.index("numerical_dissipation_contact")])
        assert rows["matrices"][:, col].any()  # the contact share only
    if COMM.rank == 0:
        print(f"\nblocks {betas}: largest difference {error:.1e} of the ledger's scale")
    stepper.destroy()


def test_source_is_checked(folder: pathlib.Path) -> None:
    path = stacked_blocks(folder / "two.msh", COMM, 0.2, (0.1, 0.1), h=0.05)
    model = ContactModel(read_mesh(path, COMM),
                         [Body(f"block{k}", Material(2000.0, 0.25, young_modulus=1e9))
                          for k in range(2)],
                         [ContactPair("joint0", "block1", "block0", 1e12)], [Fixed("base")],
                         gravity=(0.0, -9.81))
    reference = GN22(model, 1e-4, solver="reference")
    assert type(EnergyLedger(reference).bulk).__name__ == "FormTerms"
    with pytest.raises(ValueError, match="need the fast solver"):
        EnergyLedger(reference, "matrices")
    with pytest.raises(ValueError, match="source must be one of auto, forms, matrices"):
        EnergyLedger(reference, "cached")
    reference.destroy()


def _abs_form(products: StateProducts, which: int, x: np.ndarray, y: np.ndarray) -> float:
    """|x|ᵀ|A||y| for A = M (which 2) or K (3) of the products' CSR arrays, this rank's rows.

    Collective on several ranks (y's ghosts).
    """
    ptr, col, values = products.csr[0], products.csr[1], products.csr[which]
    rows = np.repeat(np.arange(len(ptr) - 1), np.diff(ptr))
    return float(np.abs(x) @ np.bincount(rows, np.abs(values) * np.abs(
        products.with_ghosts(y)[col]), minlength=len(x)))


def test_goda_compiled_sums_equal_products(shared_dir: pathlib.Path) -> None:
    # The ledger's bulk terms come from the state's products (on any number of ranks:
    # each rank's rows, their ghost columns scattered), formed once
    # per accepted step for the predictor too (MatrixTerms._local_sums: ledger_sums,
    # Mv̄ = ½(Mv₀ + Mv₁), ...); MatMatMult of the combined vectors and NumPy's dot
    # products (MatrixTerms.local_products, PETSc's products) are the
    # reference, at the first record and along the pendulum pulse (work, damping,
    # numerical dissipation all nonzero). Both are round-off of the same quadratic
    # forms: each row's product x·(A y) rounds by at most about n_row ε Σ_j |A_ij||y_j|
    # (n_row ≤ 40 entries, ε = 2.2e-16), so the terms differ by at most
    # 2 · 40 ε Σ_k |c_k| |x_k|ᵀ|A_k||y_k| over the term's products c_k x_k·A_k y_k:
    # the bound, with a factor 10 (a single row with the smooth field's cancellation
    # K v̄ ~ h² |K||v̄| takes the Rayleigh power's relative difference to 3e-11, its
    # bound ~1e-12 of |v̄|ᵀ|K||v̄|). The external work has no product: 1e-12.
    case = load_case(None, ["mesh.refinement=0.7", "time.end_time=0.006",
                            f"output.directory={(shared_dir / 'goda_sums').as_posix()}"])
    model, spec, _, _ = case.build(COMM)
    model.set_time(0.0)
    init = initial_state(model)
    stepper = GN22(model, spec.dt, GN22Parameters(spec.beta1, spec.beta2))
    stepper.initialise(init.u, init.v)
    ledger = EnergyLedger(stepper)
    bulk = ledger.bulk
    assert type(bulk).__name__ == "MatrixTerms"
    sums = bulk._sums  # type: ignore[union-attr]
    assert sums is not None  # on any number of ranks (the rows' ghosts scattered)
    P = sums.products
    d = model.damping
    bound = 10 * 2 * 40 * np.finfo(float).eps
    v0 = None
    for k in range(12):
        if k:
            stepper.step()
        got, ref = bulk.local(k > 0), bulk.local_products(k > 0)  # type: ignore[union-attr]
        if k > 0:
            assert np.all(np.abs(ref) > 0)
        x = sums.x  # u₁, u₀, v₁, v₀, a₁, Δa
        u, v, a, da = x[0], x[2], x[4], x[5]
        scale = [_abs_form(P, 2, v, v), _abs_form(P, 3, u, u)]
        if k > 0:
            assert v0 is not None and np.array_equal(x[3], v0)
            vb = 0.5 * (v0 + v)
            k1, k2, k3, k4 = numerical.bulk_coefficients(
                float(stepper.dt.value), spec.beta1, spec.beta2, d.alpha, d.beta)
            scale += [d.alpha * _abs_form(P, 2, vb, vb) + d.beta * _abs_form(
                P, 3, vb, vb), 0.0, abs(k1) * _abs_form(P, 2, da, vb)
                + _abs_form(P, 2, np.abs(k2 * a) + np.abs(k3 * da), da)
                + abs(k4) * _abs_form(P, 3, da, vb)]
            assert abs(got[3] - ref[3]) <= 1e-12 * abs(ref[3])
        v0 = v.copy()
        for term, (g, r, c) in enumerate(zip(got, ref, scale, strict=False)):
            if term != 3:
                assert abs(g - r) <= bound * c, (k, TERMS[term], g, r, c)
        ledger.record()
    ledger.destroy()
    stepper.destroy()
