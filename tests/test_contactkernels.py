"""The compiled kernels of the general pairs against their NumPy references (issue 22).

:mod:`breakwater.contact.searchkernels` against :mod:`breakwater.contact.projection` and
the NumPy integration of :class:`~breakwater.contact.surfacesearch.SurfaceSearch`;
:mod:`breakwater.contact.forcekernels` against :mod:`breakwater.contact.pointkernels` and
the NumPy friction, Jacobian assembly and slip guard the pair used before the kernels
(restated below). Random curved (P2) and straight (P1) surfaces, a slave pressed into
a master and sliding on it, some DOFs Dirichlet. The search's decisions must be the
same, the numbers equal to round-off (1e-12 relative; the residual bit for bit).
Pure array tests: under ``mpiexec -n 2`` every rank runs them.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import breakwater  # noqa: F401  (imports dolfinx_solver before dolfinx)

# isort: split
from breakwater import forms  # type: ignore[attr-defined]
from breakwater.contact import forcekernels, guardkernels, searchkernels
from breakwater.contact.pointkernels import (
    DenseEntries,
    H,
    jacobian,
    nodal_normal_forces,
    normal_and_shares,
    normal_forces,
    unit_tangent,
)
from breakwater.contact.projection import FacetGrid, closest_point, nearest_end, project, shape
from breakwater.contact.slipguard import land
from breakwater.contact.surfacesearch import SurfaceSearch

RTOL = 1e-12


def _surface(rng: np.random.Generator, x: np.ndarray, y: float, nn: int, bend: float,
             reverse: bool) -> np.ndarray:
    """Facets ``(F, nn, 2)`` between consecutive x at height y, mid-nodes bent."""
    ends = np.stack([x, y + 1e-3 * rng.normal(size=len(x))], axis=1)
    a, b = ends[:-1], ends[1:]
    if reverse:
        a, b = b, a
    if nn == 2:
        return np.stack([a, b], axis=1)
    mid = 0.5 * (a + b) + np.array([0.0, bend]) * rng.uniform(-1, 1, size=(len(a), 1))
    return np.stack([a, b, mid], axis=1)


ANY = (np.zeros((0, 2)), np.zeros(0))  # frozen: a projection onto any master facet


def _facing(p: SimpleNamespace) -> tuple[np.ndarray, np.ndarray]:
    """The slave facets' orientation (x increasing: (t_y, −t_x) points down, out of it)
    and the master facets' depths the search sees (beyond every point's)."""
    return np.ones(len(p.sX)), np.full(len(p.mX), np.inf)


def _pair(seed: int, nn: int):  # type: ignore[no-untyped-def]
    """A slave surface above a master (oriented: (t_y, −t_x) up), shared nodes numbered,
    interface positions (some −1), a state pressing and sliding the slave."""
    rng = np.random.default_rng(seed)
    sX = _surface(rng, np.sort(rng.uniform(-0.4, 0.4, 7)), 0.0, nn, 0.01, False)
    mX = _surface(rng, np.sort(rng.uniform(-0.5, 0.5, 11)), 0.0, nn, 0.01, True)

    def numbered(X: np.ndarray, start: int) -> np.ndarray:
        _, ids = np.unique(np.round(X.reshape(-1, 2), 12), axis=0, return_inverse=True)
        ids = ids.reshape(X.shape[:2])
        return start + np.stack([2 * ids, 2 * ids + 1], axis=2)

    dofs_s = numbered(sX, 0)
    dofs_m = numbered(mX, int(dofs_s.max()) + 1)
    n = int(dofs_m.max()) + 1
    dirichlet = rng.choice(n, 4, replace=False)
    keep = np.setdiff1d(np.arange(n), dirichlet)
    position = np.full(n, -1)
    position[keep] = np.arange(len(keep))
    pos_s, pos_m = position[dofs_s], position[dofs_m]
    n = len(keep)
    u1 = np.append(1e-4 * rng.normal(size=n), 0.0)
    u1[pos_s[..., 1][pos_s[..., 1] >= 0]] -= 2e-3  # pressed in
    v1 = np.append(rng.normal(size=n) * 0.05, 0.0)
    v1[pos_s[..., 0][pos_s[..., 0] >= 0]] += 0.1  # sliding
    _, first, node_of = np.unique(dofs_s[..., 0], return_index=True, return_inverse=True)
    node_of = node_of.reshape(dofs_s.shape[:2])
    node_pos = pos_s.reshape(-1, 2)[first]
    node_X = sX.reshape(-1, 2)[first]
    return SimpleNamespace(sX=sX, mX=mX, pos_s=pos_s, pos_m=pos_m, n=n, u1=u1, v1=v1,
                           node_of=node_of, node_pos=node_pos, node_X=node_X, rng=rng)


@pytest.mark.parametrize("nn", [2, 3])
def test_candidates_and_projection(nn: int) -> None:
    """The grid's candidates (same pairs, same order), the lockstep Newton, the
    projection (same facets) and the nearest ends against projection.py."""
    p = _pair(1, nn)
    xm = p.mX + p.u1[p.pos_m]
    rng = np.random.default_rng(5)
    points = np.stack([rng.uniform(-0.6, 0.6, 400), rng.uniform(-0.05, 0.05, 400)], axis=1)
    for radius in (0.02, 0.1):
        grid = FacetGrid(xm, radius)
        ref = grid.candidates(points)
        got = searchkernels.candidates(points, xm, radius)
        for a, b in zip(ref, got, strict=True):
            np.testing.assert_array_equal(a, b)
        for tol in (1e-9, 1e-3):
            f_ref, xi_ref = project(points, xm, grid, tol=tol)
            f, xi = searchkernels.project(points, xm, radius, tol)
            np.testing.assert_array_equal(f, f_ref)
            np.testing.assert_allclose(xi, xi_ref, rtol=0, atol=1e-13)
            assert (f >= 0).sum() > 100
        f_ref, xi_ref = nearest_end(points, xm, grid)
        f, xi = searchkernels.nearest_end(points, xm, radius)
        np.testing.assert_array_equal(f, f_ref)
        np.testing.assert_array_equal(xi, xi_ref)
    point, cand = ref
    start = searchkernels.chord_start(points, point, xm, cand)
    for iterations, tol in ((8, 1e-14), (2, 0.0)):
        xi = start.copy()
        searchkernels.closest_points(points, point, xm, cand, xi, iterations, tol)
        expected = closest_point(points[point], xm[cand], iterations=iterations, tol=tol)
        np.testing.assert_allclose(xi, expected, rtol=0, atol=1e-13)
    np.testing.assert_allclose(searchkernels.shape_values(start, nn), shape(start, nn)[0],
                               rtol=0, atol=1e-15)


@pytest.mark.parametrize("nn", [2, 3])
@pytest.mark.parametrize("small", [False, True])
def test_start_of_step_projection(nn: int, small: bool) -> None:
    """searchkernels.frozen against SurfaceSearch._frozen's NumPy arithmetic (some nodes
    beyond the master's end take its nearest end)."""
    p = _pair(2, nn)
    xm = p.mX + p.u1[p.pos_m]
    points = p.node_X + p.u1[p.node_pos] + np.array([0.0, 0.004])
    points[0, 0] = xm[..., 0].max() + 0.01  # beyond the end: the nearest end
    radius = 0.1
    grid = FacetGrid(xm, radius)
    facet, xi = project(points, xm, grid)
    projected = facet >= 0
    beyond = np.flatnonzero(~projected)
    assert len(beyond)
    facet[beyond], xi[beyond] = nearest_end(points[beyond], xm, grid)
    N0, dN0, _ = shape(xi, nn)
    surface = p.mX if small else xm
    t0 = unit_tangent(dN0, surface[np.maximum(facet, 0)])
    got = searchkernels.frozen(points, xm, surface, radius, *ANY)
    np.testing.assert_array_equal(got[0], facet)
    np.testing.assert_array_equal(got[3], projected)
    np.testing.assert_allclose(got[1], N0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(got[2], t0, rtol=0, atol=1e-14)


def _points(p: SimpleNamespace, integration: str, edge: float) -> dict[str, np.ndarray]:
    """The integration points and projections of the NumPy references."""
    xs_all = p.sX + p.u1[p.pos_s]
    xm_all = p.mX + p.u1[p.pos_m]
    this = SimpleNamespace(slave=SimpleNamespace(X=p.sX), radius=0.1,
                           spec=SimpleNamespace(integration=integration),
                           _gauss=np.polynomial.legendre.leggauss(2))
    point_facet, xi_s, weight = SurfaceSearch._integration(this, xs_all, xm_all)  # type: ignore[arg-type]
    Ns = shape(xi_s, p.sX.shape[1])[0]
    points = np.einsum("kn,knd->kd", Ns, xs_all[point_facet])
    facet, xi = project(points, xm_all, FacetGrid(xm_all, 0.1), tol=edge)
    on = facet >= 0
    return {"point_facet": point_facet, "xi_s": xi_s, "weight": weight, "Ns": Ns,
            "points": points, "on": on, "f_s": point_facet[on], "f_m": facet[on],
            "xi": xi[on], "w": weight[on], "Ns_on": Ns[on], "xs": xs_all[point_facet[on]],
            "xm": xm_all[facet[on]]}


@pytest.mark.parametrize("nn", [2, 3])
def test_segment_points(nn: int) -> None:
    """The segments' cuts, Gauss points and weights and the points' projections."""
    p = _pair(3, nn)
    ref = _points(p, "segments", 1e-9)
    xs_all = p.sX + p.u1[p.pos_s]
    xm_all = p.mX + p.u1[p.pos_m]
    g, w = np.polynomial.legendre.leggauss(2)
    point_facet, xi_s, weight = searchkernels.segment_points(xs_all, xm_all, p.sX, 0.1, g, w)
    assert len(point_facet) > 2 * len(p.sX)  # cut: more than one segment per facet
    np.testing.assert_array_equal(point_facet, ref["point_facet"])
    np.testing.assert_allclose(xi_s, ref["xi_s"], rtol=0, atol=1e-15)
    np.testing.assert_allclose(weight, ref["weight"], rtol=RTOL, atol=0)
    Ns = searchkernels.shape_values(xi_s, nn)
    points = searchkernels.slave_points(xs_all, point_facet, Ns)
    np.testing.assert_allclose(points, ref["points"], rtol=0, atol=1e-15)
    facet, xi = searchkernels.project(points, xm_all, 0.1, 1e-9)
    np.testing.assert_array_equal(facet >= 0, ref["on"])
    np.testing.assert_allclose(xi[facet >= 0], ref["xi"], rtol=0, atol=1e-13)
    # The whole search (segments, and the fixed points of nodes).
    empty = (np.zeros(0, np.int64), np.zeros(0), np.zeros(0), np.zeros((0, nn)))
    every = np.ones(len(p.mX), bool)
    got = searchkernels.search(p.sX, p.mX, p.pos_s, p.pos_m, p.u1, True, *empty, 0.1, 1e-9,
                               g, w, every, *_facing(p))
    nodes = _points(p, "nodes", 1e-3)
    fixed = (nodes["point_facet"], nodes["xi_s"], nodes["weight"], nodes["Ns"])
    got_nodes = searchkernels.search(p.sX, p.mX, p.pos_s, p.pos_m, p.u1, False, *fixed, 0.1,
                                     1e-3, g, w, every, *_facing(p))
    assert got[-1] and got_nodes[-1]  # every facet in use: "restricted" to all
    got, got_nodes = got[:-1], got_nodes[:-1]
    for r, out in ((ref, got), (nodes, got_nodes)):
        expected = (r["point_facet"], r["points"], r["weight"], np.flatnonzero(r["on"]),
                    r["f_s"], r["f_m"], r["Ns_on"], r["xi"], r["w"])
        for a, b in zip(out, expected, strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-14, atol=1e-15)


def _law(friction: float = 0.5) -> forms.ContactLaw:
    return forms.ContactLaw(forms.PenaltyContact(1e10, 0.0),
                            forms.RegularisedCoulomb(friction, 1e-3))


def _reference_friction(law, lam, facet, N0, t0, node_pos, pos_m, v1):  # type: ignore[no-untyped-def]
    """SurfaceForces._friction before the kernels."""
    k = np.flatnonzero((facet >= 0) & (lam > 0))
    pm = pos_m[facet[k]]
    slip = v1[node_pos[k]] - np.einsum("kn,knd->kd", N0[k], v1[pm])
    t = t0[k]
    v_T = t * np.sum(slip * t, axis=1)[:, None]
    return {"k": k, "pos_s": node_pos[k], "pos_m": pm, "N0": N0[k], "t": t, "v_T": v_T,
            "force": law.friction.traction(lam[k], v_T),
            "unit": law.friction.traction(np.ones(len(k)), v_T)}


def _scatter(out: np.ndarray, pos: np.ndarray, values: np.ndarray) -> np.ndarray:
    pos, values = pos.ravel(), values.ravel()
    keep = pos >= 0
    out += np.bincount(pos[keep], weights=values[keep], minlength=len(out))
    return out


def _reference_matrix(law, r, pos, node, n_nodes, lam, fr, cu, cv, n, small):  # type: ignore[no-untyped-def]
    """SurfaceForces.matrix before the kernels (NumPy, complex steps)."""
    groups = [(r["xs"], np.zeros_like(r["xs"])), (r["xm"], np.zeros_like(r["xm"]))]
    both = jacobian(_kernel(normal_and_shares, law, r, small), groups, cu, cv)
    size = pos.shape[1] * pos.shape[2]
    J, Jl = both[:, :size], both[:, size:]
    rows = pos.reshape(len(J), -1)
    out = DenseEntries(n)
    out.block(rows, rows, J)
    cols = np.broadcast_to(rows[:, None, :], Jl.shape)
    nodes = np.broadcast_to(node[:, :, None], Jl.shape)
    keep = cols >= 0
    dlam = np.bincount((nodes * n + cols)[keep], weights=Jl[keep],
                       minlength=n_nodes * n).reshape(-1, n)
    k, t, N0 = fr["k"], fr["t"], fr["N0"]
    D = np.zeros((len(k), 2, 2))
    for c in range(2):
        v = fr["v_T"].astype(complex)
        v[:, c] += 1j * H
        D[:, :, c] = law.friction.traction(lam[k], v).imag / H
    B = cv * np.einsum("kij,kj,kl->kil", D, t, t)
    row_pos = np.concatenate([fr["pos_s"][:, None, :], fr["pos_m"]], axis=1)
    sign = np.concatenate([-np.ones((len(k), 1)), N0], axis=1)
    dforce_lam = fr["unit"][:, :, None] * dlam[k][:, None, :]
    for a in range(row_pos.shape[1]):
        vals = sign[:, a, None, None] * dforce_lam
        rr = np.broadcast_to(row_pos[:, a, :, None], vals.shape)
        cc = np.broadcast_to(np.arange(n)[None, None, :], vals.shape)
        ok = rr >= 0
        out.add((rr * n + cc)[ok], vals[ok])
    col_sign = np.concatenate([np.ones((len(k), 1)), -N0], axis=1)
    for a in range(row_pos.shape[1]):
        for c in range(row_pos.shape[1]):
            out.block(row_pos[:, a, :], row_pos[:, c, :],
                      (sign[:, a] * col_sign[:, c])[:, None, None] * B)
    return out.matrix()


def _kernel(function, law, r, small):  # type: ignore[no-untyped-def]
    from functools import partial
    return partial(function, law, r["Ns_on"], r["xi"], r["w"],
                   reference=r["mX_on"] if small else None)


@pytest.mark.parametrize("nn", [2, 3])
@pytest.mark.parametrize("integration", ["segments", "nodes"])
@pytest.mark.parametrize("small", [False, True])
def test_forces_friction_jacobian_guard(nn: int, integration: str, small: bool) -> None:
    """f_c's normal part and λ (bit for bit), the friction forces, ∂f_c/∂Δa (normal and
    friction parts), X ∂f_c/∂Δa and the slip guard against the NumPy references."""
    p = _pair(4, nn)
    law = _law()
    r = _points(p, integration, 1e-3 if integration == "nodes" else 1e-9)
    r["mX_on"] = p.mX[r["f_m"]]
    assert len(r["f_s"]) > 10
    groups = [(r["xs"], np.zeros_like(r["xs"])), (r["xm"], np.zeros_like(r["xm"]))]
    pos = np.concatenate([p.pos_s[r["f_s"]], p.pos_m[r["f_m"]]], axis=1)
    node = p.node_of[r["f_s"]]
    n_nodes = len(p.node_pos)
    forces = _kernel(normal_forces, law, r, small)(groups)
    expected = _scatter(np.zeros(p.n), pos, forces)
    shares = _kernel(nodal_normal_forces, law, r, small)(groups)
    lam_ref = np.bincount(node.ravel(), weights=shares.ravel(), minlength=n_nodes)
    out, lam, f_got, gap, _ = forcekernels.residual(
        p.sX, p.mX, p.pos_s, p.pos_m, p.u1, r["f_s"], r["f_m"], r["Ns_on"], r["xi"], r["w"],
        small, 1e10, 0.0, p.node_of, n_nodes)
    assert (gap < 0).sum() > 5 and np.abs(out).max() > 0
    np.testing.assert_array_equal(out, expected)
    np.testing.assert_array_equal(lam, lam_ref)
    np.testing.assert_array_equal(f_got, forces)
    # Friction at the slave nodes' start-of-step projection.
    xm0 = p.mX + p.u1[p.pos_m]
    facet, N0, t0, _ = searchkernels.frozen(p.node_X + p.u1[p.node_pos], xm0,
                                            p.mX if small else xm0, 0.1, *ANY)
    fr = _reference_friction(law, lam, facet, N0, t0, p.node_pos, p.pos_m, p.v1)
    assert len(fr["k"]) > 3
    none = np.full(len(p.node_pos), np.nan)  # no linearisation slips: the law itself
    k, v_T, force, unit = forcekernels.friction(lam, facet, N0, t0, p.node_pos, p.pos_m, p.v1,
                                                0.5, 1e-3, none)
    np.testing.assert_array_equal(k, fr["k"])
    for a, b in ((v_T, fr["v_T"]), (force, fr["force"]), (unit, fr["unit"])):
        np.testing.assert_array_equal(a, b)
    # With linearisation slips h at every other node (the guard's crawl points): there
    # the force is the law's tangent line at h, −μλ (φ(h) + φ'(h)(c − h)) t₀.
    lin = none.copy()
    lin[k[::2]] = np.linspace(-5e-3, 5e-3, len(k[::2]))
    _, v_T_lin, force_lin, unit_lin = forcekernels.friction(lam, facet, N0, t0, p.node_pos,
                                                            p.pos_m, p.v1, 0.5, 1e-3, lin)
    h, c = lin[k], np.einsum("kd,kd->k", fr["v_T"], t0[k])
    ρ = np.sqrt(h**2 + 1e-6)
    line = np.where(np.isnan(h), np.nan, h / ρ + 1e-6 / ρ**3 * (c - h))[:, None] * t0[k]
    expected_lin = np.where(np.isnan(h)[:, None], fr["force"], -0.5 * lam[k][:, None] * line)
    np.testing.assert_allclose(force_lin, expected_lin, rtol=1e-14, atol=1e-14 * abs(force).max())
    np.testing.assert_allclose(unit_lin, expected_lin / lam[k][:, None], rtol=1e-14,
                               atol=1e-14 * abs(unit).max())
    # v_T: the slip where the law's slope is taken, h t₀ at a crawl point (jacobian's ∂φ).
    np.testing.assert_array_equal(
        v_T_lin, np.where(np.isnan(h)[:, None], fr["v_T"], t0[k] * h[:, None]))
    total = expected.copy()
    _scatter(total, fr["pos_s"], -fr["force"])
    _scatter(total, fr["pos_m"], fr["N0"][:, :, None] * fr["force"][:, None, :])
    forcekernels.add_friction(out, k, force, facet, N0, p.node_pos, p.pos_m)
    np.testing.assert_array_equal(out, total)
    # The Jacobian.
    cu, cv = 0.5 * 0.605 * 1e-6, 0.5 * 1e-3
    A_ref = _reference_matrix(law, r, pos, node, n_nodes, lam, fr, cu, cv, p.n, small)
    act, A_act = forcekernels.jacobian(p.sX, p.mX, p.pos_s, p.pos_m, p.u1, r["f_s"], r["f_m"],
                              r["Ns_on"], r["xi"], r["w"], gap, small, 1e10, 0.0, p.node_of,
                              n_nodes, cu, cv, True, lam, k, v_T, unit, facet, N0, t0,
                              p.node_pos, 0.5, 1e-3)
    A = np.zeros((p.n, p.n))
    A[np.ix_(act, act)] = A_act
    scale = np.abs(A_ref).max()
    assert scale > 0 and len(act) < p.n
    np.testing.assert_allclose(A, A_ref, rtol=0, atol=RTOL * scale)
    # Zero outside act: the left product X[:, act] A[act, act] is X A.
    X = np.random.default_rng(6).normal(size=(p.n + 3, p.n))
    np.testing.assert_allclose(forcekernels.left_product(X, act, A_act), X @ A, rtol=0,
                               atol=RTOL * np.abs(X).max() * scale * p.n)
    # The slip guard (SurfaceForces.precheck before the kernels).
    dv, chi = 0.5e-3, 1e-3
    keep = np.flatnonzero((facet >= 0) & np.all(p.node_pos >= 0, axis=1))
    ps, N, t_all = p.node_pos[keep], N0[keep], t0[keep]
    pm = p.pos_m[facet[keep]]
    v_m = np.einsum("kn,knd->kd", N, p.v1[pm])
    c0 = np.sum((p.v1[ps] - v_m) * t_all, axis=1)
    # Large steps reverse slips (landed at zero); small ones land on the law's curve
    # (the NumPy reference slipguard.land).
    for scale, kind in ((1e3, "reverse"), (3e-3, "on_curve")):
        step = np.random.default_rng(7).normal(size=p.n) * scale
        ext = np.append(step, 0.0)
        y_m = np.einsum("kn,knd->kd", N, ext[pm])
        y_s = ext[ps]
        c1 = c0 - dv * np.sum((y_s - y_m) * t_all, axis=1)
        reverse = (c0 * c1 < 0) & (np.abs(c0) > chi)
        landed, on_curve = land(c0[:, None], c1[:, None], chi)
        on_curve &= ~reverse & (landed[:, 0] != c1)
        fix = reverse | on_curve
        assert {"reverse": reverse, "on_curve": on_curve}[kind].sum() > 0
        target = np.where(on_curve, landed[:, 0], 0.0)
        expected_step = step.copy()
        t, ys = t_all[fix], y_s[fix]
        along = (np.sum(y_m[fix] * t, axis=1) + (c0[fix] - target[fix]) / dv)[:, None]
        expected_step[ps[fix]] = ys - t * np.sum(ys * t, axis=1)[:, None] + t * along
        # A slip that grows by more than CRAWL times beyond the curved zone is not moved:
        # its next linearisation slip is where the law gives the linear model's force f,
        # at most GROW |c₁| (crawl_point).
        ρ = np.sqrt(c0**2 + chi**2)
        f = c0 / ρ + (c1 - c0) * (1 - (c0 / ρ) ** 2) / ρ
        crawl = ~reverse & ~(f**2 < guardkernels.F_MAX**2) & (c0 * c1 > 0) & (
            np.abs(c1) > guardkernels.CRAWL * np.abs(c0))
        with np.errstate(divide="ignore"):  # |f| ≥ 1: infinitely far
            far = chi * np.abs(f) / np.sqrt(np.maximum(1 - f**2, 0.0))
        point = np.sign(c1) * np.minimum(far, guardkernels.GROW * np.abs(c1))
        lin_next = np.full(len(p.node_pos), np.nan)
        lin_next[keep[crawl]] = point[crawl]
        got = none.copy()
        bounds = np.full(len(p.node_pos), guardkernels.FREE, np.int8)
        acts = np.ones(len(p.node_pos), bool)
        original = step.copy()
        assert guardkernels.slip_guard(step, p.v1, facet, N0, t0, p.node_pos, p.pos_m, dv,
                                       chi, none, got, bounds, acts) == fix.sum()
        np.testing.assert_allclose(step, expected_step, rtol=0,
                                   atol=1e-12 * np.abs(step).max())
        np.testing.assert_allclose(got, lin_next, rtol=1e-12)
        assert crawl.sum() > 0 if kind == "reverse" else True
        # A reversing node is REVERSED for the rest of the solve: its crawl points are at
        # most REGROW |c₁|; with every node NONE (a rescue), none takes one.
        np.testing.assert_array_equal(np.flatnonzero(bounds == guardkernels.REVERSED),
                                      np.sort(keep[reverse]))
        assert np.all(bounds[bounds != guardkernels.REVERSED] == guardkernels.FREE)
        for state, grow in ((guardkernels.REVERSED, guardkernels.REGROW),
                            (guardkernels.NONE, None)):
            step, got = original.copy(), none.copy()
            guardkernels.slip_guard(step, p.v1, facet, N0, t0, p.node_pos, p.pos_m, dv, chi,
                                    none, got, np.full(len(p.node_pos), state, np.int8), acts)
            if grow is None:
                assert np.isnan(got).all()
            else:
                bounded = np.sign(c1) * np.minimum(far, grow * np.abs(c1))
                expected = np.full(len(p.node_pos), np.nan)
                expected[keep[crawl]] = bounded[crawl]
                np.testing.assert_allclose(got, expected, rtol=1e-12)


@pytest.mark.parametrize("nn", [2, 3])
def test_candidates_dropped_before_the_projection_could_not_be_accepted(nn: int) -> None:
    """``near`` drops only (point, facet) pairs that the projection rejects anyway.

    Strongly bent facets (the middle node off the chord by 40 % of the facet and along
    it by up to 45 %: the curve leaves its nodes' box) and points around them; every
    pair of the grid is projected without the filter (closest_point, the acceptance of
    ``project``) and each accepted pair must survive ``near``, in the kernel and in the
    NumPy reference alike. The nodes' box widened by the radius alone would drop some.
    """
    rng = np.random.default_rng(11)
    F = 30
    a = np.stack([np.linspace(-0.3, 0.3, F + 1)[:-1], np.zeros(F)], axis=1)
    b = np.stack([np.linspace(-0.3, 0.3, F + 1)[1:], np.zeros(F)], axis=1)
    nodes = np.stack([a, b], axis=1)
    if nn == 3:
        mid = 0.5 * (a + b) + 0.02 * np.stack([rng.uniform(-0.45, 0.45, F),
                                                0.4 * rng.choice([-1, 1], F)], axis=1)
        nodes = np.concatenate([nodes, mid[:, None]], axis=1)
    from breakwater.contact.projection import curve, near

    # Points about the curves (within 2 mm), a radius below the curves' overshoot.
    on, s = rng.integers(0, F, 2000), rng.uniform(-1.0, 1.0, 2000)
    points = curve(nodes[on], s)[0] + rng.normal(0.0, 0.001, (2000, 2))
    radius, tol = 0.002, 1e-3
    point, cand = FacetGrid(nodes, radius).candidates(points)
    xi = np.real(closest_point(points[point], nodes[cand], iterations=8))
    x, dx, _ = curve(nodes[cand], xi)
    r = x - points[point]
    accepted = ((np.abs(xi) <= 1 + tol) & (np.sum(r * r, axis=1) <= radius**2)
                & (np.abs(np.sum(r * dx, axis=1)) <= 1e-10 * np.sum(dx * dx, axis=1)))
    kept = {tuple(pair) for pair in zip(*near(points, point, cand, nodes, radius, tol),
                                        strict=True)}
    compiled = searchkernels.near(points, point, nodes, cand, radius, tol)
    assert kept == {tuple(pair) for pair in zip(*compiled, strict=True)}
    assert accepted.sum() > 100 and len(kept) < 0.8 * len(point)  # it does drop pairs
    assert {(p, f) for p, f, ok in zip(point, cand, accepted, strict=True) if ok} <= kept
    if nn == 3:  # the curve's overshoot matters: the nodes' box alone is not enough
        box = nodes[cand]
        inside = np.all((points[point] >= box.min(axis=1) - radius)
                        & (points[point] <= box.max(axis=1) + radius), axis=1)
        assert np.any(accepted & ~inside)


def test_active_system_is_the_dense_product() -> None:
    """``active_system(B, X_act, act)`` is ``1 + B X_act[act]`` (B sparse, to round-off)."""
    from breakwater.stepping.interfacenewton import active_system

    rng = np.random.default_rng(3)
    n, act = 50, np.sort(rng.choice(50, 30, replace=False))
    B = rng.standard_normal((30, 30)) * (rng.uniform(size=(30, 30)) < 0.1) * 1e10
    X_act = np.ascontiguousarray(rng.standard_normal((n, 30)) * 1e-9)
    expected = B @ X_act[act] + np.eye(30)
    np.testing.assert_allclose(active_system(B, X_act, act), expected, rtol=1e-13,
                               atol=1e-13 * np.abs(expected).max())


def test_primal_system_is_the_dense_product() -> None:
    """``primal_system(B, transposed_rows(X_act, act))`` is ``(1 + X_act[act] B)ᵀ``, each
    entry the sum of the column-wise loop it replaced (k ascending): equal to the bit
    to the entries summed in that order; to round-off to NumPy's product."""
    from breakwater.stepping.interfacenewton import primal_system, transposed_rows

    rng = np.random.default_rng(5)
    n, m = 150, 130  # more than one 64-wide tile of transposed_rows, a partial last one
    act = np.sort(rng.choice(n, m, replace=False))
    B = rng.standard_normal((m, m)) * (rng.uniform(size=(m, m)) < 0.05) * 1e10
    X_act = np.ascontiguousarray(rng.standard_normal((n, m)) * 1e-9)
    X_aa_t = transposed_rows(X_act, act)
    np.testing.assert_array_equal(X_aa_t, X_act[act].T)
    J = primal_system(B, X_aa_t).T
    ordered = np.zeros((m, m))
    for k in range(m):
        for j in np.flatnonzero(B[k]):
            ordered[:, j] += X_act[act, k] * B[k, j]
    ordered += np.eye(m)
    np.testing.assert_array_equal(J, ordered)
    expected = X_act[act] @ B + np.eye(m)
    np.testing.assert_allclose(J, expected, rtol=1e-13, atol=1e-13 * np.abs(expected).max())


def test_coupled_unknowns_give_the_same_newton_step() -> None:
    """``coupled`` drops the unknowns whose row and column of B are zero (an open
    point's), and the Newton step solved without them is the step solved with them:
    ``δ = G − X_act w``, ``(1 + B X_act[act]) w = B G[act]`` (round-off: 1e-12 of δ,
    a 30-unknown LU of condition ≈ 1e3)."""
    from breakwater.stepping.interface import coupled
    from breakwater.stepping.interfacenewton import active_system

    rng = np.random.default_rng(4)
    n, m = 50, 30
    act = np.sort(rng.choice(n, m, replace=False))
    B = rng.standard_normal((m, m)) * 1e3
    dropped = [2, 5, 17]
    B[dropped, :] = 0.0
    B[:, dropped] = 0.0
    B[7, :] = 0.0  # a zero row with a nonzero column stays
    X = rng.standard_normal((n, n)) * 1e-4
    G = rng.standard_normal(n)

    def step(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        X_act = np.ascontiguousarray(X[:, a])
        return G - X_act @ np.linalg.solve(active_system(b, X_act, a), b @ G[a])

    kept, B_kept = coupled(act, B)
    keep = np.setdiff1d(np.arange(m), dropped)
    np.testing.assert_array_equal(kept, act[keep])
    np.testing.assert_array_equal(B_kept, B[np.ix_(keep, keep)])
    full = step(act, B)
    np.testing.assert_allclose(step(kept, B_kept), full, rtol=0,
                               atol=1e-12 * np.abs(full).max())
    # Nothing to drop: the arrays themselves.
    same = coupled(kept, B_kept)
    assert same[0] is kept and same[1] is B_kept


def test_mark_near_is_the_box_test() -> None:
    """``mark_near`` marks the master facets whose node box comes within the reach of a
    slave facet's (the box test written with NumPy), keeps earlier marks and counts the
    new ones."""
    rng = np.random.default_rng(8)
    xs = rng.uniform(0.0, 1.0, (6, 3, 2))
    xm = rng.uniform(-2.0, 3.0, (40, 3, 2))
    reach = 0.1
    lo, hi = xs.min(axis=1) - reach, xs.max(axis=1) + reach
    m_lo, m_hi = xm.min(axis=1), xm.max(axis=1)
    expected = np.all((m_lo[None] <= hi[:, None]) & (m_hi[None] >= lo[:, None]),
                      axis=2).any(axis=0)
    assert 0 < expected.sum() < len(xm)
    near = np.zeros(len(xm), bool)
    near[np.flatnonzero(~expected)[0]] = True  # an earlier mark stays
    earlier = near.copy()
    added = searchkernels.mark_near(xs, xm, reach, near)
    np.testing.assert_array_equal(near, expected | earlier)
    assert added == int((expected & ~earlier).sum())
    assert searchkernels.mark_near(xs, xm, reach, near) == 0


@pytest.mark.parametrize("nn", [2, 3])
@pytest.mark.parametrize("integration", ["segments", "nodes"])
def test_search_restricted_to_the_facets_in_use(nn: int, integration: str) -> None:
    """A search restricted to the master facets near the slave (``use``) is the whole
    search, bit for bit, where the others are beyond the radius; where one of them comes
    within it, ``beyond_reach`` says so and the search takes every facet.

    The master surface: the pair's, and a copy of it 1.2 m away (beyond the radius,
    0.1, of every slave facet: it would cut nothing and hold no projection)."""
    p = _pair(3, nn)
    far = p.mX + np.array([1.2, 0.0])
    mX = np.concatenate([p.mX, far])
    pos_m = np.concatenate([p.pos_m, p.pos_m])
    xs = p.sX + p.u1[p.pos_s]
    xm = mX + p.u1[pos_m]
    use = np.zeros(len(mX), bool)
    searchkernels.mark_near(xs, xm, 0.2, use)
    assert use[: len(p.mX)].any() and not use[len(p.mX):].any()
    g, w = np.polynomial.legendre.leggauss(2)
    edge = 1e-3 if integration == "nodes" else 1e-9
    r = _points(p, "nodes", edge)
    fixed = ((np.zeros(0, np.int64), np.zeros(0), np.zeros(0), np.zeros((0, nn)))
             if integration == "segments" else
             (r["point_facet"], r["xi_s"], r["weight"], r["Ns"]))

    def search(X: np.ndarray, pos: np.ndarray, mask: np.ndarray) -> tuple:  # type: ignore[type-arg]
        return searchkernels.search(p.sX, X, p.pos_s, pos, p.u1, integration == "segments",
                                    *fixed, 0.1, edge, g, w, mask, *_facing(p))

    every = np.ones(len(mX), bool)
    whole = search(mX, pos_m, every)
    restricted = search(mX, pos_m, use)
    assert restricted[-1] and len(whole[3]) > 10
    for a, b in zip(restricted, whole, strict=True):
        np.testing.assert_array_equal(a, b)
    # One far facet moved under the slave: out of ``use`` but within reach.
    moved = mX.copy()
    under = len(p.mX) + len(p.mX) // 2
    moved[under] = p.mX[len(p.mX) // 2] + np.array([0.0, -0.03])
    xm_moved = moved + p.u1[pos_m]
    assert not searchkernels.beyond_reach(xs, xm_moved, use, 0.1, edge)
    assert searchkernels.beyond_reach(xs, xm_moved, use | (np.arange(len(mX)) == under),
                                      0.1, edge)
    fallback, whole = search(moved, pos_m, use), search(moved, pos_m, every)
    assert not fallback[-1]
    for a, b in zip(fallback[:-1], whole[:-1], strict=True):
        np.testing.assert_array_equal(a, b)


def test_beyond_reach_holds_the_curves() -> None:
    """``beyond_reach``'s boxes hold each quadratic facet's curve, not only its nodes.

    A slave facet on y = 0, x in [0, 1]; a master facet whose nodes are at y = 0.3, 0.1
    and 0.12 (mid-node): its curve, y(ξ) = 0.12 − 0.1 ξ + 0.08 ξ², dips to 0.08875 at
    ξ = 0.625 (x = 0.8125), below its nodes. A radius between the two (0.09) reaches the
    curve: not beyond, where a box of the nodes would say beyond. Its box grown by the
    sag c = |½(0.3 + 0.1) − 0.12| = 0.08 starts at y = 0.02: beyond any radius below.
    """
    xs = np.array([[[0.0, 0.0], [1.0, 0.0], [0.5, 0.0]]])
    xm = np.array([[[0.0, 0.3], [1.0, 0.1], [0.5, 0.12]]])
    xi = np.linspace(-1, 1, 20001)
    lowest = (0.12 - 0.1 * xi + 0.08 * xi**2).min()
    assert abs(lowest - 0.08875) < 1e-8
    out = np.zeros(1, bool)
    assert not searchkernels.beyond_reach(xs, xm, out, 0.09, 1e-9)
    assert searchkernels.beyond_reach(xs, xm, out, 0.019, 1e-9)
    assert not searchkernels.beyond_reach(xs, xm, out, 0.021, 1e-9)  # the box: conservative
    assert searchkernels.beyond_reach(xs, xm, np.ones(1, bool), 0.09, 1e-9)  # in use


def test_iterate_state_is_gn22_update() -> None:
    """u₁ and v₁ of an iterate, compiled, are NumPy's GN22 update bit for bit (the
    accepted state is then the converged iterate's)."""
    rng = np.random.default_rng(11)
    u, v, a = (np.append(rng.normal(size=30), 0.0) for _ in range(3))
    y = rng.normal(size=30)
    dt, beta1, beta2 = 1e-4, 0.6, 0.605
    c_a, c_u, c_v = 0.5 * dt**2, 0.5 * beta2 * dt**2, beta1 * dt
    da = np.append(y, 0.0)
    u1, v1 = searchkernels.iterate_state(u, v, a, y, dt, c_a, c_u, c_v)
    np.testing.assert_array_equal(u1, u + (dt * v + c_a * a + c_u * da))
    np.testing.assert_array_equal(v1, v + (dt * a + c_v * da))


def test_friction_round_off_is_the_numpy_estimate() -> None:
    """``friction_round_off`` against the NumPy estimate newtonaids.resolution used
    before it (restated), to 1e-14 relative (sums in another order)."""
    p = _pair(4, 3)
    r = _points(p, "segments", 1e-9)
    _, lam, _, _, _ = forcekernels.residual(
        p.sX, p.mX, p.pos_s, p.pos_m, p.u1, r["f_s"], r["f_m"], r["Ns_on"], r["xi"], r["w"],
        False, 1e10, 0.0, p.node_of, len(p.node_pos))
    xm0 = p.mX + p.u1[p.pos_m]
    facet, N0, t0, _ = searchkernels.frozen(p.node_X + p.u1[p.node_pos], xm0, xm0, 0.1, *ANY)
    mu, chi = 0.5, 1e-3
    k, v_T, _, _ = forcekernels.friction(lam, facet, N0, t0, p.node_pos, p.pos_m, p.v1, mu,
                                         chi, np.full(len(p.node_pos), np.nan))
    assert len(k) > 3
    rng = np.random.default_rng(12)
    v, a = p.v1, np.append(rng.normal(size=p.n), 0.0)
    y = rng.normal(size=p.n)
    dt, beta1 = 1e-4, 0.6
    ε = float(np.finfo(float).eps)
    mag = np.abs(v) + dt * np.abs(a) + beta1 * dt * np.abs(np.append(y, 0.0))
    node = mag[p.node_pos[k]].sum(axis=1) + np.einsum(
        "jb,jbd->j", np.abs(N0[k]), mag[p.pos_m[facet[k]]])
    slope = chi**2 / (np.einsum("jd,jd->j", v_T, v_T) + chi**2) ** 1.5
    expected = float(np.sqrt(np.sum((mu * lam[k] * slope * ε * node) ** 2)))
    got = forcekernels.friction_round_off(k, v_T, lam, facet, N0, p.node_pos, p.pos_m, v, a, y,
                                          dt, beta1 * dt, mu, chi, ε)
    assert expected > 0
    assert abs(got - expected) <= 1e-14 * expected


def test_friction_normals_carry_the_pair_resultant() -> None:
    # The friction's nodal normal forces sum to the pair's resultant Σλ where some
    # λ_k < 0 (a facet cut by the contact's end) or a node has no master point, scaled
    # over the nodes that carry friction; elsewhere λ itself (the same array: bit for bit).
    from breakwater.contact.newtonaids import friction_normals

    lam = np.array([3.0, 5.0, 0.0, 2.0])
    facet = np.array([4, 5, -1, 6])
    same, s = friction_normals(lam, facet)
    assert same is lam and s == 1.0
    cut = np.array([3.0, 5.0, -0.5, 2.0])
    scaled, s = friction_normals(cut, facet)
    assert s == pytest.approx(9.5 / 10.0) and scaled[[0, 1, 3]].sum() == pytest.approx(9.5)
    orphan = np.array([3.0, 5.0, 1.0, 2.0])  # node 2 presses but has no master point
    scaled, s = friction_normals(orphan, facet)
    assert s == pytest.approx(11.0 / 10.0) and scaled[[0, 1, 3]].sum() == pytest.approx(11.0)


def test_jump_step_is_the_primal_step() -> None:
    """The conforming pairs' step on the jumps (:mod:`breakwater.stepping.jumpsystem`)
    is the step of the whole system ``(1 + X_II B) δ = G``, B = ∂f_c/∂y from the node
    tangents W (:func:`tangent_block`): 3-D nodes, some open (W = 0), some with a
    Dirichlet side (−1). C = D X Dᵀ is each entry's ± sum of X's four entries (1e-15
    of |X|: a few terms); the step agrees to 1e-10 of |δ| (two LU solves of a system
    of condition ≈ 600 with W's 1e10 against X's 1e-9: measured 5e-15)."""
    from breakwater.contact.nodalkernels import tangent_block
    from breakwater.stepping.jumpsystem import JumpSystem, jump_compliance, jump_rows

    rng = np.random.default_rng(11)
    nodes, gdim = 40, 3
    n = 2 * nodes * gdim + 7  # and unknowns no node holds
    order = rng.permutation(n)[: 2 * nodes * gdim].reshape(2, nodes, gdim)
    slave, master = np.ascontiguousarray(order[0]), np.ascontiguousarray(order[1])
    slave[3, 1] = master[5, 2] = master[6, 0] = -1  # Dirichlet sides
    W = rng.standard_normal((nodes, gdim, gdim)) * 1e10
    W[rng.uniform(size=nodes) < 0.3] = 0.0  # open nodes
    R = rng.standard_normal((n, n))
    X = np.ascontiguousarray((R @ R.T / n + np.eye(n)) * 1e-9)
    G = rng.standard_normal(n)

    act, A = tangent_block(W, slave, master, n)
    B = np.zeros((n, n))
    B[np.ix_(act, act)] = A
    expected = np.linalg.solve(np.eye(n) + X @ B, G)
    δ = JumpSystem().step(X, G, W, slave, master)
    np.testing.assert_allclose(δ, expected, rtol=0, atol=1e-10 * np.abs(expected).max())

    Wh, s, m = jump_rows(W, slave, master)
    assert len(s) == gdim * np.count_nonzero(W.reshape(nodes, -1).any(axis=1))
    D = np.zeros((len(s), n))
    for p in range(len(s)):
        if s[p] >= 0:
            D[p, s[p]] = -1.0
        if m[p] >= 0:
            D[p, m[p]] = 1.0
    np.testing.assert_allclose(jump_compliance(X, s, m), D @ X @ D.T, rtol=0,
                               atol=1e-15 * np.abs(X).max())
    blocks = np.zeros((len(s), len(s)))
    for k in range(len(Wh)):
        blocks[k * gdim:(k + 1) * gdim, k * gdim:(k + 1) * gdim] = Wh[k]
    np.testing.assert_allclose(D.T @ blocks @ D, B, rtol=0, atol=1e-15 * np.abs(B).max())
