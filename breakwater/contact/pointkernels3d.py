"""The NumPy reference of a 3-D general pair's point kernel and its complex-step Jacobian.

Vectorised over points with the analytic operations of
:mod:`breakwater.contact.projection3d` (complex-step safe): :func:`normal_forces` is what
:func:`breakwater.contact.forcekernels3d.point` computes (two Newton steps of the
closest-point projection from the search's (ξ̄, η̄), the master's unit normal there, the
penalty traction ε_n⟨−g_n⟩₊ n̄; the slave receives ``−N_s t w``, the master ``N̄ t w``),
and :func:`jacobian` its derivatives by a complex step per local DOF (36 for two 6-node
faces). ``tests/test_pair3d.py`` checks the compiled kernels against them.
:func:`friction_forces` is the slave nodes' friction of
:func:`breakwater.contact.friction3d.friction` (``tests/test_pair3d_friction.py``).
"""

from __future__ import annotations

import numpy as np

from breakwater.contact.projection3d import closest_point, shape, surface, unit_normal

__all__ = ["H", "friction_forces", "jacobian", "normal_forces"]

H = 1e-20  # complex step


def normal_forces(Ns: np.ndarray, xi: np.ndarray, xs: np.ndarray, xm: np.ndarray,
                  eps: float, weight: np.ndarray, reference: np.ndarray | None = None,
                  g0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Nodal forces of contact points (real or complex).

    Args:
        Ns: Slave shape functions at the points ``(K, ns)``.
        xi: Newton's start (ξ̄, η̄) ``(K, 2)``.
        xs: The slave faces' nodes ``(K, ns, 3)``.
        xm: The master faces' nodes ``(K, nm, 3)`` (oriented: the normal outward).
        eps: ε_n.
        weight: The points' weights ``(K,)``.
        reference: The master faces' reference nodes (small rotations' normal), or None.
        g0: The initial gap.

    Returns:
        The forces ``(K, ns + nm, 3)`` and g_n ``(K,)``.
    """
    x = np.einsum("kn,knd->kd", Ns, xs)
    xi = closest_point(x, xm, xi, iterations=2, tol=0.0)
    N = shape(xi, xm.shape[1])[0]
    _, dx, _ = surface(xm if reference is None else reference, xi)
    n = unit_normal(dx)
    x_bar = np.einsum("kn,knd->kd", N, xm)
    g = np.sum((x - x_bar) * n, axis=1) + g0
    p = np.where(np.real(g) <= 0, -eps * g, 0 * g)
    t = (p * weight)[:, None] * n
    forces = np.concatenate([-Ns[:, :, None] * t[:, None, :], N[:, :, None] * t[:, None, :]],
                            axis=1)
    return forces, g


def jacobian(Ns: np.ndarray, xi: np.ndarray, xs: np.ndarray, xm: np.ndarray, eps: float,
             weight: np.ndarray, cu: float, reference: np.ndarray | None = None
             ) -> np.ndarray:
    """∂forces/∂Δa of each point by complex steps ``i h c_u`` of its local DOFs.

    Returns:
        ``(K, 3 (ns + nm), 3 (ns + nm))``, the local DOFs in the order slave nodes then
        master nodes, x y z each (the forces flattened the same way).
    """
    K, ns, nm = len(Ns), xs.shape[1], xm.shape[1]
    L = 3 * (ns + nm)
    out = np.zeros((K, L, L))
    for j in range(L):
        a, d = divmod(j, 3)
        s, m = xs.astype(complex), xm.astype(complex)
        if a < ns:
            s[:, a, d] += 1j * H * cu
        else:
            m[:, a - ns, d] += 1j * H * cu
        f, _ = normal_forces(Ns, xi, s, m, eps, weight, reference)
        out[:, :, j] = f.reshape(K, L).imag / H
    return out


def friction_forces(lam: np.ndarray, N0: np.ndarray, T0: np.ndarray, vs: np.ndarray,
                    vm: np.ndarray, mu: float, chi: float) -> np.ndarray:
    """The friction forces on slave nodes (real or complex; complex-step safe).

    ``F = −μ λ Σ_α T₀_α c_α / sqrt(|c|² + χ²)``, ``c_α = T₀_α·(v_s − Σ_b N̄₀_b v_b)``.

    Args:
        lam: The nodes' normal forces ``(m,)``.
        N0: The master shape values at their start-of-step points ``(m, nm)``.
        T0: The tangent bases there ``(m, 2, 3)``.
        vs: The slave nodes' velocities ``(m, 3)``.
        vm: The master face nodes' velocities ``(m, nm, 3)``.
        mu: μ.
        chi: χ.

    Returns:
        F ``(m, 3)``, the force on each slave node (the master's nodes take −N̄₀_b F).
    """
    rel = vs - np.einsum("kb,kbd->kd", N0, vm)
    c = np.einsum("kad,kd->ka", T0, rel)
    s = np.sqrt(np.sum(c * c, axis=1) + chi * chi)
    return -mu * (lam / s)[:, None] * np.einsum("ka,kad->kd", c, T0)
