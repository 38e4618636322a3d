"""Newton's slip guard: nodal slips do not reverse within a Newton step, nor crawl.

With χ = 1e-10 the regularised friction law is a step function of the slip velocity:
a Newton step that reverses the relative tangential velocity of a node jumps from one
branch ``±μp`` to the other, and Newton 2-cycles between stick and slip. For each node
whose slip velocity would reverse (turn by more than 90° in the tangent plane: in 2D a
sign change; and is not already inside the law's stick band, ``|v_T| > χ``), the slave's
tangential step is cut so that the node lands at zero slip velocity, where the tangent
``μp/χ`` is exact; Newton then converges to stick or leaves zero on the side the residual
asks for. A step that does not reverse but whose linear model asks for a friction
force in the law's curved zone (a slip within :data:`~breakwater.contact.guardkernels.CURVED`
χ) lands where the law gives that force, instead of crawling along the saturating law
one χ per iteration (:mod:`breakwater.contact.guardkernels`; measured: the separately
meshed Goda case 6592 → 4114 Newton iterations, the same results to six digits). The
fast solver's guards land; the reference solver's (``SlipGuard(landing=False)``) cuts
reversals alone, its Newton kept as it was.
Normal components are untouched. The decision
is taken from values gathered on every rank
(:class:`~breakwater.contact.conforming.InterfaceNodes`), so it is the same for any
partition.

The guard knows nothing of the time stepper: it is given the nodal velocities of the
current iterate and ``∂v/∂x``, the velocity change per unit Newton step (β₁Δt for
GN22, whose unknown is Δa).

(Also tried: taking growing slip velocities in ``s = asinh(v/χ)``, where
``φ = tanh s``, to leave the band faster: no fewer iterations on the Goda case, so
not kept.)
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from breakwater import forms  # type: ignore[attr-defined]
from breakwater.contact.conforming import InterfaceNodes
from breakwater.contact.guardkernels import F_MAX


def guard_slip(w0: np.ndarray, w1: np.ndarray, tangents: np.ndarray, χ: float,
               landing: bool = True) -> np.ndarray:
    """Newton's proposal for nodal slip velocities with reversals landed at zero.

    A node's slip reverses when its tangential velocity turns by more than 90°
    (w₀·w₁ < 0 in the tangent plane) from outside the band ``|w₀| ≤ χ``: the
    isotropic law's branch jump (in 2D, a sign change along the one tangent). Its
    tangential velocity is then set to zero, where the tangent μp/χ is exact, whatever
    the tangent basis. Any other node whose linear model asks for a force in the law's
    curved zone lands where the law gives that force (:func:`land`).

    Args:
        w0: Current relative tangential velocities, shape (n, gdim).
        w1: Newton's proposal, shape (n, gdim).
        tangents: Orthonormal tangent vectors per node, shape (n, gdim - 1, gdim).
        χ: Regularisation velocity.
        landing: Land slips on the law's curve (False: reversals alone, the reference
            path's guard).

    Returns:
        The corrected proposal: ``w1`` but for its tangential part at the nodes whose
        slip reverses, which is zero, and at those that land on the curve (the normal
        part is kept); ``w1`` itself where no node changes.
    """
    c0 = np.einsum("nkd,nd->nk", tangents, w0)
    c1 = np.einsum("nkd,nd->nk", tangents, w1)
    reverse = (np.sum(c0 * c1, axis=1) < 0) & (np.sqrt(np.sum(c0 * c0, axis=1)) > χ)
    landed, on_curve = c1, np.zeros(len(c1), bool)
    if landing:
        landed, on_curve = land(c0, c1, χ)
        on_curve &= ~reverse
    if not (reverse.any() or on_curve.any()):
        return w1
    target = np.where(on_curve[:, None], landed, np.where(reverse[:, None], 0.0, c1))
    return w1 - np.einsum("nkd,nk->nd", tangents, c1 - target)


def land(c0: np.ndarray, c1: np.ndarray, χ: float) -> tuple[np.ndarray, np.ndarray]:
    """The landing of tangential slips on the law's curve (the module doc).

    The linear model's force ``f = φ(c₀) + φ'(c₀)(c₁ − c₀)`` of the isotropic law
    ``φ(c) = c / sqrt(|c|² + χ²)``, and the slip where the law gives it,
    ``χ f / sqrt(1 − |f|²)``, where ``|f| < F_MAX``
    (:mod:`breakwater.contact.guardkernels`, whose :func:`~breakwater.contact.guardkernels.land`
    is the compiled form, operation for operation).

    Args:
        c0: The iterates' slips in the tangent bases, shape (n, gdim − 1).
        c1: Newton's proposals.
        χ: Regularisation velocity.

    Returns:
        The landing slips, and where they apply (elsewhere: not landings).
    """
    r = np.sqrt(np.sum(c0 * c0, axis=1) + χ * χ)[:, None]
    φ0 = c0 / r
    p = np.sum(φ0 * (c1 - c0), axis=1)[:, None]
    f = φ0 + ((c1 - c0) - φ0 * p) / r
    f2 = np.sum(f * f, axis=1)
    on_curve = f2 < F_MAX * F_MAX
    return (χ / np.sqrt(np.where(on_curve, 1.0 - f2, 1.0)))[:, None] * f, on_curve


class SlipGuard:
    """The slip guard of every contact pair of a model (a Newton line-search pre-check).

    Args:
        nodes: The node pairs of each contact pair.
        landing: Land slips on the law's curve too (:func:`guard_slip`); False: reversals
            alone (the reference path's Newton, kept as it was).

    """

    def __init__(self, nodes: Sequence[InterfaceNodes], landing: bool = True) -> None:
        self.nodes = nodes
        self.landing = landing

    def __call__(self, v: Sequence[np.ndarray], step: Sequence[np.ndarray],
                 dv_dx: float) -> int:
        """Cut the Newton step where a nodal slip velocity would reverse (collective).

        Newton's next iterate is ``x − step``, with velocities ``v − dv_dx · step``.

        Args:
            v: Local velocity arrays (``f.x.array``) of the current iterate, per body.
            step: Local arrays of the Newton step, per body; the owned slave entries
                of the corrected nodes are changed in place.
            dv_dx: Velocity change per unit of the unknown (β₁Δt for GN22's Δa).

        Returns:
            The number of nodes corrected (the same on every rank); 0: ``step`` is
            untouched.
        """
        corrected = 0
        for nodes in self.nodes:
            p = nodes.pair
            s, m = p.slave, p.master
            vs, vm = nodes.gather(v[s], v[m])
            ys, ym = nodes.gather(step[s], step[m])
            w0 = nodes.tangential(vs - vm)
            w1 = w0 - dv_dx * nodes.tangential(ys - ym)  # x_new = x − y
            w1_new = guard_slip(w0, w1, nodes.tangents, self._band(p.law.friction),
                                self.landing)
            fix = np.any(w1_new != w1, axis=1)
            if not fix.any():
                continue
            corrected += int(fix.sum())
            # Slave step with the normal part kept and the tangential part giving w1_new.
            ys_new = ys - nodes.tangential(ys) + nodes.tangential(ym) + (w0 - w1_new) / dv_dx
            nodes.scatter_slave(ys_new, step[s], fix)
        return corrected

    @staticmethod
    def _band(friction: forms.RegularisedCoulomb) -> float:
        """The law's stick band now (a float; cheaper than the law's ``values()``)."""
        return forms.parameter_value(friction.stick_band)
