"""The fast path's interface unknowns: where each is held on each rank, and f_c on them.

The unknowns of the fast path's Newton (:mod:`breakwater.stepping.condensed`) are the
acceleration increments y = Δa_I at the contact-surface DOFs (global stacked indices,
sorted; :func:`~breakwater.stepping.bulk.interface_dofs`), the same array on every rank.
:class:`InterfaceUnknowns` maps them to the body Functions' local entries and to the
owned rows of the stacked vectors; :class:`ContactSum` evaluates the contact forces
f_c(y) and their Jacobian, summed over the providers (:class:`ContactForces`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Protocol

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater.common.timings import Timings
from breakwater.model.layout import MonolithicLayout

__all__ = ["ContactFactory", "ContactForces", "ContactSum", "InterfaceUnknowns"]


class ContactForces(Protocol):
    """Contact forces on the interface unknowns, a part of f_c (summed over providers).

    Evaluated at the state Functions (u, v, a at t and the step's Δa, which
    :class:`ContactSum` sets before calling); both arrays are the same on every rank.
    """

    def vector(self) -> np.ndarray:
        """f_c on the interface unknowns, shape ``(n_I,)``."""
        ...

    def matrix(self) -> np.ndarray:
        """∂f_c/∂y on the interface unknowns, dense, shape ``(n_I, n_I)``."""
        ...

    def left_product(self, X: np.ndarray) -> np.ndarray | None:
        """X ∂f_c/∂y from the provider's own structure (sparse, nodal), or None.

        None: :class:`ContactSum` forms ``X @ matrix()``, summed with the other such
        providers' matrices first (one product).
        """
        ...


#: Builds the contact-force providers of a model from its stacked layout and the
#: interface unknowns (global stacked indices, sorted).
ContactFactory = Callable[[MonolithicLayout, np.ndarray], Sequence[ContactForces]]


class InterfaceUnknowns:
    """Where the interface unknowns are held on this rank.

    Args:
        layout: The stacked-vector layout.
        indices: Global stacked indices of the interface unknowns (sorted).

    Attributes:
        I: The global stacked indices.
        n: Their number.
        positions: Per body, (local DOFs, interface positions) of the unknowns this rank
            holds (owned or ghost).
        owned: Which interface unknowns this rank owns (a mask of length n).
        owned_rows: Their rows in the owned part of a stacked vector.
    """

    def __init__(self, layout: MonolithicLayout, indices: np.ndarray) -> None:
        self.comm = layout.comm
        self.I = indices
        self.n = n = len(indices)
        self.positions = []
        for gi in layout.global_index:
            pos = np.minimum(np.searchsorted(self.I, gi), max(n - 1, 0))
            hit = (self.I[pos] == gi) if n else np.zeros(len(gi), bool)
            self.positions.append((np.flatnonzero(hit), pos[hit]))
        start, n_local = layout.start, layout.offsets[-1]
        self.owned = (self.I >= start) & (self.I < start + n_local)
        self.owned_rows = self.I[self.owned] - start

    def write(self, functions: Sequence[fem.Function], y: np.ndarray) -> None:
        """Write y into one Function per body at every interface entry this rank holds."""
        for f, (local, pos) in zip(functions, self.positions, strict=True):
            f.x.array[local] = y[pos]

    def add(self, functions: Sequence[fem.Function], y: np.ndarray) -> None:
        """Add y to one Function per body at every interface entry this rank holds."""
        for f, (local, pos) in zip(functions, self.positions, strict=True):
            f.x.array[local] += y[pos]

    def gather(self, *owned: np.ndarray) -> list[np.ndarray]:
        """Owned stacked arrays at the interface unknowns, on every rank (one reduction)."""
        out = np.zeros((len(owned), self.n))
        for row, arr in zip(out, owned, strict=True):
            row[self.owned] = arr[self.owned_rows]
        self.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        return list(out)


class ContactSum:
    """f_c(y) and its Jacobian on the interface unknowns, summed over the providers.

    Each evaluation writes y into Δa first (the providers read the state Functions).

    Args:
        interface: The interface unknowns.
        da: The step's unknown Δa, one Function per body.
        providers: The contact-force providers (the list is read at each evaluation).
        timings: Where the evaluations are timed (``interface_assembly``).
    """

    def __init__(self, interface: InterfaceUnknowns, da: Sequence[fem.Function],
                 providers: Sequence[ContactForces], timings: Timings) -> None:
        self.interface, self.da = interface, da
        self.providers = providers
        self.timings = timings

    def set(self, y: np.ndarray) -> None:
        """Write y into Δa at every interface entry this rank holds."""
        self.interface.write(self.da, y)

    def vector(self, y: np.ndarray) -> np.ndarray:
        """f_c(y) on the interface unknowns (the same on every rank)."""
        with self.timings("interface_assembly"):
            self.set(y)
            out = self.providers[0].vector()
            for c in self.providers[1:]:
                out = out + c.vector()
            return out

    def left_jacobian(self, y: np.ndarray, X: np.ndarray) -> np.ndarray:
        """X ∂f_c/∂y on the interface unknowns (the same on every rank).

        A provider whose ``left_product(X)`` gives the product (from its matrix's
        structure) adds it; the others (``None``) add their dense matrices, multiplied once.
        """
        n = self.interface.n
        out = np.zeros((n, n))
        dense: np.ndarray | None = None
        with self.timings("interface_assembly"):
            self.set(y)
            for c in self.providers:
                product = c.left_product(X)
                if product is not None:
                    out += product
                else:
                    m = c.matrix()
                    dense = m if dense is None else dense + m
        if dense is not None:
            out += X @ dense
        return out
