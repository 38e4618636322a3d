"""The interface Newton on the unknowns a step's contact may touch.

A general pair's master surface may be much longer than its contact: the separately
meshed Goda caisson's master is the mound's crest and slopes (340 interface unknowns),
of which the caisson's base can reach about half. f_c is zero, and independent of y, on
the others ("far"): they are bulk unknowns of the step. Eliminated with the bulk, the
step's interface equations are those of the near unknowns n alone,

    G_n(y_n) = y_n − z_n + X_nn f_c(y_n) = 0,    S_n = X_nn⁻¹,    F_n = S_n G_n,

and the far rows follow: ``y_f = z_f − X_fn (f_c − F)_n``, which is what the step's
``Δa = z − X (f_c − F)`` gives there (F_f = 0: the far rows are in equilibrium, as the
bulk's). The Newton then runs on n_near unknowns instead of n_I: its products
X_II f_c and S G shrink with the square of the ratio.

Exact by construction: :class:`NearContact` evaluates the providers on the whole
interface (the far unknowns at Newton's start) and raises :class:`OutOfReach` where
that assumption fails, an evaluation with a force or a Jacobian entry on a far unknown,
or a slip guard that moved one; :class:`~breakwater.stepping.interfacenewton.InterfaceNewton`
then solves the step on all the unknowns. The solution itself, its far rows set, is
evaluated once more and must reach no far unknown either (:meth:`Reach.solve`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from breakwater.common.arrays import read_only
from breakwater.contact.coupling import BulkStiffness

if TYPE_CHECKING:
    from breakwater.stepping.factorisations import Factorisation
    from breakwater.stepping.interface import ContactSum

__all__ = ["NearContact", "NearFactors", "OutOfReach", "Reach", "near_factors"]


class OutOfReach(Exception):
    """The step's contact touched an interface unknown outside the near set."""


@dataclass
class NearFactors:
    """X_II and S restricted to the near unknowns, and the far rows' coupling.

    Attributes:
        near: The near unknowns (sorted interface positions).
        far: The others.
        X_II: ``X_II[near, near]``.
        S: Its inverse (the Schur complement of A on the near unknowns).
        X_fn: ``X_II[far, near]``.
    """

    near: np.ndarray
    far: np.ndarray
    X_II: np.ndarray
    S: np.ndarray
    X_fn: np.ndarray


def near_factors(fact: Factorisation, near: np.ndarray) -> NearFactors:
    """:class:`NearFactors` of a factorisation for the unknowns ``near``."""
    n = len(fact.X_II)
    far = np.setdiff1d(np.arange(n), near)
    X_nn = np.ascontiguousarray(fact.X_II[np.ix_(near, near)])
    return NearFactors(near, far, X_nn, np.linalg.inv(X_nn),
                       np.ascontiguousarray(fact.X_II[np.ix_(far, near)]))


class Reach:
    """An interface Newton's solves on the near unknowns: their factors and counts.

    Attributes:
        solves: Steps solved on the near unknowns.
        fallbacks: Steps whose contact touched a far unknown (solved on all).
    """

    def __init__(self) -> None:
        self.solves = 0
        self.fallbacks = 0
        self._kept: tuple[Factorisation, NearFactors] | None = None

    def factors(self, fact: Factorisation, near: np.ndarray) -> NearFactors:
        """:func:`near_factors`, kept while the factorisation and the near set stay."""
        kept = self._kept
        if kept is None or kept[0] is not fact or not np.array_equal(kept[1].near, near):
            self._kept = kept = (fact, near_factors(fact, near))
        return kept[1]

    def solve(self, newton: Any, fact: Factorisation, near: np.ndarray, z_I: np.ndarray,
              y0: np.ndarray, w_I: np.ndarray, w_norm2: float, v_pred: np.ndarray,
              dv_dx: float) -> int | None:
        """The interface Newton's solve on the unknowns ``near``; None: out of reach.

        ``newton``: the :class:`~breakwater.stepping.interfacenewton.InterfaceNewton`
        (its ``_solve`` on ``fact``'s near factors, with its contact seen on the near
        unknowns); the other arguments are those of its ``solve``. On success its y,
        f_c and F are set on all the interface unknowns (:meth:`whole`) and its
        ``support`` to ``near``.
        """
        nf = self.factors(fact, near)
        whole = newton.contact
        newton.contact = NearContact(whole, near, y0, v_pred)
        its: int | None = None
        try:
            its = newton._solve(nf, z_I[near], y0[near], w_I[near], w_norm2, v_pred[near],
                                dv_dx)
        except OutOfReach:
            pass
        finally:
            newton.contact = whole
        if its is not None:
            y, fc, F = self.whole(nf, z_I, y0, newton.y, newton.fc, newton.F)
            # The solution itself (its far rows now the bulk's) reaches no far unknown:
            # one evaluation, whose search the outputs then find (it is their state).
            if not whole.vector(y)[nf.far].any():
                self.solves += 1
                newton.y, newton.fc, newton.F, newton.support = y, fc, F, near
                return its
        self.fallbacks += 1
        return None

    @property
    def near(self) -> np.ndarray | None:
        """The last near set (None: none yet)."""
        return None if self._kept is None else self._kept[1].near

    def whole(self, nf: NearFactors, z_I: np.ndarray, y0: np.ndarray, y: np.ndarray,
              fc: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A near solve's (y, f_c, F) on all the interface unknowns.

        The far rows: ``y_f = z_f − X_fn (f_c − F)_n``, f_c and F zero.
        """
        out = np.array(y0, dtype=float)
        out[nf.near] = y
        fc_all, F_all = np.zeros(len(out)), np.zeros(len(out))
        fc_all[nf.near], F_all[nf.near] = fc, F
        out[nf.far] = z_I[nf.far] - nf.X_fn @ (fc - F)
        return out, fc_all, F_all


class NearContact:
    """A :class:`~breakwater.stepping.interface.ContactSum` seen on the near unknowns.

    The providers are evaluated on the whole interface vector: Newton's start ``base``
    with the near entries replaced by the iterate.

    Args:
        contact: The providers' sum.
        near: The near unknowns.
        base: Newton's start on the whole interface.
        v_pred: The predictor's velocities on the whole interface (the guards').

    Its evaluations raise :class:`OutOfReach` at a force, a Jacobian entry or a guard's
    step on a far unknown.
    """

    def __init__(self, contact: ContactSum, near: np.ndarray, base: np.ndarray,
                 v_pred: np.ndarray) -> None:
        self.contact, self.near = contact, near
        self.base, self.v_pred = base, v_pred
        self.far = np.ones(len(base), bool)
        self.far[near] = False
        self.index = np.full(len(base), -1, np.int64)
        self.index[near] = np.arange(len(near))
        self.primal = contact.primal
        self._kept: tuple[np.ndarray, np.ndarray] | None = None  # (y, _whole(y)), y read-only

    def _whole(self, y: np.ndarray) -> np.ndarray:
        """The whole interface vector of the near iterate y (read-only if y is)."""
        if self._kept is not None and self._kept[0] is y:
            return self._kept[1]
        out = self.base.copy()
        out[self.near] = y
        if not y.flags.writeable:  # an iterate: the evaluations of one see one array
            self._kept = (y, read_only(out))
        return out

    def vector(self, y: np.ndarray) -> np.ndarray:
        """f_c at the near unknowns."""
        fc = self.contact.vector(self._whole(y))
        if fc[self.far].any():
            raise OutOfReach
        return fc[self.near]

    def active_jacobian(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The providers' ``(act, A)``, act as near positions."""
        active = self.contact.active_jacobian(self._whole(y))
        if active is None:
            raise OutOfReach
        act, A = active
        at = self.index[act]
        if len(at) and at.min() < 0:
            raise OutOfReach
        return at, A

    def jump_jacobian(self, y: np.ndarray) -> None:
        """None: the near unknowns are a general pair's (no conforming pairs' jumps)."""
        return None

    def left_jacobian(self, y: np.ndarray, X: np.ndarray) -> np.ndarray:
        """Not on the near unknowns: the providers have no active form."""
        raise OutOfReach

    def precheck(self, x: np.ndarray, step: np.ndarray, v_pred: np.ndarray,
                 dv_dx: float, bulk: BulkStiffness | None = None) -> int:
        """The providers' guards on the whole interface (far steps zero; S on the near)."""
        whole = np.zeros(len(self.base))
        whole[self.near] = step
        if bulk is not None:
            index = np.full(len(self.base), -1, np.int64)
            index[self.near] = np.arange(len(self.near))
            bulk = BulkStiffness(bulk.S, index)
        cut = self.contact.precheck(self._whole(x), whole, self.v_pred, dv_dx, bulk)
        if whole[self.far].any():
            raise OutOfReach
        step[:] = whole[self.near]
        return cut

    def true_law(self, crawl: bool = True) -> bool:
        """The providers' ``true_law(crawl)``."""
        return self.contact.true_law(crawl)

    def regularise(self, stretch: float) -> bool:
        """The providers' ``regularise(stretch)``."""
        return self.contact.regularise(stretch)

    def resolution(self, y: np.ndarray) -> float:
        """The providers' round-off of f_c at the iterate."""
        return self.contact.resolution(self._whole(y))
