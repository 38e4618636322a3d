"""The point kernels of the general contact pairs: nodal forces of contact points.

Vectorised over points, written with analytic NumPy operations only (no ``abs``, the
active set decided on real parts by :mod:`forms.contact`), so that they run in complex
arithmetic: :func:`jacobian` differentiates any of them by complex steps, exactly (no
cancellation), the projection's Newton (:func:`breakwater.contact.projection.closest_point`)
included; :class:`DenseEntries` sums their per-point blocks into the interface matrix.
Used by :class:`breakwater.contact.general.SurfaceContact`.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import partial
from typing import Any

import numpy as np

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.contact.projection import closest_point, shape

__all__ = ["DenseEntries", "contact_geometry", "jacobian", "nodal_normal_forces",
           "normal_and_shares", "normal_forces", "unit_tangent"]

H = 1e-20  # complex step (no cancellation: any tiny step is exact to round-off)


def unit_tangent(dN: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """Unit tangent ``dx/dξ / |dx/dξ|`` (analytic: no abs, complex-step safe)."""
    t = np.einsum("kn,knd->kd", dN, nodes)
    return t / np.sqrt(np.sum(t * t, axis=1))[:, None]


def contact_geometry(Ns: np.ndarray, xi: np.ndarray, xs: np.ndarray, xm: np.ndarray,
                     refine: int, reference: np.ndarray | None = None
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Slave points, their projections and the master's normal there (real or complex).

    Args:
        Ns: Slave shape functions at each point, ``(K, nn)``.
        xi: The projection's local coordinate on the master facet (Newton's start).
        xs: The slave facets' node positions, ``(K, nn, gdim)``.
        xm: The master facets' node positions (oriented: ``(t_y, −t_x)`` is outward).
        refine: Newton steps of the projection (``tol`` 0: always that many).
        reference: The master facets' reference node positions: n̄ is the reference
            facet's normal at the projection (small rotations); None: the current one's.

    Returns:
        ``x_s``, ξ̄, the master shape functions N̄ at ξ̄, the projection x̄ and n̄.
    """
    x_s = np.einsum("kn,knd->kd", Ns, xs)
    xi = closest_point(x_s, xm, xi, iterations=refine, tol=0.0)
    N, dN, _ = shape(xi, xm.shape[1])
    t = unit_tangent(dN, xm if reference is None else reference)
    n = np.stack([t[:, 1], -t[:, 0]], axis=1)
    return x_s, xi, N, np.einsum("kn,knd->kd", N, xm), n


def _contact_point(law: forms.ContactLaw, Ns: np.ndarray, xi: np.ndarray,
                   groups: Sequence[tuple[np.ndarray, np.ndarray]], refine: int,
                   reference: np.ndarray | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Projection, normal and pressure at contact points: (x_s, N̄, n̄, traction p n̄).

    The geometry is :func:`contact_geometry`'s.
    """
    (xs, _), (xm, _) = groups
    x_s, _, N, x_bar, n = contact_geometry(Ns, xi, xs, xm, refine, reference)
    return x_s, N, n, law.traction(x_s, x_bar, n)


def normal_forces(law: forms.ContactLaw, Ns: np.ndarray, xi: np.ndarray, weight: np.ndarray,
                  groups: Sequence[tuple[np.ndarray, np.ndarray]], refine: int = 2,
                  reference: np.ndarray | None = None) -> np.ndarray:
    """Nodal residual of the normal pressure at contact points (real or complex).

    The point ``x_s = Σ N_s x_k`` of the slave facet is projected onto the master facet
    (``refine`` Newton steps from ξ, in the inputs' arithmetic, so that a complex step
    carries the implicit derivative of the projection); ``g_n = (x_s − x̄)·n̄``
    (eq. 7), ``p = ε_n ⟨−g_n⟩₊`` (eq. 11 penalised, as in eq. 23), from
    :class:`forms.ContactLaw`.

    Args:
        law: The contact law (float parameters).
        Ns: Slave shape functions at each point, ``(K, nn)``.
        xi: The projection's local coordinate on the master facet (Newton's start).
        weight: Reference length of each point.
        groups: ``[(x, v)]`` of the slave facet and of the master facet (oriented:
            ``(t_y, −t_x)`` is outward), each ``(K, nn, gdim)``.
        refine: Newton steps of the projection.
        reference: The master facets' reference nodes ``(K, nn, gdim)``: n̄ is the
            reference surface's normal at the projection (small rotations); None: the
            current surface's (eq. 7).

    Returns:
        ``(K, 2 nn, gdim)``: the residual on the slave's nodes, then on the master's.
    """
    _, N, _, traction = _contact_point(law, Ns, xi, groups, refine, reference)
    traction = traction * weight[:, None]
    return np.concatenate([-Ns[:, :, None] * traction[:, None, :],
                           N[:, :, None] * traction[:, None, :]], axis=1)


def nodal_normal_forces(law: forms.ContactLaw, Ns: np.ndarray, xi: np.ndarray,
                        weight: np.ndarray, groups: Sequence[tuple[np.ndarray, np.ndarray]],
                        refine: int = 2, reference: np.ndarray | None = None) -> np.ndarray:
    """Each point's share ``p w N_k`` of its slave nodes' normal forces, ``(K, nn)``.

    Summed over the points, ``λ_k = ∫ p N_k``: the normal force of slave node k
    consistent with the integrated pressure (as :func:`normal_forces`).
    """
    _, _, n, traction = _contact_point(law, Ns, xi, groups, refine, reference)
    p = np.sum(traction * n, axis=1)
    return (p * weight)[:, None] * Ns


def normal_and_shares(law: forms.ContactLaw, Ns: np.ndarray, xi: np.ndarray,
                       weight: np.ndarray, groups: Sequence[tuple[np.ndarray, np.ndarray]],
                       refine: int = 2, reference: np.ndarray | None = None) -> np.ndarray:
    """:func:`normal_forces` and :func:`nodal_normal_forces` side by side, ``(K, ·)``."""
    _, N, n, traction = _contact_point(law, Ns, xi, groups, refine, reference)
    tw = traction * weight[:, None]
    forces = np.concatenate([-Ns[:, :, None] * tw[:, None, :], N[:, :, None] * tw[:, None, :]],
                            axis=1)
    shares = (np.sum(tw * n, axis=1))[:, None] * Ns
    return np.concatenate([forces.reshape(len(Ns), -1), shares], axis=1)


def jacobian(kernel: partial[np.ndarray], groups: Sequence[tuple[np.ndarray, np.ndarray]],
             cu: float, cv: float) -> np.ndarray:
    """∂kernel/∂Δa per point by complex steps, ``(K, outputs, local)``.

    Each local DOF (group, node, component) is stepped in x by ``i h cu`` and in v
    by ``i h cv`` (x and v of GN22 move by cu and cv per unit Δa). The steps are taken
    in one batched evaluation: the kernel (a ``partial`` whose per-point arguments
    have K rows) runs once on ``local`` copies of the points, copy j stepped in DOF j.
    """
    K, nn, gdim = groups[0][0].shape
    local = len(groups) * nn * gdim
    if not K:
        return np.zeros((0, 0, 0))

    def tile(a: Any) -> Any:
        per_point = isinstance(a, np.ndarray) and a.ndim >= 1 and a.shape[0] == K
        return np.tile(a, (local,) + (1,) * (a.ndim - 1)) if per_point else a

    batched = partial(kernel.func, *map(tile, kernel.args),
                      **{k: tile(a) for k, a in kernel.keywords.items()})
    cx = [(tile(x).astype(complex), tile(v).astype(complex)) for x, v in groups]
    for j in range(local):
        group, rest = divmod(j, nn * gdim)
        node, comp = divmod(rest, gdim)
        x, v = cx[group]
        x[j * K:(j + 1) * K, node, comp] += 1j * H * cu
        v[j * K:(j + 1) * K, node, comp] += 1j * H * cv
    columns = batched(cx).reshape(local, K, -1).imag / H
    return np.ascontiguousarray(columns.transpose(1, 2, 0))


class DenseEntries:
    """Entries of a dense n × n matrix, collected and summed once (:meth:`matrix`)."""

    def __init__(self, n: int) -> None:
        self.n = n
        self.flat: list[np.ndarray] = []
        self.values: list[np.ndarray] = []

    def add(self, flat: np.ndarray, values: np.ndarray) -> None:
        """A[flat] += values (flat row-major indices)."""
        self.flat.append(flat.ravel())
        self.values.append(values.ravel())

    def block(self, rows: np.ndarray, cols: np.ndarray, block: np.ndarray) -> None:
        """A[rows, cols] += block per point (Dirichlet entries, −1, skipped)."""
        keep = (rows[:, :, None] >= 0) & (cols[:, None, :] >= 0)
        self.add((rows[:, :, None] * self.n + cols[:, None, :])[keep], block[keep])

    def matrix(self) -> np.ndarray:
        """The sum, ``(n, n)``."""
        n = self.n
        if not self.flat:
            return np.zeros((n, n))
        return np.bincount(np.concatenate(self.flat), weights=np.concatenate(self.values),
                           minlength=n * n).reshape(n, n)
