"""Friction on the 3-D general (non-matching) contact pair (issue 25).

- The compiled friction kernels (:mod:`breakwater.contact.friction3d`) against the NumPy
  reference (:func:`breakwater.contact.pointkernels3d.friction_forces`), and the whole
  contact Jacobian (normal and friction parts) against complex steps of the reference and
  central finite differences of the compiled residual, on curved 6-node faces pressed
  into each other with slip velocities of the order of χ (pure arrays: every rank runs
  them).
"""

from __future__ import annotations

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater.contact import forcekernels3d, friction3d, pointkernels3d
from breakwater.contact.projection3d import shape

COMM = MPI.COMM_WORLD


# --- the kernels ----------------------------------------------------------------------------

def _face(rng: np.random.Generator, y: float, bend: float, up: bool) -> np.ndarray:
    """A curved 6-node triangle near the plane y (mid-edge nodes moved by up to bend),
    its normal along +y if ``up`` (as test_pair3d's)."""
    corners = np.array([[0.0, y, 0.0], [1.0, y, 0.0], [0.0, y, 1.0]])
    corners += 0.005 * rng.normal(size=(3, 3))
    if up:
        corners = corners[[0, 2, 1]]
    mids = np.array([0.5 * (corners[a] + corners[b]) for a, b in ((1, 2), (0, 2), (0, 1))])
    mids[:, 1] += bend * rng.uniform(-1, 1, 3)
    return np.concatenate([corners, mids])


class _Points:
    """K contact points, each on its own slave face pressed 0.03 into its own master face;
    each slave node's start-of-step master point on its point's master face."""

    K, ns, nm = 6, 6, 6
    eps, cu, cv, mu, chi = 1e10, 0.3, 0.7, 0.4, 1e-3

    def __init__(self, seed: int) -> None:
        rng = np.random.default_rng(seed)
        K, ns, nm = self.K, self.ns, self.nm
        self.xs = np.stack([_face(rng, -0.03, 0.005, False) for _ in range(K)])
        self.xm = np.stack([_face(rng, 0.0, 0.005, True) for _ in range(K)])
        xi = rng.uniform(0.1, 0.4, (K, 2))
        self.Ns = shape(xi, ns)[0]
        self.start = xi + 0.01 * rng.normal(size=(K, 2))
        self.w = rng.uniform(0.5, 1.5, K)
        self.pos_s = np.arange(K * ns * 3).reshape(K, ns, 3)
        self.pos_m = K * ns * 3 + np.arange(K * nm * 3).reshape(K, nm, 3)
        self.n = K * (ns + nm) * 3
        self.f = np.arange(K)
        self.node_of = np.arange(K * ns).reshape(K, ns)
        self.node_pos = self.pos_s.reshape(-1, 3)
        # Each slave node's master point: on its point's master face, in the interior.
        self.facet0 = np.repeat(self.f, ns)
        xi0 = rng.uniform(0.1, 0.4, (K * ns, 2))
        self.N0 = shape(xi0, nm)[0]
        self.T0 = friction3d.tangent_basis(self.xm[self.facet0], xi0)
        # Velocities: slips of the order of χ (the law's curved zone) and beyond.
        self.v0 = np.append(self.chi * rng.normal(size=self.n) * rng.uniform(0.2, 5, self.n),
                            0.0)

    def residual(self, y: np.ndarray) -> np.ndarray:
        """The compiled f_c (normal and friction) at Δa = y (u₀ = 0, v₀)."""
        u1 = np.append(self.cu * y, 0.0)
        v1 = self.v0 + np.append(self.cv * y, 0.0)
        out, lam, _, _, _ = forcekernels3d.residual(
            self.xs, self.xm, self.pos_s, self.pos_m, u1, self.f, self.f, self.Ns,
            self.start, self.w, False, self.eps, 0.0, self.node_of, self.K * self.ns)
        k, _, force, _ = friction3d.friction(lam, self.facet0, self.N0, self.T0,
                                             self.node_pos, self.pos_m, v1, self.mu, self.chi)
        friction3d.add_friction(out, k, force, self.facet0, self.N0, self.node_pos, self.pos_m)
        return out

    def jacobian(self, y: np.ndarray) -> np.ndarray:
        """The compiled ∂f_c/∂Δa at Δa = y, dense."""
        u1 = np.append(self.cu * y, 0.0)
        v1 = self.v0 + np.append(self.cv * y, 0.0)
        _, lam, _, gap, _ = forcekernels3d.residual(
            self.xs, self.xm, self.pos_s, self.pos_m, u1, self.f, self.f, self.Ns,
            self.start, self.w, False, self.eps, 0.0, self.node_of, self.K * self.ns)
        k, c, _, unit = friction3d.friction(lam, self.facet0, self.N0, self.T0,
                                            self.node_pos, self.pos_m, v1, self.mu, self.chi)
        extra = friction3d.friction_dofs(k, self.facet0, self.node_pos, self.pos_m)
        act, A, rows, dpw = forcekernels3d.jacobian(
            self.xs, self.xm, self.pos_s, self.pos_m, u1, self.f, self.f, self.Ns, self.start,
            self.w, gap, False, self.eps, 0.0, self.cu, extra)
        where = np.full(self.n + 1, -1, np.int64)
        where[act] = np.arange(len(act))
        friction3d.friction_jacobian(A, where, k, c, unit, lam, self.facet0, self.N0, self.T0,
                                     self.node_pos, self.pos_m, self.mu, self.chi, self.cv,
                                     self.f, self.node_of, self.Ns, rows, dpw)
        out = np.zeros((self.n, self.n))
        out[np.ix_(act, act)] = A
        return out

    def reference(self, y: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        """The NumPy reference's f_c at Δa = y (real or complex), friction at ``nodes``."""
        K, ns = self.K, self.ns
        u1 = self.cu * y
        v1 = self.v0[:-1] + self.cv * y
        xs = self.xs + u1[self.pos_s]
        xm = self.xm + u1[self.pos_m]
        forces, g = pointkernels3d.normal_forces(self.Ns, self.start, xs, xm, self.eps, self.w)
        out = np.zeros(self.n, dtype=forces.dtype)
        np.add.at(out, self.pos_s.ravel(), forces[:, :ns].ravel())
        np.add.at(out, self.pos_m.ravel(), forces[:, ns:].ravel())
        lam = ((-self.eps * g * self.w)[:, None] * self.Ns).reshape(K * ns)
        F = pointkernels3d.friction_forces(
            lam[nodes], self.N0[nodes], self.T0[nodes], v1[self.node_pos[nodes]],
            v1[self.pos_m[self.facet0[nodes]]], self.mu, self.chi)
        np.add.at(out, self.node_pos[nodes].ravel(), -F.ravel())
        master = self.N0[nodes][:, :, None] * F[:, None, :]
        np.add.at(out, self.pos_m[self.facet0[nodes]].ravel(), master.ravel())
        return out


@pytest.mark.parametrize("seed", [0, 1])
def test_friction_kernel_and_jacobian(seed: int) -> None:
    """The compiled friction forces equal the reference's to 1e-12 of their scale; the
    compiled Jacobian (normal and friction parts) equals the reference's complex steps to
    1e-9 of its largest entry (the friction's ∂φ/∂c is analytic there, a complex step of
    φ here: both exact to round-off, summed over ~10³ terms of up to μλ/χ), and central
    differences of the compiled residual (h = 1e-9 in Δa, so that Δv = 7e-10 stays far
    below χ = 1e-3: the O(h²) error of the law's curvature 1/χ² is 1e-12 relative) to 1e-6
    of the largest entry."""
    P = _Points(seed)
    y0 = np.zeros(P.n)
    u1 = np.zeros(P.n + 1)
    _, lam, _, gap, _ = forcekernels3d.residual(
        P.xs, P.xm, P.pos_s, P.pos_m, u1, P.f, P.f, P.Ns, P.start, P.w, False, P.eps, 0.0,
        P.node_of, P.K * P.ns)
    assert np.all(gap < 0)
    k, c, force, _ = friction3d.friction(lam, P.facet0, P.N0, P.T0, P.node_pos, P.pos_m,
                                         P.v0, P.mu, P.chi)
    # The 6-node triangle's vertex shape values are negative inside: those nodes' λ < 0
    # carry no friction; the mid-edge nodes' do.
    assert 0 < len(k) < P.K * P.ns and np.all(lam[k] > 0)
    assert np.abs(c).max() > 3 * P.chi and np.abs(c).min() < P.chi  # both sides of χ
    ref = pointkernels3d.friction_forces(lam[k], P.N0[k], P.T0[k], P.v0[P.node_pos[k]],
                                         P.v0[P.pos_m[P.facet0[k]]], P.mu, P.chi)
    assert np.abs(force - ref).max() < 1e-12 * np.abs(ref).max()
    # |F| ≤ μλ, opposite the slip: F·(Σ c_α T₀_α) < 0.
    slip = np.einsum("ka,kad->kd", c, P.T0[k])
    assert np.all(np.linalg.norm(force, axis=1) <= P.mu * lam[k] * (1 + 1e-12))
    assert np.all(np.sum(force * slip, axis=1) < 0)
    # The compiled f_c is the reference's.
    R = P.residual(y0)
    R_ref = P.reference(y0, k)
    assert np.abs(R - R_ref).max() < 1e-10 * np.abs(R_ref).max()
    # The Jacobian against the reference's complex steps.
    J = P.jacobian(y0)
    H = 1e-30
    J_ref = np.empty_like(J)
    for j in range(P.n):
        y = np.zeros(P.n, complex)
        y[j] = 1j * H
        J_ref[:, j] = P.reference(y, k).imag / H
    scale = np.abs(J_ref).max()
    friction_part = np.abs(J_ref - forcekernels_normal(P)).max()
    assert friction_part > 1e-3 * scale  # the friction part is not negligible here
    assert np.abs(J - J_ref).max() < 1e-9 * scale
    # And central differences of the compiled residual.
    h = 1e-9
    for j in range(P.n):
        e = np.zeros(P.n)
        e[j] = h
        fd = (P.residual(e) - P.residual(-e)) / (2 * h)
        assert np.abs(fd - J[:, j]).max() < 1e-6 * scale, j


def forcekernels_normal(P: _Points) -> np.ndarray:
    """The normal part of the Jacobian alone (the compiled kernel without friction)."""
    u1 = np.zeros(P.n + 1)
    _, _, _, gap, _ = forcekernels3d.residual(
        P.xs, P.xm, P.pos_s, P.pos_m, u1, P.f, P.f, P.Ns, P.start, P.w, False, P.eps, 0.0,
        P.node_of, P.K * P.ns)
    act, A, _, _ = forcekernels3d.jacobian(P.xs, P.xm, P.pos_s, P.pos_m, u1, P.f, P.f, P.Ns,
                                           P.start, P.w, gap, False, P.eps, 0.0, P.cu,
                                           np.zeros(0, np.int64))
    out = np.zeros((P.n, P.n))
    out[np.ix_(act, act)] = A
    return out
