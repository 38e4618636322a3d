"""The contact law: penalty normal contact and regularised Coulomb friction.

the paper's §2-3, eqs. 7-15 and 23. **This module is the one place where the contact law
is written.** The residual (:meth:`breakwater.model.model.ContactModel.traction`), the
energy ledger (:mod:`forms.energy`), the history's resultants, the nodal outputs
(:meth:`breakwater.contact.conforming.InterfaceNodes.contact_state`) and the Newton slip guard
(:mod:`breakwater.contact.slipguard`, through :attr:`RegularisedCoulomb.stick_band`) all
evaluate the objects below, which a model builds per contact pair
(:meth:`ContactLaw.of`, with ``fem.Constant`` parameters; :meth:`ContactLaw.values`
for nodal arrays).

Where to change the friction law: here, in :class:`RegularisedCoulomb` (or a new
class with the same methods, built in :meth:`ContactLaw.of`). If the new law needs a
new parameter, it also needs an entry in the case schema (``[contact.<interface>]``,
:mod:`breakwater.casefile.case`) and the field of :class:`breakwater.model.model.ContactPair` that
carries it to :meth:`ContactLaw.of`. The fast solver's compiled kernels
(``breakwater/contact/nodalkernels.py``) repeat these two laws' formulas, and their
derivatives, for the conforming pairs' inner loop: a pair whose law is another class
takes the UFL forms there (``nodal_contact_applies``), and a change to the formulas of
:class:`PenaltyContact` or :class:`RegularisedCoulomb` must be made in the kernels too
(``tests/test_nodalcontact.py`` compares the kernels with these forms).

Each law evaluates on UFL expressions (for forms) and on NumPy arrays of nodal
values (for outputs and nodal algorithms) with the same arithmetic: the few
operations that differ (``dot``, ``sqrt``, the active-set ``conditional`` and the
product of a scalar field with a vector field) come from :func:`_ops`, which picks
UFL or NumPy from the type of the arguments. On the UFL path the parameters may be
``fem.Constant`` s and the vectors restricted expressions (``u_s("+")``); on the
NumPy path the parameters are floats, scalars per node have shape ``(n,)`` and
vectors per node shape ``(n, gdim)``; the arrays may be complex (the NumPy operations
are analytic, so a complex step differentiates them: the general contact pairs of
:mod:`breakwater.contact.general` take their Jacobian so).

Quantities are written for a slave body s pressed on a master body m, on a
conforming interface, with the master's outward unit normal ``n`` (pointing from
the master into the slave):

- normal gap            g_n = (u_s − u_m)·n + g_0                     (eq. 7)
- penalty pressure      p = ε_n ⟨−g_n⟩₊, active at g_n ≤ 0  (eq. 11 penalised, as in eq. 23)
- relative tangential velocity   v_T = (I − n⊗n)(v_s − v_m)           (eqs. 9-10)
- regularised Coulomb   t_T = −μ p v_T / sqrt(|v_T|² + χ²)           (eqs. 14-15)
- traction on the slave t_s = p n + t_T; the master receives −t_s     (eq. 23)
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np
import ufl


class _UflOps:
    """The backend operations on UFL expressions."""

    dot = staticmethod(ufl.dot)
    sqrt = staticmethod(ufl.sqrt)

    @staticmethod
    def where_closed(g_n, closed, open_):
        """``closed`` where g_n ≤ 0, else ``open_``."""
        return ufl.conditional(ufl.le(g_n, 0.0), closed, open_)

    @staticmethod
    def scale(s, v):
        """Scalar field times vector field."""
        return s * v

    @staticmethod
    def divide(v, s):
        """Vector field over scalar field."""
        return v / s


class _NumpyOps:
    """The backend operations on nodal arrays: vectors ``(n, gdim)``, scalars ``(n,)``."""

    sqrt = staticmethod(np.sqrt)

    @staticmethod
    def dot(a, b):
        return np.sum(a * b, axis=-1)

    @staticmethod
    def where_closed(g_n, closed, open_):
        # The real part decides: complex arrays carry complex-step derivatives
        # (breakwater.contact.general), and the active set does not depend on them.
        return np.where(np.real(np.asarray(g_n)) <= 0.0, closed, open_)

    @staticmethod
    def scale(s, v):
        return np.asarray(s)[..., None] * v

    @staticmethod
    def divide(v, s):
        return v / np.asarray(s)[..., None]


def _ops(*args: Any) -> type[_UflOps] | type[_NumpyOps]:
    """UFL operations if any argument is a UFL expression, else NumPy's."""
    if any(isinstance(a, ufl.core.expr.Expr) for a in args):
        return _UflOps
    return _NumpyOps


def parameter_value(parameter: Any) -> float:
    """A law's parameter as a float: a ``fem.Constant``'s value now, or the number."""
    return float(getattr(parameter, "value", parameter))


def _floats(law):
    """A copy of a law (a dataclass) with each parameter a float."""
    return replace(law, **{f.name: parameter_value(getattr(law, f.name)) for f in fields(law)})


def tangential_part(v, n):
    """Tangential projection (I − n⊗n) v (UFL, or nodal arrays ``(n, gdim)``)."""
    if isinstance(v, np.ndarray) and isinstance(n, np.ndarray) and v.ndim == 2:
        return v - np.einsum("ki,ki->k", v, n)[:, None] * n  # the same, without dispatch
    op = _ops(v, n)
    return v - op.scale(op.dot(v, n), n)


@dataclass(frozen=True)
class PenaltyContact:
    """Penalty normal contact: gap → pressure (eqs. 7, 12).

    Attributes:
        ε_n: Normal penalty (N/m³), a float or a ``fem.Constant``.
        g0: Initial normal gap (m), zero on a conforming interface.

    """

    ε_n: Any
    g0: Any = 0.0

    def gap(self, u_s, u_m, n):
        """Normal gap g_n = (u_s − u_m)·n + g_0; negative means penetration (eq. 7).

        Args:
            u_s: Slave displacement on the interface.
            u_m: Master displacement on the interface.
            n: Master outward unit normal (from master into slave).

        """
        return _ops(u_s, u_m, n).dot(u_s - u_m, n) + self.g0

    def closed(self, g_n, closed=1.0, open_=0.0):
        """The active set: ``closed`` where g_n ≤ 0, else ``open_``.

        The contact is taken as active at ``g_n = 0`` (``≤``), so that the Jacobian
        of a closed but unloaded interface is not singular.
        """
        return _ops(g_n, self.ε_n).where_closed(g_n, closed, open_)

    def pressure(self, g_n):
        """Penalty contact pressure p = ε_n ⟨−g_n⟩₊ (Pa; eq. 11 penalised, as in eq. 23)."""
        return self.ε_n * self.closed(g_n, -g_n, 0.0)

    def energy(self, g_n):
        """Energy density stored in the penalty, ½ ε_n ⟨−g_n⟩₊² = ½ p²/ε_n (J/m²)."""
        return 0.5 * self.pressure(g_n)**2 / self.ε_n


@dataclass(frozen=True)
class RegularisedCoulomb:
    """Regularised Coulomb friction: pressure and slip velocity → traction (eqs. 14-15).

    Attributes:
        μ: Friction coefficient (-); 0 for frictionless contact.
        χ: Regularisation velocity (m/s); χ → 0 recovers Coulomb's law.

    """

    μ: Any
    χ: Any

    @property
    def stick_band(self):
        """χ: below this slip speed the law is smooth (``|t_T| < μp/√2``).

        Newton's slip guard (:mod:`breakwater.contact.slipguard`) leaves steps that start
        inside the band alone.
        """
        return self.χ

    def direction(self, v_T):
        """Regularised sign of the slip velocity φ(v_T) = v_T / sqrt(|v_T|² + χ²) (eq. 15)."""
        op = _ops(v_T, self.χ)
        return op.divide(v_T, op.sqrt(op.dot(v_T, v_T) + self.χ**2))

    def traction(self, p, v_T):
        """Friction traction on the slave, t_T = −μ p φ(v_T) (Pa, eq. 14).

        Args:
            p: Contact pressure (Pa).
            v_T: Relative tangential velocity of slave on master (m/s).

        """
        return _ops(p, v_T, self.μ).scale(-self.μ * p, self.direction(v_T))

    def power(self, p, v_T):
        """Power dissipated per unit area, −t_T·v_T = μ p |v_T|²/sqrt(|v_T|² + χ²) ≥ 0."""
        return -_ops(p, v_T).dot(self.traction(p, v_T), v_T)


@dataclass(frozen=True)
class ContactLaw:
    """The interface law of a contact pair: a normal law and a friction law.

    Attributes:
        normal: Gap → pressure.
        friction: Pressure and slip velocity → tangential traction.

    """

    normal: PenaltyContact
    friction: RegularisedCoulomb

    @classmethod
    def of(cls, pair: Any, parameter=float) -> ContactLaw:
        """The law of a contact pair's parameters.

        Args:
            pair: Anything with the attributes ``penalty``, ``gap``, ``friction`` and
                ``regularisation`` (a :class:`breakwater.model.model.ContactPair`).
            parameter: Maps each value to the law's parameter, e.g. to a
                ``fem.Constant`` for forms.

        """
        return cls(PenaltyContact(parameter(pair.penalty), parameter(pair.gap)),
                   RegularisedCoulomb(parameter(pair.friction), parameter(pair.regularisation)))

    def values(self) -> ContactLaw:
        """The same law with float parameters (the ``fem.Constant`` s' values now).

        For nodal arrays: a ``fem.Constant`` parameter would take the UFL path.
        """
        return ContactLaw(_floats(self.normal), _floats(self.friction))

    def gap(self, u_s, u_m, n):
        """Normal gap g_n (eq. 7), see :meth:`PenaltyContact.gap`."""
        return self.normal.gap(u_s, u_m, n)

    def pressure(self, u_s, u_m, n):
        """Contact pressure p = ε_n ⟨−g_n⟩₊ of the displacements (eq. 11 penalised; eq. 23)."""
        return self.normal.pressure(self.gap(u_s, u_m, n))

    def traction(self, u_s, u_m, n, v_s=None, v_m=None):
        """Total interface traction on the slave, t_s = p n + t_T (Pa, eq. 23).

        Args:
            u_s: Slave displacement on the interface.
            u_m: Master displacement on the interface.
            n: Master outward unit normal.
            v_s: Slave velocity on the interface; None (with ``v_m``): frictionless,
                ``t_s = p n`` (statics).
            v_m: Master velocity on the interface.

        """
        p = self.pressure(u_s, u_m, n)
        op = _ops(u_s, u_m, n, p)
        if v_s is None or v_m is None:
            return op.scale(p, n)
        v_T = tangential_part(v_s - v_m, n)
        return op.scale(p, n) + self.friction.traction(p, v_T)


def contact_residual(t_s, w_s, w_m, dS: ufl.Measure) -> ufl.Form:
    """Contact contribution to the residual, −∫ t_s · (w_s − w_m) dS (eq. 23).

    The slave receives ``t_s`` and the master ``−t_s`` (action and reaction).
    """
    return -ufl.dot(t_s, w_s - w_m) * dS
