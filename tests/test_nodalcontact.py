"""The fast solver's nodal contact forces against the assembled UFL contact forms.

:class:`breakwater.contact.nodal.NodalContactForces` evaluates the contact law on the
interface nodes, which are the points of the interface forms' Gauss–Lobatto quadrature
on P2 facets, with the law's nodal derivatives
(:meth:`forms.ContactLaw.nodal`). Its f_c and ∂f_c/∂y must be those of the UFL
forms assembled by dolfinx (:class:`breakwater.stepping.condensed.InterfaceAssembler`) to
round-off: the quadrature is the same and the basis functions are Kronecker deltas at
its points up to basix's points (1e-16 off the facet's ends). Checked at random states
with open and closed nodes, slipping and sticking nodes (|v_T| near χ), on the Goda
case and on the three stacked blocks (two pairs, a body in both), serially and on 2
ranks. Tolerance: 1e-12 of each array's largest entry (the sums run over a few terms
of both signs; measured 1e-15).
"""

from __future__ import annotations

import pathlib

import numpy as np
import ufl
from blocks import stacked_blocks
from mpi4py import MPI

from breakwater.casefile.case import load_case
from breakwater.contact.nodal import NodalContactForces, nodal_contact_applies
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, ContactPair, Fixed, Material
from breakwater.stepping.condensed import InterfaceAssembler
from breakwater.stepping.gn22 import GN22

COMM = MPI.COMM_WORLD


def _random_state(stepper: GN22, seed: int) -> None:
    """u of ±1e-6 m (the penalty gaps of both signs), v, a around χ and larger."""
    rng = np.random.default_rng(seed + COMM.rank)
    for fns, scale in ((stepper.u, 1e-6), (stepper.v, 1e-9), (stepper.a, 1e-6),
                       (stepper.da, 1e-4)):
        for f in fns:
            f.x.array[:] = scale * rng.standard_normal(len(f.x.array))
            f.x.scatter_forward()


def _compare(stepper: GN22) -> None:
    solver = stepper.fast
    assert solver is not None
    providers = solver.providers
    assert providers and all(isinstance(p, NodalContactForces) for p in providers)
    forms = InterfaceAssembler(stepper.model, solver.layout, ufl.extract_blocks(
        stepper.model.interface_residual(stepper.u1, stepper.v1)), stepper.da,
        solver.interface.positions, solver.I)
    for seed in range(3):
        _random_state(stepper, seed)
        f = sum(p.vector() for p in providers)
        J = sum(p.matrix() for p in providers)
        f_ref, J_ref = forms.vector(), forms.matrix()
        assert np.abs(f_ref).max() > 0 and np.abs(J_ref).max() > 0
        np.testing.assert_allclose(f, f_ref, rtol=0, atol=1e-12 * np.abs(f_ref).max())
        np.testing.assert_allclose(J, J_ref, rtol=0, atol=1e-12 * np.abs(J_ref).max())


def test_goda_nodal_equals_forms() -> None:
    model, *_ = load_case(None, ["mesh.refinement=0.7"]).build(COMM)
    assert nodal_contact_applies(model)
    stepper = GN22(model, 1e-4)
    try:
        _compare(stepper)
    finally:
        stepper.destroy()


def test_blocks_nodal_equals_forms(folder: pathlib.Path) -> None:
    widths, heights = 0.4, (0.2, 0.15, 0.1)
    path = stacked_blocks(folder / "three.msh", COMM, widths, heights, h=0.05)
    bodies = [Body(f"block{k}", Material(ρ, 0.2, young_modulus=1e11))
              for k, ρ in enumerate((1800.0, 2300.0, 2500.0))]
    model = ContactModel(read_mesh(path, COMM), bodies,
                         [ContactPair("joint0", "block1", "block0", 1e13, friction=0.3),
                          ContactPair("joint1", "block2", "block1", 1e13, friction=0.6)],
                         [Fixed("base")], gravity=(0.0, -9.81))
    stepper = GN22(model, 1e-4)
    try:
        _compare(stepper)
    finally:
        stepper.destroy()


def test_left_product_is_the_dense_product() -> None:
    # X ∂f_c from the matrix's node structure equals the dense product (a random X).
    model, *_ = load_case(None, ["mesh.refinement=0.7"]).build(COMM)
    stepper = GN22(model, 1e-4)
    try:
        _random_state(stepper, 5)
        provider = stepper.solver.providers[0]
        n = provider.n
        X = np.random.default_rng(7).standard_normal((n + 3, n))
        expected = X @ provider.matrix()
        np.testing.assert_allclose(provider.left_product(X), expected, rtol=0,
                                   atol=1e-12 * np.abs(expected).max())
    finally:
        stepper.destroy()
