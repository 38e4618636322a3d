"""Interface node pairs and the Newton slip guard."""

from __future__ import annotations

import pathlib
import sys

import numpy as np
import pytest
from mpi4py import MPI

from breakwater.errors import MeshError
from breakwater.gn22 import _guard_slip
from breakwater.interface import InterfaceNodes
from breakwater.mesh import read_mesh
from breakwater.model import Body, ContactModel, ContactPair, Material

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from blocks import two_rectangles

χ = 1e-10
T2 = np.array([[[1.0, 0.0]]])  # tangent of a horizontal interface, master normal +y


def test_guard_lands_reversals_at_zero():
    w0 = np.array([[1e-3, 5.0]])  # the normal component (y) must be left alone
    w1 = np.array([[-2e-3, 7.0]])
    assert np.array_equal(_guard_slip(w0, w1, T2, χ), [[0.0, 7.0]])


@pytest.mark.parametrize(("w0", "w1"), [
    (1e-3, 5e-4),      # slows down without reversing
    (1e-3, 2e-3),      # speeds up
    (0.5 * χ, -2e-3),  # starts inside the band |w| <= χ, where the tangent is right
    (0.0, 1e-3),       # leaves zero
])
def test_guard_keeps_other_steps(w0, w1):
    a, b = np.array([[w0, 0.0]]), np.array([[w1, 0.0]])
    assert _guard_slip(a, b, T2, χ) is b


def test_guard_3d_tangent_basis():
    # 3D: master normal +z; tangents x and y. Only the reversing component is zeroed.
    t = np.array([[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
    out = _guard_slip(np.array([[1e-3, 1e-3, 0.0]]), np.array([[-1e-3, 2e-3, 3.0]]), t, χ)
    assert np.allclose(out, [[0.0, 2e-3, 3.0]], rtol=0, atol=1e-15)


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
