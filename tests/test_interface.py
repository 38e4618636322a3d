"""Interface node pairs, the nodal contact law and the Newton slip guard."""

from __future__ import annotations

import pathlib
import sys

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
import ufl
from dolfinx import fem, la

from breakwater import forms  # type: ignore[attr-defined]
from breakwater.common.errors import MeshError
from breakwater.contact.conforming import InterfaceNodes
from breakwater.contact.guardkernels import CURVED
from breakwater.contact.guardkernels import land as land_kernel
from breakwater.contact.slipguard import SlipGuard, guard_slip, land
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, ContactPair, Material

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from blocks import two_rectangles

χ = 1e-10
T2 = np.array([[[1.0, 0.0]]])  # tangent of a horizontal interface, master normal +y


def test_guard_lands_reversals_at_zero():
    w0 = np.array([[1e-3, 5.0]])  # the normal component (y) must be left alone
    w1 = np.array([[-2e-3, 7.0]])
    assert np.array_equal(guard_slip(w0, w1, T2, χ), [[0.0, 7.0]])


@pytest.mark.parametrize(("w0", "w1"), [
    (1e-3, 5e-4),      # slows down without reversing
    (1e-3, 2e-3),      # speeds up
    (0.5 * χ, -2e-3),  # starts inside the band |w| <= χ, where the tangent is right
    (0.0, 1e-3),       # leaves zero
])
def test_guard_keeps_other_steps(w0, w1):
    a, b = np.array([[w0, 0.0]]), np.array([[w1, 0.0]])
    assert guard_slip(a, b, T2, χ) is b


def test_guard_3d_isotropic():
    # 3D: master normal +z. A slip that turns by less than 90° is Newton's to take (the
    # x component's sign change alone is no reversal of the isotropic law); one that
    # turns by more lands at zero in the whole tangent plane, the normal part kept; the
    # same in any tangent basis (x, y, or turned by 30°).
    w0 = np.array([[1e-3, 1e-3, 0.0], [1e-3, 1e-3, 0.0]])
    w1 = np.array([[-1e-3, 2e-3, 3.0], [-2e-3, 5e-4, 3.0]])
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
    for t1, t2 in (([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), ([c, s, 0.0], [-s, c, 0.0])):
        t = np.array([[t1, t2], [t1, t2]])
        out = guard_slip(w0, w1, t, χ)
        assert np.allclose(out, [[-1e-3, 2e-3, 3.0], [0.0, 0.0, 3.0]], rtol=0, atol=1e-15)


def _φ(c: float) -> float:
    return c / np.sqrt(c * c + χ * χ)


def _newton(c: float, target: float, guarded: bool) -> tuple[float, int]:
    """Newton on the scalar law φ(c) = target (a node whose friction force is fixed)."""
    for its in range(1, 200):
        step = (_φ(c) - target) / (χ * χ / (c * c + χ * χ) ** 1.5)  # next c − step
        w1 = np.array([[c - step, 0.0]])
        c = float((guard_slip(np.array([[c, 0.0]]), w1, T2, χ) if guarded else w1)[0, 0])
        if abs(_φ(c) - target) < 1e-14:
            return c, its
    raise AssertionError("no convergence")


@pytest.mark.parametrize("target", [0.3, 0.9, 0.99, -0.999])
def test_landing_solves_the_scalar_law_at_once(target):
    # Newton on the saturating law from zero slip crawls (about one χ per iteration
    # towards a slip of 22χ at φ = 0.999); the landing inverts the law at the linear
    # model's force, which for one node is the force asked for: one step, exact.
    exact = χ * target / np.sqrt(1.0 - target * target)
    c, its = _newton(0.0, target, guarded=True)
    assert its == 1 and abs(c - exact) <= 1e-13 * abs(exact)
    c_plain, its_plain = _newton(0.0, target, guarded=False)
    assert abs(c_plain - exact) <= 1e-6 * abs(exact)
    if abs(target) > 0.5:
        assert its_plain >= 4


def test_landing_keeps_converged_slips_and_leaves_saturation_to_newton():
    # At a solution (a zero step) the landing is the slip itself: guard_slip returns
    # w1. Near saturation (a slip beyond CURVED χ) Newton's step stands.
    w = np.array([[5.0 * χ, 2.0], [-30.0 * χ, 0.0]])
    out = guard_slip(w, w.copy(), T2, χ)
    np.testing.assert_allclose(out, w, rtol=1e-14, atol=0)
    far = np.array([[2.0 * CURVED * χ, 0.0]])
    assert guard_slip(far, far * 1.01, T2, χ)[0, 0] == far[0, 0] * 1.01
    # A step that lands (from 2χ to 3χ) is left alone by the reference path's guard.
    w0, w1 = np.array([[2.0 * χ, 0.0]]), np.array([[3.0 * χ, 0.0]])
    assert guard_slip(w0, w1, T2, χ)[0, 0] > 5.0 * χ
    assert guard_slip(w0, w1, T2, χ, landing=False) is w1


def test_landing_compiled_equals_numpy_and_is_isotropic():
    # The compiled landing gives the NumPy reference's numbers bit for bit (tangent
    # planes of 1 and 2 dimensions); in 3D the guarded proposal is the same in any
    # tangent basis.
    rng = np.random.default_rng(3)
    for ntan in (1, 2):
        c0 = χ * rng.normal(size=(200, ntan)) * 10.0 ** rng.uniform(-1, 2, size=(200, 1))
        c1 = c0 + χ * rng.normal(size=(200, ntan)) * 10.0 ** rng.uniform(-2, 2, size=(200, 1))
        ref, on = land(c0, c1, χ)
        assert 20 < on.sum() < 180
        for k in range(200):
            out = np.empty(ntan)
            assert land_kernel(c0[k], c1[k], χ, out) == on[k]
            if on[k]:
                assert np.array_equal(out, ref[k])
    w0 = np.array([[3e-10, -1e-10, 0.0]])
    w1 = np.array([[3.5e-10, -0.5e-10, 4.0]])
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
    outs = [guard_slip(w0, w1, np.array([[t1, t2]]), χ)
            for t1, t2 in (([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), ([c, s, 0.0], [-s, c, 0.0]))]
    assert not np.array_equal(outs[0], w1)  # it landed
    np.testing.assert_allclose(outs[1], outs[0], rtol=0, atol=1e-12 * χ)  # round-off
    assert outs[0][0, 2] == 4.0  # the normal part kept


@pytest.fixture(scope="module")
def stacked(folder):
    comm = MPI.COMM_WORLD
    path = two_rectangles(folder / "narrow.msh", comm, a=(0.2, 0.1), b=(0.6, 0.2),
                          h=0.05)
    return read_mesh(path, comm)


def test_interface_nodes_pair_up(stacked):
    m = Material(2000.0, 0.25, shear_modulus=1e8)
    model = ContactModel(stacked, [Body("a", m), Body("b", m)],
                         [ContactPair("interface", "a", "b", penalty=1e10)])
    nodes = InterfaceNodes(model, model.pairs[0])
    # P2 on the interface [-0.1, 0.1] x {0.2}: 2 nodes per facet plus one, the same
    # list on every rank, sorted by x, with the master (b) normal +y.
    n_facets = round(0.2 / 0.05)
    assert nodes.size == 2 * n_facets + 1
    assert np.allclose(nodes.x[:, 1], 0.2) and np.all(np.diff(nodes.x[:, 0]) > 0)
    assert np.allclose(nodes.normal, [0.0, 1.0], atol=1e-14)
    assert np.allclose(nodes.tangents[:, 0], [1.0, 0.0], atol=1e-14)
    # gather returns the interface values of both sides at the same points
    fs, fm = model.functions("x")
    for f in (fs, fm):
        f.interpolate(lambda x: np.vstack([x[0], 2 * x[0]]))
    s, mm = nodes.gather(fs.x.array, fm.x.array)
    assert np.allclose(s, mm, atol=1e-14) and np.allclose(s[:, 0], nodes.x[:, 0], atol=1e-14)


def test_interface_between_wrong_bodies(stacked):
    m = Material(2000.0, 0.25, shear_modulus=1e8)
    with pytest.raises(MeshError, match="physical group 'nope' is not in the mesh"):
        ContactModel(stacked, [Body("a", m), Body("b", m)],
                     [ContactPair("nope", "a", "b", penalty=1e10)])


def _interface_values(model: ContactModel, nodes: InterfaceNodes, expr) -> np.ndarray:
    """Nodal values of a UFL vector on the interface, from the residual's quadrature.

    The interface measure's Gauss–Lobatto points are the slave's P2 nodes, so
    ``∫ expr·φ_i dS = W_i expr(x_i)`` with ``W_i = ∫ φ_i dS`` for each basis
    function φ_i of the slave: the ratio is the value the residual uses at node i.
    """
    pair = model.pairs[0]
    w = model.w[pair.slave]("+")
    ones = ufl.as_vector([1.0] * model.gdim)
    master = fem.Function(model.bodies[pair.master].V).x.array  # zeros
    out = []
    for f in (ufl.dot(expr, w), ufl.dot(ones, w)):
        b = fem.assemble_vector(model.form(f * pair.dS))
        b.scatter_reverse(la.InsertMode.add)
        out.append(nodes.gather(b.array, master)[0])
    return out[0] / out[1]


def test_nodal_law_is_the_residuals_law(stacked):
    """The nodal contact state (outputs, ledger checks) is the law the residual integrates.

    The same :class:`forms.ContactLaw` evaluated on UFL (assembled with the interface's
    nodal quadrature) and on the gathered nodal arrays, on a state with closed and
    open nodes and slip velocities inside and outside the stick band |v_T| < χ.
    Tolerance 1e-12 of the largest traction: round-off only.
    """
    m = Material(2000.0, 0.25, shear_modulus=1e8)
    χ = 1e-3
    model = ContactModel(stacked, [Body("a", m), Body("b", m)],
                         [ContactPair("interface", "a", "b", penalty=1e10, friction=0.4,
                                      regularisation=χ, gap=2e-8)])
    nodes = InterfaceNodes(model, model.pairs[0])
    pair = model.pairs[0]
    u, v = model.functions("u"), model.functions("v")
    # Slave a above master b at y = 0.2, x in [-0.1, 0.1]: g_n = 1e-6 x + 2e-8 is
    # closed for x < -0.02 and open beyond; v_T = 30χ x - 0.2χ runs through the band.
    u[0].interpolate(lambda x: np.vstack([3e-7 * x[0], 1e-6 * x[0]]))
    v[0].interpolate(lambda x: np.vstack([30 * χ * x[0], 0.5 + 0 * x[0]]))
    v[1].interpolate(lambda x: np.vstack([0.2 * χ + 0 * x[0], 0.3 + 0 * x[0]]))
    state = nodes.contact_state(*(f.x.array for f in u), *(f.x.array for f in v))
    closed = state["gap"] <= 0
    speed = np.linalg.norm(state["slip_velocity"], axis=1)
    assert closed.any() and (~closed).any()
    assert (closed & (speed < χ)).any() and (closed & (speed > χ)).any()
    assert np.all(state["pressure"][~closed] == 0)
    for velocity in (v, None):
        t_ufl = _interface_values(model, nodes, model.traction(pair, u, velocity))
        t_nodal = state["pressure"][:, None] * nodes.normal
        if velocity is not None:
            t_nodal = t_nodal + state["friction_traction"]
        scale = np.abs(t_nodal).max()
        assert scale > 0
        assert np.allclose(t_ufl, t_nodal, rtol=0, atol=1e-12 * scale)
    # The ledger's friction power density is the law's −t_T·v_T = μ p |v_T|²/sqrt(|v_T|² + χ²).
    law = pair.law.values()
    power = law.friction.power(state["pressure"], state["slip_velocity"])
    expected = 0.4 * state["pressure"] * speed**2 / np.sqrt(speed**2 + χ**2)
    assert np.allclose(power, expected, rtol=1e-14, atol=0)


def test_law_on_sample_values():
    """The law's formulas on nodal arrays (the paper's eqs. 7, 12, 14-15), including g_n = 0."""
    law = forms.ContactLaw(forms.PenaltyContact(2.0, 0.5), forms.RegularisedCoulomb(0.3, 1e-3))
    n = np.array([[0.0, 1.0]] * 3)
    u_s = np.array([[0.0, -1.0], [0.0, -0.5], [0.0, 0.25]])
    gap = law.gap(u_s, np.zeros_like(u_s), n)
    assert np.array_equal(gap, [-0.5, 0.0, 0.75])
    p = law.normal.pressure(gap)
    assert np.array_equal(p, [1.0, 0.0, 0.0])
    assert np.array_equal(law.normal.closed(gap), [1.0, 1.0, 0.0])
    assert np.array_equal(law.normal.energy(gap), [0.25, 0.0, 0.0])
    v_T = np.array([[4e-3, 0.0], [3e-3, 4e-3], [0.0, 0.0]])
    t_T = law.friction.traction(np.array([1.0, 2.0, 3.0]), v_T)
    assert np.allclose(t_T, [[-0.3 * 4 / np.sqrt(17), 0.0], [-0.6 * 3 / np.sqrt(26),
                                                             -0.6 * 4 / np.sqrt(26)], [0, 0]],
                       rtol=1e-15, atol=0)
    # the same law with fem.Constant-like parameters reads their values
    assert forms.ContactLaw.of(ContactPair("i", "a", "b", 2.0, 0.3, 1e-3, 0.5)).values() == law


def test_slip_guard_cuts_the_reversing_slave_step(stacked):
    """SlipGuard on a model: a Newton step reversing the slip velocity lands it at zero."""
    m = Material(2000.0, 0.25, shear_modulus=1e8)
    model = ContactModel(stacked, [Body("a", m), Body("b", m)],
                         [ContactPair("interface", "a", "b", penalty=1e10, friction=0.5)])
    nodes = InterfaceNodes(model, model.pairs[0])
    v, step = model.functions("v"), model.functions("y")
    v[0].x.array.reshape(-1, 2)[:] = [1e-3, 0.0]       # slave slides at +1 mm/s
    step[0].x.array.reshape(-1, 2)[:] = [2.0, 7.0]     # v − 1e-3·y: −1 mm/s, a reversal
    step[1].x.array.reshape(-1, 2)[:] = [0.0, 3.0]
    before = [f.x.array.copy() for f in step]
    guard = SlipGuard([nodes])
    assert guard([f.x.array for f in v], [f.x.array for f in step], 1e-3) == nodes.size
    ys, ym = nodes.gather(step[0].x.array, step[1].x.array)
    assert np.allclose(ys, [[1.0, 7.0]] * nodes.size, rtol=0, atol=1e-12)  # lands at v_T = 0
    assert np.array_equal(ym, np.tile([0.0, 3.0], (nodes.size, 1)))
    # off the interface the step is untouched
    interface = np.zeros(before[0].size // 2, bool)
    interface[nodes._slave[0]] = True
    assert np.array_equal(step[0].x.array.reshape(-1, 2)[~interface],
                          before[0].reshape(-1, 2)[~interface])
    # a second pass finds nothing to cut
    assert guard([f.x.array for f in v], [f.x.array for f in step], 1e-3) == 0
