"""Friction on the 3-D general (non-matching) contact pair (issue 25).

- The compiled friction kernels (:mod:`breakwater.contact.friction3d`) against the NumPy
  reference (:func:`breakwater.contact.pointkernels3d.friction_forces`), and the whole
  contact Jacobian (normal and friction parts) against complex steps of the reference and
  central finite differences of the compiled residual, on curved 6-node faces pressed
  into each other with slip velocities of the order of χ, the nodes' normal forces scaled
  as the pair scales them (``friction_normals``: some 6-node vertex forces are negative;
  the scale's derivative included) (pure arrays: every rank runs them).
- A block pushed diagonally on a slab across non-matching faces (test_pair3d's), from its
  frictional static state: above μN it slides along the push at (F − μN)/m, the friction
  opposite the slip; below, it creeps at the regularised law's rate; the Newton converges
  quadratically.
- A block held up to t = 0 (pushed with F = 1.5 μN) between rollers on its side faces,
  released (:mod:`breakwater.statics.release`): its slave nodes on the rollers' edges
  start sliding too, and it slides at (F − μN)/m from t = 0.
"""

from __future__ import annotations

import pathlib
from typing import Any
from unittest import mock

import numpy as np
import pytest
from mpi4py import MPI

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
import itertools

import ufl
from breakwater.meshes.apart import Box, boxes
from dolfinx import fem

from breakwater.contact import (
    coupling,
    forcekernels,
    forcekernels3d,
    friction3d,
    guardkernels,
    newtonaids,
    pointkernels3d,
)
from breakwater.contact.projection3d import shape
from breakwater.contact.surfaces import SurfacePair
from breakwater.model.mesh import read_mesh
from breakwater.model.model import Body, ContactModel, Fixed, Material, SurfaceLoad
from breakwater.statics.initial import initial_state

COMM = MPI.COMM_WORLD


def no_crawl(lam: np.ndarray) -> np.ndarray:
    """No crawl point at any node (:func:`friction3d.friction`'s ``lin``): the law itself."""
    return np.full((len(lam), 2), np.nan)


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
        lam, _ = newtonaids.friction_normals(lam, self.facet0)
        k, _, force, _ = friction3d.friction(lam, self.facet0, self.N0, self.T0,
                                             self.node_pos, self.pos_m, v1, self.mu, self.chi,
                                             no_crawl(lam))
        friction3d.add_friction(out, k, force, self.facet0, self.N0, self.node_pos, self.pos_m)
        return out

    def jacobian(self, y: np.ndarray) -> np.ndarray:
        """The compiled ∂f_c/∂Δa at Δa = y, dense."""
        u1 = np.append(self.cu * y, 0.0)
        v1 = self.v0 + np.append(self.cv * y, 0.0)
        _, lam, _, gap, _ = forcekernels3d.residual(
            self.xs, self.xm, self.pos_s, self.pos_m, u1, self.f, self.f, self.Ns,
            self.start, self.w, False, self.eps, 0.0, self.node_of, self.K * self.ns)
        scaled, scale = newtonaids.friction_normals(lam, self.facet0)
        k, c, _, unit = friction3d.friction(scaled, self.facet0, self.N0, self.T0,
                                            self.node_pos, self.pos_m, v1, self.mu, self.chi,
                                            no_crawl(lam))
        extra = friction3d.friction_dofs(k, self.facet0, self.node_pos, self.pos_m)
        act, A, rows, dpw = forcekernels3d.jacobian(
            self.xs, self.xm, self.pos_s, self.pos_m, u1, self.f, self.f, self.Ns, self.start,
            self.w, gap, False, self.eps, 0.0, self.cu, extra)
        where = np.full(self.n + 1, -1, np.int64)
        where[act] = np.arange(len(act))
        friction3d.friction_jacobian(A, where, k, c, unit, scaled, lam, scale, self.facet0,
                                     self.N0, self.T0, self.node_pos, self.pos_m, self.mu,
                                     self.chi, self.cv, self.f, self.node_of, self.Ns, rows,
                                     dpw)
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
        # friction_normals' scale (every node has a master point here).
        lam = lam * (np.sum(lam) / np.sum(lam[np.real(lam) > 0]))
        F = pointkernels3d.friction_forces(
            lam[nodes], self.N0[nodes], self.T0[nodes], v1[self.node_pos[nodes]],
            v1[self.pos_m[self.facet0[nodes]]], self.mu, self.chi)
        np.add.at(out, self.node_pos[nodes].ravel(), -F.ravel())
        master = self.N0[nodes][:, :, None] * F[:, None, :]
        np.add.at(out, self.pos_m[self.facet0[nodes]].ravel(), master.ravel())
        return out


def _one_node(c0: np.ndarray, c1: np.ndarray, dv: float, dim: int
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One slave node over a resting master facet (3 nodes, shape values 1/3 each) of a
    plane whose tangent basis is x̂ (2-D: t₀ = x̂) or (x̂, −ẑ) (3-D: n̄ = ŷ), at the
    slip c0 (tangent components), Newton's step giving the slip c1.

    Returns:
        v1, the step, the facet (0), N̄₀ and the tangent basis (2-D: t₀ ``(1, 2)``).
    """
    T = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])[: dim - 1, :dim]
    n = dim * 4  # the slave node's DOFs, then the facet's three nodes'
    v1 = np.zeros(n + 1)
    v1[:dim] = c0 @ T
    step = np.zeros(n)
    step[:dim] = (c0 - c1) @ T / dv  # c₁ = c₀ − dv T (y_s − ȳ_m), ȳ_m = 0
    step[1] = 0.3  # a normal step, kept
    basis = T[0][None, :] if dim == 2 else T[None, :, :]
    return v1, step, np.zeros(1, np.int64), np.full((1, 3), 1.0 / 3.0), basis


@pytest.mark.parametrize("angle", [0.0, 0.7, 2.5])
@pytest.mark.parametrize("kind", ["crawl", "land", "reverse"])
def test_slip_guard_is_the_2d_guard_turned(angle: float, kind: str) -> None:
    """The 3-D slip guard (:func:`friction3d.slip_guard`, with crawl points) on a slip
    along the tangent basis' direction (cos θ, sin θ) is the 2-D guard's
    (:func:`guardkernels.slip_guard`) on that line, turned by θ: the same landing, the
    same crawl point (a vector along Newton's proposal), the same bounds; the normal step
    kept. The 2-D guard is the reference (``tests/test_contactkernels.py`` checks it
    against its formulas); asked to 1e-13 relative (one rotation's round-off). ``crawl``:
    a slip of 200χ that Newton grows to 260χ, beyond the curved zone (the linear model's
    force 1 − 5e-6): its law is linearised at the next iterate where the law gives that
    force (316χ, within GROW |c₁|); ``land``: from 2χ to 3χ (force 0.983), landed on the
    law's curve; ``reverse``: from 5χ to −5χ, landed at zero slip."""
    chi, dv = 1e-3, 0.5e-3
    a0, a1 = {"crawl": (200.0, 260.0), "land": (2.0, 3.0), "reverse": (5.0, -5.0)}[kind]
    turn = np.array([np.cos(angle), np.sin(angle)])
    v2, step2, f2, N2, t2 = _one_node(np.array([a0 * chi]), np.array([a1 * chi]), dv, 2)
    lin2, next2 = np.full(1, np.nan), np.full(1, np.nan)
    bounds2 = np.full(1, guardkernels.FREE, np.int8)
    fixed2 = guardkernels.slip_guard(step2, v2, f2, N2, t2, np.array([[0, 1]]),
                                     np.arange(2, 8).reshape(1, 3, 2), dv, chi, lin2, next2,
                                     bounds2, np.ones(1, bool))
    v3, step3, f3, N3, T3 = _one_node(a0 * chi * turn, a1 * chi * turn, dv, 3)
    crawl = newtonaids.CrawlPoints(1, 2, friction3d.slip_guard)
    fixed3 = crawl.guard(step3, v3, (f3, N3, T3), np.array([[0, 1, 2]]),
                         np.arange(3, 12).reshape(1, 3, 3), dv, chi, np.ones(1, bool))
    assert fixed3 == fixed2 == (0 if kind == "crawl" else 1)
    np.testing.assert_array_equal(crawl._bounds, bounds2)
    assert bool(np.isnan(next2[0])) == (kind != "crawl") == (not crawl.any)
    if kind == "crawl":
        assert next2[0] == pytest.approx(316.2 * chi, rel=1e-3)
        # 1e-9: the law's inverse χ f/sqrt(1 − f²) magnifies the slips' round-off by
        # 1/(1 − f²) = 1e5 (measured 1.1e-11).
        np.testing.assert_allclose(crawl.at[0], next2[0] * turn, rtol=1e-9)
    # The slave's tangential step (the slip's), turned; its normal step kept.
    c2 = (step2[0] * t2[0, 0]) * turn
    c3 = step3[:3] @ T3[0].T
    np.testing.assert_allclose(c3, c2, rtol=1e-13, atol=1e-13 * abs(c2).max())
    assert step3[1] == step2[1] == 0.3
    # The next iterate's friction at the crawl point: the law's tangent line there, as
    # the 2-D pair's (forcekernels.friction), turned.
    if kind == "crawl":
        lam = np.array([2.0])
        _, _, force2, _ = forcekernels.friction(lam, f2, N2, t2, np.array([[0, 1]]),
                                                np.arange(2, 8).reshape(1, 3, 2), v2, 0.5,
                                                chi, next2)
        _, c, force3, _ = friction3d.friction(lam, f3, N3, T3, np.array([[0, 1, 2]]),
                                              np.arange(3, 12).reshape(1, 3, 3), v3, 0.5,
                                              chi, crawl.at)
        np.testing.assert_allclose(c[0], crawl.at[0], rtol=0)  # the slope's slip
        np.testing.assert_allclose(force3[0] @ T3[0].T, force2[0, 0] * turn, rtol=1e-13)
    assert crawl.drop() == (kind == "crawl") and not crawl.any


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("kind", ["crawl", "land", "reverse"])
def test_slip_guard_leaves_a_node_it_does_not_act_at(dim: int, kind: str) -> None:
    """Where the guard does not act (``acts`` False: the bulk holds the node's slip,
    :func:`coupling.guarded_nodes`) each of its three decisions (a crawl point, a landing,
    a reversal cut; the slips of :func:`test_slip_guard_is_the_2d_guard_turned`) is left
    out: Newton's step stands to the bit and the node takes no crawl point; where it acts
    the same step is cut or a crawl point set (so the case tests the switch)."""
    chi, dv = 1e-3, 0.5e-3
    a0, a1 = {"crawl": (200.0, 260.0), "land": (2.0, 3.0), "reverse": (5.0, -5.0)}[kind]
    c0, c1 = np.array([a0, 0.0][: dim - 1]) * chi, np.array([a1, 0.0][: dim - 1]) * chi
    kernel = guardkernels.slip_guard if dim == 2 else friction3d.slip_guard
    pos_s = np.arange(dim)[None, :]
    pos_m = np.arange(dim, 4 * dim).reshape(1, 3, dim)
    for acts in (False, True):
        v1, step, f, N0, t0 = _one_node(c0, c1, dv, dim)
        newton = step.copy()
        crawl = newtonaids.CrawlPoints(1, dim - 1, kernel)
        fixed = crawl.guard(step, v1, (f, N0, t0), pos_s, pos_m, dv, chi,
                            np.array([acts]))
        if not acts:
            assert fixed == 0 and not crawl.any
            np.testing.assert_array_equal(step, newton)
        else:
            assert (fixed == 1) != crawl.any  # a crawl point, or a cut
            assert crawl.any == (kind == "crawl")


def test_guard_acts_where_the_law_holds_the_slip_against_the_bulk() -> None:
    """:func:`coupling.guarded_nodes`: the guard acts at a node where μλβ₁Δt/χ ≥
    COUPLING t·S·t, S's block at the node's unknowns along its tangent(s) (the mean over
    a 3-D basis), computed here by a loop over the nodes; at every node where S is not
    known (None, an unknown outside the near set of :class:`coupling.BulkStiffness`'s
    ``index``, a DOF that is not an unknown)."""
    rng = np.random.default_rng(3)
    n = 12
    B = rng.normal(size=(n, n))
    S = B @ B.T + n * np.eye(n)  # symmetric positive definite, as X_II⁻¹
    stick = 2.0  # μ β₁Δt / χ
    for dim in (2, 3):
        nodes = n // dim
        pos = np.arange(nodes * dim).reshape(nodes, dim)
        pos[1, 0] = -1  # a held component: not an unknown
        T = rng.normal(size=(nodes, dim - 1, dim))
        T /= np.linalg.norm(T, axis=2)[:, :, None]
        tangents = T[:, 0] if dim == 2 else T
        stt = np.full(nodes, np.nan)
        for k in range(nodes):
            if (pos[k] >= 0).all():
                blk = S[np.ix_(pos[k], pos[k])]
                stt[k] = np.mean([t @ blk @ t for t in T[k]])
        bulk = coupling.BulkStiffness(S)
        np.testing.assert_allclose(bulk.tangential(pos, tangents), stt, rtol=1e-14)
        # λ on both sides of the threshold λ* = COUPLING S_tt / stick (×0.5, ×2).
        lam = np.where(np.arange(nodes) % 2 == 0, 0.5, 2.0) * (
            coupling.COUPLING * np.nan_to_num(stt, nan=1.0) / stick)
        acts = coupling.guarded_nodes(lam, stick, bulk, pos, tangents)
        expected = (np.arange(nodes) % 2 == 1) | np.isnan(stt)
        np.testing.assert_array_equal(acts, expected)
        assert coupling.guarded_nodes(lam, stick, None, pos, tangents).all()
        # S on a near set (the reach's Newton): the rows of the unknowns it holds.
        near = np.arange(0, n, 2)
        index = np.full(n, -1)
        index[near] = np.arange(len(near))
        sub = coupling.BulkStiffness(S[np.ix_(near, near)], index)
        inside = np.isin(pos, near).all(axis=1) & (pos >= 0).all(axis=1)
        got = sub.tangential(pos, tangents)
        np.testing.assert_array_equal(np.isnan(got), ~inside)
        np.testing.assert_allclose(got[inside], stt[inside], rtol=1e-14)


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
    # The 6-node triangle's vertex shape values are negative inside: those nodes' λ < 0
    # carry no friction, the others' are scaled so that they carry μΣλ (s < 1).
    lam, scale = newtonaids.friction_normals(lam, P.facet0)
    assert scale < 1
    k, c, force, _ = friction3d.friction(lam, P.facet0, P.N0, P.T0, P.node_pos, P.pos_m,
                                         P.v0, P.mu, P.chi, no_crawl(lam))
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


def _held_nodes(rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """Four slave nodes over two 6-node master faces sharing four nodes (one master node
    held): node 0 free, node 1 held along x, node 2 along z (both on face 0), node 3
    along x and z (on face 1); random shape values and tangent bases tilted out of the
    x-z plane. Returns pos_m, node_pos, facet0, N0, T0."""
    master = np.arange(12, 12 + 8 * 3).reshape(8, 3)
    master[7] = -1  # a held master node
    pos_m = np.ascontiguousarray(master[[[0, 1, 2, 3, 4, 5], [2, 3, 4, 5, 6, 7]]])
    node_pos = np.arange(12).reshape(4, 3)
    node_pos[1, 0] = node_pos[2, 2] = node_pos[3, 0] = node_pos[3, 2] = -1
    facet0 = np.array([0, 0, 0, 1])
    N0 = rng.uniform(0.1, 1.0, (4, 6))
    N0 /= N0.sum(axis=1)[:, None]
    T0 = np.empty((4, 2, 3))
    for j in range(4):
        t1 = np.array([np.cos(j), 0.1 * rng.normal(), np.sin(j)])
        t1 /= np.linalg.norm(t1)
        n = np.cross(t1, rng.normal(size=3))
        t2 = np.cross(n / np.linalg.norm(n), t1)
        T0[j] = t1, t2
    return pos_m, node_pos, facet0, N0, T0


def test_start_slip_on_held_components_moves_the_master() -> None:
    """:func:`newtonaids.slip_velocities_at`: velocities at the interface unknowns that
    give every slave node the asked slip, its held components included (issue 25).

    Four slave nodes over two 6-node master faces that share four nodes (one master node
    held): node 0 free, node 1 held along x, node 2 along z (both on face 0), node 3
    along x and z (on face 1); tangent bases tilted out of the x-z plane. The held
    components' slip is the master's, two conditions per component on 7 free master
    nodes: solvable exactly. The relative velocity v_k − Σ_b N̄₀_b v_b (v_k's held
    components 0) is the asked slip to 1e-13 of it, and the friction kernel's slip (the
    dynamics' law, :func:`friction3d.friction`) is its tangent components. Before, the
    held components were left out (the slave node's own velocity only): node 3 had none
    and the static state's friction on the master there was lost at t = 0."""
    rng = np.random.default_rng(3)
    pos_m, node_pos, facet0, N0, T0 = _held_nodes(rng)
    c = 1e-9 * rng.normal(size=(4, 2))
    rel = np.einsum("ka,kad->kd", c, T0)
    k = np.arange(4)
    pos, vel = newtonaids.slip_velocities_at(node_pos, pos_m, facet0, N0, k, rel, 36)
    assert np.all(pos >= 0) and len(np.unique(pos)) == len(pos)
    v1 = np.zeros(37)
    v1[pos] = vel
    got = v1[node_pos] - np.einsum("kb,kbd->kd", N0, v1[pos_m[facet0]])
    np.testing.assert_allclose(got, rel, rtol=0, atol=1e-13 * np.abs(rel).max())
    _, slip, _, _ = friction3d.friction(np.ones(4), facet0, N0, T0, node_pos, pos_m, v1,
                                        0.5, 1e-10, no_crawl(np.ones(4)))
    np.testing.assert_allclose(slip, c, rtol=0, atol=1e-13 * np.abs(c).max())


def test_node_past_the_master_edge_takes_the_nearest_vertex() -> None:
    """:func:`friction3d.frozen`: a slave node with no projection (past the master's
    edge) takes the nearest master vertex within the search radius, as the 2-D pair
    takes the nearest end, and carries the friction of its slip there.

    The master: the square [0, 1]² of the plane y = 0, two flat 6-node triangles. Node 0
    above the square (a projection), node 1 0.02 past its edge x = 1 near the corner
    (1, 0, 1), node 2 0.5 past it (beyond the radius 0.1). Before, node 1 had no master
    point and no friction (only the scale of ``friction_normals`` restored μN, in sum).
    With λ = 1 and the same slip velocity v (the master at rest), nodes 0 and 1 carry the
    same force, the law's −μ v/sqrt(|v|² + χ²) (to round-off: 1e-15 of μ)."""
    from types import SimpleNamespace

    corners = np.array([[[0.0, 0, 0], [1, 0, 0], [0, 0, 1]], [[1.0, 0, 0], [1, 0, 1], [0, 0, 1]]])
    mids = [(1, 2), (0, 2), (0, 1)]  # projection3d.NODES[6]'s mid-edge nodes
    mX = np.concatenate([corners, 0.5 * (corners[:, [a for a, _ in mids]]
                                         + corners[:, [b for _, b in mids]])], axis=1)
    pos_m = np.arange(36).reshape(2, 6, 3)  # every master node its own (resting) DOFs
    node_X = np.array([[0.3, 0.001, 0.3], [1.02, 0.001, 0.98], [1.5, 0.001, 0.5]])
    node_pos = np.arange(36, 45).reshape(3, 3)
    pair = SimpleNamespace(_mX=mX, _pm=pos_m, node_X=node_X, node_pos=node_pos, radius=0.1,
                           small_rotations=False)
    u0 = np.zeros(46)
    facet, N0, T0 = friction3d.frozen(pair, u0)  # type: ignore[arg-type]
    assert facet[0] >= 0 and facet[2] == -1
    assert facet[1] == 1  # the corner (1, 0, 1) is face 1's vertex 1
    np.testing.assert_array_equal(N0[1], np.eye(6)[1])
    np.testing.assert_allclose(np.abs(np.cross(T0[1, 0], T0[1, 1])), [0, 1, 0], atol=1e-15)
    mu, chi, v = 0.5, 1e-4, np.array([1e-3, 0.0, 0.0])
    v1 = np.zeros(46)
    v1[node_pos[:2]] = v
    k, _, force, _ = friction3d.friction(np.ones(3), facet, N0, T0, node_pos, pos_m, v1, mu,
                                         chi, no_crawl(np.ones(3)))
    np.testing.assert_array_equal(k, [0, 1])
    law = -mu * v / np.sqrt(v @ v + chi**2)
    np.testing.assert_allclose(force, [law, law], rtol=0, atol=1e-15 * mu)


def test_sliding_velocities_slip_along_the_tangential_direction() -> None:
    """:func:`newtonaids.sliding_velocities` (a held body's release): every slave node
    in contact slips at the asked speed along the tangential part of the sliding
    direction d at its master point, ``Σ_α (d·T₀_α) T₀_α`` normalised, its held
    components included (the master's share), as the friction kernel measures it.

    The four nodes and two master faces of the test above (nodes held along x, z, and
    both; tangent bases tilted out of the x-z plane, so that each node's tangential
    slip has components along its held directions); d along (1, 0, 0.3). The kernel's
    slip is the asked one to 1e-13 of it, and no velocity is set on a held component.
    Before, a release left out every node with a held component (here nodes 1–3)."""
    rng = np.random.default_rng(3)
    pos_m, node_pos, facet0, N0, T0 = _held_nodes(rng)
    d = np.array([1.0, 0.0, 0.3]) / np.hypot(1.0, 0.3)
    speed = 1e-8
    k = np.arange(4)
    pos, vel = newtonaids.sliding_velocities(node_pos, pos_m, facet0, N0, T0, k, d, speed, 36)
    assert np.all(pos >= 0) and len(np.unique(pos)) == len(pos)
    v1 = np.zeros(37)
    v1[pos] = vel
    c = np.einsum("kad,d->ka", T0, d)
    c *= speed / np.linalg.norm(c, axis=1)[:, None]
    _, slip, _, _ = friction3d.friction(np.ones(4), facet0, N0, T0, node_pos, pos_m, v1,
                                        0.5, 1e-10, no_crawl(np.ones(4)))
    np.testing.assert_allclose(slip, c, rtol=0, atol=1e-13 * speed)


# --- a block pushed diagonally ------------------------------------------------------------

RHO, PUSH, DT = 2400.0, 5.0, 0.01
MASS = RHO * 0.5 * 0.3 * 0.5
WEIGHT = MASS * 9.81
FORCE = PUSH * MASS * np.sqrt(2.0)  # the push's magnitude, along (1, 0, 1)/√2


def _started(model: ContactModel, comm: MPI.Comm, mass: float) -> tuple[Any, Any, Any]:
    """The model's initial state, a GN22 stepper (Δt = DT) started from it, and the
    block's (body 1, density RHO, mass ``mass``) mass-weighted mean of a vector field."""
    from breakwater.stepping.gn22 import GN22

    model.set_time(0.0)
    state = initial_state(model)
    s = GN22(model, DT)
    s.initialise(state.u, state.v)
    block = model.bodies[1].submesh

    def centre(f: fem.Function) -> np.ndarray:
        return np.array([comm.allreduce(fem.assemble_scalar(fem.form(
            RHO * f[k] * ufl.dx(domain=block))), op=MPI.SUM) for k in range(3)]) / mass

    return state, s, centre


def _block(folder: pathlib.Path, comm: MPI.Comm, mu: float, chi: float, steps: int
           ) -> dict[str, Any]:
    """test_pair3d's block on a slab (non-matching faces), with friction μ and χ, pushed
    along (1, 0, 1) from t > 0 with F = PUSH m per component, from its static state.

    The push is a uniform traction on the faces x = 0.1 (along x) and z = 0.1 (along z),
    whose lines of action pass through the block's vertical axis: no torque about y
    (test_pair3d's traction (p, 0, p) on the face x = 0.1 alone spins the block about y,
    the friction then turns from the push's direction).
    """
    from breakwater.stepping.interfacenewton import InterfaceNewton

    path = boxes(folder / "slide3d.msh", COMM,
                 [Box("slab", (0, 0, 0), (1.5, 0.3, 1.5), 0.3),
                  Box("block", (0.1, 0.3, 0.1), (0.5, 0.3, 0.5), 0.2)])
    material = Material(RHO, 0.2, young_modulus=1e9)
    p = PUSH * MASS / (0.3 * 0.5)

    def on(t: float) -> float:
        return 1.0 if t > 0 else 0.0

    model = ContactModel(
        read_mesh(path, comm), [Body("slab", material), Body("block", material)],
        fixed=[Fixed("slab_bottom")],
        loads=[SurfaceLoad("block_left", (p, 0.0, 0.0), on),
               SurfaceLoad("block_back", (0.0, 0.0, p), on)],
        surface_pairs=[SurfacePair("c", "block", "slab", "block_bottom", "slab_top", 1e11,
                                   friction=mu, regularisation=chi)],
        gravity=np.array([0.0, -9.81, 0.0]))
    _, s, centre = _started(model, comm, MASS)

    out: dict[str, list[Any]] = {"v": [], "x": [], "normal": [], "friction": [],
                                 "iterations": []}
    pair = s.surfaces[0]
    norms: list[list[float]] = []  # each step's Newton residuals (of each try)
    iterate = InterfaceNewton._iterate

    def recorded(self: InterfaceNewton, *args: Any, **kwargs: Any) -> Any:
        result = iterate(self, *args, **kwargs)
        norms.append(list(result[1]))
        return result

    for _ in range(steps):
        with mock.patch.object(InterfaceNewton, "_iterate", recorded):
            out["iterations"].append(s.step())
        out["v"].append(centre(s.v[1]))
        out["x"].append(centre(s.u[1]))
        normal, friction = pair.resultants()
        out["normal"].append(normal)
        out["friction"].append(friction)
    # The slave nodes' slip velocities at the end, weighted by their normal forces.
    u0, u1, v1 = pair._state(accepted=True)
    fr = pair._friction(u0, v1, pair.normal_forces(u1), accepted=True)
    slip = np.einsum("ka,kad->kd", fr["c"], fr["frozen"][2][fr["k"]])
    out["slip_velocity"] = list(fr["lam"][fr["k"]] @ slip)
    out["slip_speed"] = [float(np.linalg.norm(fr["c"], axis=1).max())]
    assert s.fast is not None
    newton = s.fast.newton
    counts = {"continuations": newton.continuations, "rescues": newton.rescues}
    s.destroy()
    result: dict[str, Any] = {k: np.array(v) for k, v in out.items()}
    result["norms"] = norms
    result.update(counts)
    return result


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    """The angle between vectors a and b (rad), accurate for small angles."""
    return float(np.arctan2(np.linalg.norm(np.cross(a, b)), np.dot(a, b)))


SLIDE_STEPS = 12


@pytest.fixture(scope="module")
def diagonal_slide(folder: pathlib.Path) -> dict[str, Any]:
    """The block pushed diagonally with μ = 0.3 at the paper's χ = 1e-10 m/s,
    SLIDE_STEPS steps on the ranks of the run: :func:`test_block_pushed_diagonally_slides`
    checks its physics, :func:`test_parallel_equals_serial` its first steps against runs
    on each rank alone (one run for both: the same steps)."""
    return _block(folder, COMM, 0.3, 1e-10, SLIDE_STEPS)


def test_block_pushed_diagonally_slides(diagonal_slide: dict[str, Any]) -> None:
    """F > μN: with μ = 0.3 and the paper's χ = 1e-10 m/s the block (m = 180 kg,
    N = mg = 1765.8 N) pushed with |F| = 1272.8 N along (1, 0, 1) slides along the push
    with a = (F − μN)/m = 4.128 m/s² (from the momentum between steps 4 and 12; asked to
    1 %, measured 1.3e-5: the penalty's settling and the push's tipping moment change N
    by 1e-4, its acceleration's direction (1e-3 rad) by its elastic vibration), the
    friction resultant is μN to 1e-6 (the slip is 1e9 χ, φ = 1 − 5e-19, but the slave
    nodes' slip directions spread with the block's elastic vibration: the resultant of
    μλ_k along each is shorter, measured 8.6e-8) and opposite the slave nodes' mean slip
    velocity Σ λ_k v_T,k to 1e-6 rad (measured 6.6e-9), and horizontal; the Newton
    converges quadratically."""
    mu, steps = 0.3, SLIDE_STEPS
    r = diagonal_slide
    a = (r["v"][-1] - r["v"][3]) / ((steps - 4) * DT)
    expected = (FORCE - mu * WEIGHT) / MASS
    push = np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0)
    if COMM.rank == 0:
        print(f"\nslide: a = {a} (expected {expected:.6g} along {push}), iterations "
              f"{r['iterations']}")
    friction, normal = r["friction"][-1], r["normal"][-1]
    ratio = np.linalg.norm(friction) / (mu * np.linalg.norm(normal))
    angle = _angle(-friction, r["slip_velocity"])
    if COMM.rank == 0:
        print(f"friction {friction}, normal {normal}: |F|/μ|N| − 1 = {ratio - 1:.3g}, "
              f"angle to the mean slip {angle:.3g} rad")
    assert np.linalg.norm(a) == pytest.approx(expected, rel=0.01)
    assert _angle(a, push) < 1e-3
    assert ratio == pytest.approx(1.0, rel=1e-6)
    assert angle < 1e-6
    # Newton converges quadratically: once a step's relative residual e = ‖F‖/‖F₀‖ is
    # below 0.1, the next is below 10 e² (down to 1e-9, the tolerances' round-off; the
    # scale s taken as a constant, the residual fell by 1e-2 per iteration).
    for n in r["norms"]:
        e = np.array(n) / n[0]
        for now, then in itertools.pairwise(e):
            if now < 0.1 and then > 1e-9:
                assert then < 10 * now**2, e
    assert abs(friction[1]) < 1e-6 * np.linalg.norm(friction)


def test_block_pushed_below_mu_n_creeps(folder: pathlib.Path) -> None:
    """F < μN: with μ = 1 (f = |F|/μN = 0.7208) the block sticks; the regularised law
    lets it creep. A rigid block creeping at the speed v along the push carries the
    friction Σ μλ_k φ(v) = μN v/sqrt(v² + χ²) at every slave node alike, which balances
    F where v = χ f/sqrt(1 − f²) (the law's inverse); it reaches it within
    m χ/(μN (1 − f²)^(3/2)) = 3e-4 s, a fraction of a step. With χ = 1e-3 m/s (a stick
    band large enough to measure: the paper's 1e-10 m/s creeps 1e-11 m here) v = 1.040
    mm/s: over T = 8 steps = 0.08 s the block's centre moves v T = 0.083 mm horizontally,
    to 5 % (measured 3.0 %: the first step's elastic response to the sudden push, an
    offset of 2.5e-6 m; over 12 steps it was 2.0 %), and its mean speed over the last 4
    steps is v to 2 % (measured 1.2 %: the block's elastic vibration under the sudden
    push modulates the base's slip; 0.3 % over the last 6 of 12 steps), along the push.

    The elastic block, not each node's law, holds the slip here (μλβ₁Δt/χ below 0.1 of
    the bulk's stiffness at the nodes, :mod:`breakwater.contact.coupling`): Newton's own
    steps converge, in at most 7 iterations a step (measured 42 in 8 steps; 110 while the
    slip guard acted at every node, linearising the law far along the saturated part at
    slips of 1.5χ and landing nodes at 64χ)."""
    mu, chi, steps = 1.0, 1e-3, 8
    r = _block(folder, COMM, mu, chi, steps)
    assert r["iterations"].sum() <= 7 * steps
    f = FORCE / (mu * WEIGHT)
    creep = chi * f / np.sqrt(1.0 - f * f)
    push = np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0)
    moved = r["x"][-1] * np.array([1.0, 0.0, 1.0])  # from the static state (at rest)
    mean = (r["x"][-1] - r["x"][steps // 2 - 1]) / ((steps - steps // 2) * DT)
    if COMM.rank == 0:
        print(f"\ncreep: moved {moved} (v T = {creep * steps * DT:.4g} along {push}), mean "
              f"speed {mean} (v = {creep:.4g}), iterations {r['iterations']}")
    assert f < 1
    assert np.linalg.norm(moved) == pytest.approx(creep * steps * DT, rel=0.05)
    assert np.linalg.norm(mean) == pytest.approx(creep, rel=0.02)
    assert _angle(mean, push) < 1e-2


def test_parallel_equals_serial(folder: pathlib.Path, diagonal_slide: dict[str, Any]
                                ) -> None:
    """The sliding block's first 4 steps on the ranks of the run (those of
    :func:`diagonal_slide`) and on each rank alone (COMM_SELF): the centre's velocity and
    displacement and the pair's resultants agree to 1e-9 of their scale (every rank
    evaluates the gathered pair in the same order; the partition changes the bulk's sums,
    and the Newton's iterates, by round-off: its tolerance 1e-9 bounds what is left of
    them). Serially the two runs are the same run."""
    steps = 4
    runs = [{key: diagonal_slide[key][:steps] for key in ("v", "x", "normal", "friction")}]
    if COMM.size > 1:
        runs.append(_block(folder, MPI.COMM_SELF, 0.3, 1e-10, steps))
    for key in ("v", "x", "normal", "friction"):
        a, b = runs[0][key], runs[-1][key]
        scale = np.abs(a).max()
        if COMM.rank == 0:
            print(f"\n{key}: largest difference {np.abs(a - b).max() / scale:.3g} of {scale:.4g}")
        assert np.abs(a - b).max() <= 1e-9 * scale, key


# --- a held block released between rollers ------------------------------------------------

ROLLER_MASS = RHO * 0.4 * 0.2 * 0.4
ROLLER_PUSH = 1.5 * 0.3 * ROLLER_MASS * 9.81  # F = 1.5 μN along x


def _rollers_block(folder: pathlib.Path, steps: int) -> dict[str, Any]:
    """A 0.4 × 0.2 × 0.4 m block on a 1 × 0.2 × 0.8 m slab (non-matching faces, μ = 0.3,
    the paper's χ = 1e-10 m/s), its side faces z = 0.2 and 0.6 on rollers (held along z),
    pushed along x with F = 1.5 μN by a traction on its face x = 0.1, from t = 0 on: no
    frictional static state, the block is held up to t = 0 and released
    (:mod:`breakwater.statics.release`).

    Returns:
        The block centre's acceleration at t = 0 (``a0``) and velocity at t = 0 and after
        each step (``v``), the pair's friction and normal resultants at t = 0 and after each step,
        the initial state's kind and held bodies.
    """
    path = boxes(folder / "rollers3d.msh", COMM,
                 [Box("slab", (0, 0, 0), (1.0, 0.2, 0.8), 0.3),
                  Box("block", (0.1, 0.2, 0.2), (0.4, 0.2, 0.4), 0.2)])
    material = Material(RHO, 0.2, young_modulus=1e9)
    model = ContactModel(
        read_mesh(path, COMM), [Body("slab", material), Body("block", material)],
        fixed=[Fixed("slab_bottom"), Fixed("block_back", (2,)), Fixed("block_front", (2,))],
        loads=[SurfaceLoad("block_left", (ROLLER_PUSH / (0.2 * 0.4), 0.0, 0.0),
                           lambda t: 1.0)],
        surface_pairs=[SurfacePair("c", "block", "slab", "block_bottom", "slab_top", 1e11,
                                   friction=0.3, regularisation=1e-10)],
        gravity=np.array([0.0, -9.81, 0.0]))
    state, s, centre = _started(model, COMM, ROLLER_MASS)

    pair = s.surfaces[0]
    out: dict[str, Any] = {"kind": state.kind, "held": state.held, "a0": centre(s.a[1])}
    normal, friction = pair.resultants()
    v, normals, frictions = [centre(s.v[1])], [normal], [friction]
    for _ in range(steps):
        s.step()
        v.append(centre(s.v[1]))
        normal, friction = pair.resultants()
        normals.append(normal)
        frictions.append(friction)
    s.destroy()
    out.update(v=np.array(v), normal=np.array(normals), friction=np.array(frictions))
    return out


def test_held_block_on_rollers_released_sliding(folder: pathlib.Path) -> None:
    """A block held up to t = 0 (F = 1.5 μN) whose slave nodes on its bottom edges are
    held along z by the rollers of its side faces: released, it slides along x with
    a = (F − μN)/m = ½ μ g = 1.4715 m/s² from t = 0 (Meriam & Kraige, *Engineering
    Mechanics: Dynamics*, §3/4, block on a rough plane), and the friction resultant is
    μN at t = 0 and after every step.

    The release starts every slave node in contact sliding at RELEASE χ along the
    sliding direction (:func:`breakwater.statics.release.release`), its held components
    included, where the law carries μλ(1 − 5e-5). Before, a node with a held component
    got no release velocity: at t = 0 the edge nodes carried no friction, the friction
    resultant was 0.839 μN and a₀ 1.945 m/s² (+32 %), the first step's acceleration
    +13 %. And the sliding direction d is the held friction's less its component along
    z, which the rollers hold (:func:`~breakwater.statics.release.held_bodies`): with
    it (−1.59 N along z against 339 N, the mesh not symmetric about z) the state of
    incipient sliding stalled, the block was released from the held state with its
    bonded shear, +8.0 % and +5.4 % on its acceleration at the second and third steps,
    and a₀ had 0.057 m/s² along z.

    Asked, as test_block_pushed_diagonally_slides: the acceleration at t = 0 (GN22's a₀,
    the block's mass-weighted mean) and over each of the first 4 steps (from the
    centre's momentum) to 1 %, which an edge left out exceeds (their share of the
    friction is 16 % of μN on this mesh); the block starts in the motion of sliding,
    so that only its elastic response to the release speed's friction and the
    penalty's settling are left (measured 1.0e-4 at t = 0, below 4.1e-5 over the
    steps). The friction resultant μN to 1e-4: the law at the release speed 100 χ
    carries μ(1 − 5e-5) at t = 0 (measured 0.99995), μ once the block slides at 1e8 χ
    (measured 1 + 1.5e-12). Along z (held), a₀ and the friction nil to 1e-3 of their
    x components (measured 1e-11). The mesh (block 0.2 m, slab 0.3 m) is one whose held
    friction has a component along z; at 0.3 and 0.5 m it is 25 % faster, but that
    component too small to stall the incipient sliding. 17 s alone on this machine."""
    mu, steps = 0.3, 4
    r = _rollers_block(folder, steps)
    expected = (ROLLER_PUSH - mu * ROLLER_MASS * 9.81) / ROLLER_MASS
    a = np.diff(r["v"], axis=0) / DT
    ratio = [float(np.linalg.norm(f) / (mu * np.linalg.norm(n)))
             for f, n in zip(r["friction"], r["normal"], strict=True)]
    if COMM.rank == 0:
        print(f"\nrollers: a0 = {r['a0']} (expected {expected:.6g} along x), step "
              f"accelerations {a[:, 0]}, friction at t = 0 {r['friction'][0]}, normal "
              f"{r['normal'][0]}, |F|/μ|N| {ratio}")
    assert r["kind"] == "held" and r["held"] == ["block"]
    assert r["a0"][0] == pytest.approx(expected, rel=0.01)
    for step in a:
        assert step[0] == pytest.approx(expected, rel=0.01)
    assert ratio == pytest.approx([1.0] * len(ratio), rel=1e-4)
    assert abs(r["a0"][2]) < 1e-3 * expected
    assert abs(r["friction"][0][2]) < 1e-3 * np.linalg.norm(r["friction"][0])
