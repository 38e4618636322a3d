"""The fast path's interface unknowns: where each is held on each rank, and f_c on them.

The unknowns of the fast path's Newton (:mod:`breakwater.stepping.condensed`) are the
acceleration increments y = Δa_I at the contact-surface DOFs (global stacked indices,
sorted; :func:`~breakwater.stepping.bulk.interface_dofs`), the same array on every rank.
:class:`InterfaceUnknowns` maps them to the body Functions' local entries and to the
owned rows of the stacked vectors; :class:`ContactSum` evaluates the contact forces
f_c(y) and their Jacobian, summed over the providers (:class:`ContactForces`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Protocol

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater.common.jit import kernel
from breakwater.common.timings import Timings
from breakwater.contact.coupling import BulkStiffness
from breakwater.model.layout import MonolithicLayout

__all__ = ["BodyGuard", "ContactFactory", "ContactForces", "ContactSum", "Guard",
           "InterfaceUnknowns", "StateForces", "StateProvider", "coupled"]

#: A provider's slip guard ``guard(x, step, v_pred, dv_dx, bulk) -> corrected``
#: (:meth:`ContactForces.precheck`).
Guard = Callable[[np.ndarray, np.ndarray, np.ndarray, float, BulkStiffness | None], int]


class ContactForces(Protocol):
    """Contact forces on the interface unknowns, a part of f_c (summed over providers).

    Evaluated at an iterate y of the interface unknowns (the step's Δa there), the
    state at t staged; the arrays are the same on every rank. :meth:`begin` is called
    once per step before the Newton (collective), the others per Newton iteration (on
    every rank together).
    """

    def begin(self) -> None:
        """Take the staged step's state (u, v, a at t, Δt, the staged Δa)."""
        ...

    def end(self) -> None:
        """The step's Newton is done (converged or not)."""
        ...

    def add_vector(self, y: np.ndarray, out: np.ndarray) -> None:
        """Add f_c(y) on the interface unknowns, shape ``(n_I,)``, to ``out``."""
        ...

    def add_left_product(self, y: np.ndarray, X: np.ndarray, out: np.ndarray) -> bool:
        """Add X ∂f_c/∂y to ``out`` from the provider's own structure (sparse, nodal).

        Returns:
            False where there is no structure to use (nothing added): the caller then
            forms ``X @ matrix(y)``, summed with the other such providers' first.
        """
        ...

    def matrix(self, y: np.ndarray) -> np.ndarray:
        """∂f_c/∂y on the interface unknowns, dense, shape ``(n_I, n_I)``."""
        ...

    def resolution(self, y: np.ndarray) -> float:
        """The round-off of f_c(y): a residual below it is converged (0: none known)."""
        ...

    def active_jacobian(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """∂f_c/∂y as ``(act, A)``: nonzero only in rows and columns ``act``, there A.

        None where the provider has no such form (then :meth:`add_left_product` or
        :meth:`matrix`).
        """
        ...

    def precheck(self, x: np.ndarray, step: np.ndarray, v_pred: np.ndarray,
                 dv_dx: float, bulk: BulkStiffness | None = None) -> int:
        """The provider's slip guard on Newton's step (next iterate ``x − step``).

        ``v_pred + dv_dx x`` are the iterate's velocities; ``step`` is cut in place. The
        guard acts at the nodes whose friction law holds their slip against the bulk's
        stiffness ``bulk`` (:mod:`breakwater.contact.coupling`; None: at every node).

        Returns:
            The nodes corrected (0: ``step`` untouched).
        """
        ...

    def true_law(self, crawl: bool = True) -> bool:
        """The next iterates' forces from the law itself, not from the guard's tangent lines.

        A general pair's guard may linearise a node's law at a crawl point
        (:mod:`breakwater.contact.guardkernels`) for the next iterates; ``crawl``: whether
        it may set new ones (not in a rescue, :class:`~breakwater.stepping.interfacenewton.
        InterfaceNewton`).

        Returns:
            Whether the last iterate's were not (the Newton then tests it again).
        """
        ...

    def regularise(self, stretch: float) -> bool:
        """The next evaluations' friction law with its regularisation χ times ``stretch``.

        1: the law's own χ again. The interface Newton's continuation
        (:mod:`breakwater.stepping.continuation`).

        Returns:
            Whether the provider has a friction law that this changes.
        """
        ...


class StateProvider(Protocol):
    """Contact forces evaluated at the state Functions (Δa holding the iterate)."""

    def begin_step(self) -> None:
        """The Newton of a step starts (u, v, a fixed until :meth:`end_step`)."""
        ...

    def at(self, y: np.ndarray) -> bool:
        """The iterate of the next evaluations; True: taken as it is (Δa need not hold it)."""
        ...

    def end_step(self) -> None:
        """The Newton of the step is done."""
        ...

    def vector(self) -> np.ndarray:
        """f_c on the interface unknowns."""
        ...

    def left_product(self, X: np.ndarray) -> np.ndarray | None:
        """X ∂f_c/∂y from the provider's structure, or None."""
        ...

    def matrix(self) -> np.ndarray:
        """∂f_c/∂y on the interface unknowns, dense."""
        ...

    def resolution(self, y: np.ndarray) -> float:
        """The round-off of ``vector()`` at Δa = y (0: none known)."""
        ...

    def active_jacobian(self) -> tuple[np.ndarray, np.ndarray] | None:
        """``matrix()`` as ``(act, A)`` on the unknowns it couples, or None."""
        ...


class StateForces:
    """A :class:`ContactForces` of a provider that reads the state Functions.

    Each evaluation writes y into Δa first (the provider assembles forms or projects
    points at the state: :class:`~breakwater.stepping.condensed.InterfaceAssembler`,
    :class:`~breakwater.contact.general.SurfaceContact`).

    Args:
        provider: The provider.
        interface: The interface unknowns.
        da: The step's unknown Δa, one Function per body.
        guard: The provider's slip guard (:data:`Guard`), or None.
    """

    def __init__(self, provider: StateProvider, interface: InterfaceUnknowns,
                 da: Sequence[fem.Function],
                 guard: Guard | None = None) -> None:
        self.provider, self.interface, self.da = provider, interface, da
        self.guard = guard

    def begin(self) -> None:
        """The provider's :meth:`StateProvider.begin_step` (collective)."""
        self.provider.begin_step()

    def end(self) -> None:
        """The provider's :meth:`StateProvider.end_step`; its law itself from now on."""
        self.provider.end_step()
        self.true_law()

    def _set(self, y: np.ndarray) -> None:
        """The iterate y for the provider: given, or written into Δa."""
        if not self.provider.at(y):
            self.interface.write(self.da, y)

    def add_vector(self, y: np.ndarray, out: np.ndarray) -> None:
        """Add the provider's ``vector()`` at Δa = y."""
        self._set(y)
        out += self.provider.vector()

    def add_left_product(self, y: np.ndarray, X: np.ndarray, out: np.ndarray) -> bool:
        """Add the provider's ``left_product(X)`` at Δa = y, if it has one."""
        self._set(y)
        product = self.provider.left_product(X)
        if product is None:
            return False
        out += product
        return True

    def matrix(self, y: np.ndarray) -> np.ndarray:
        """The provider's ``matrix()`` at Δa = y."""
        self._set(y)
        return self.provider.matrix()

    def resolution(self, y: np.ndarray) -> float:
        """The provider's ``resolution(y)``."""
        self._set(y)
        return self.provider.resolution(y)

    def active_jacobian(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The provider's ``active_jacobian()`` at Δa = y."""
        self._set(y)
        return self.provider.active_jacobian()

    def precheck(self, x: np.ndarray, step: np.ndarray, v_pred: np.ndarray,
                 dv_dx: float, bulk: BulkStiffness | None = None) -> int:
        """The provider's guard, if any."""
        return self.guard(x, step, v_pred, dv_dx, bulk) if self.guard is not None else 0

    def true_law(self, crawl: bool = True) -> bool:
        """The provider's ``true_law(crawl)``, if it has one (a general pair)."""
        law = getattr(self.provider, "true_law", None)
        return bool(law(crawl)) if law is not None else False

    def regularise(self, stretch: float) -> bool:
        """The provider's ``regularise(stretch)``, if it has one (a general pair)."""
        regularise = getattr(self.provider, "regularise", None)
        return bool(regularise(stretch)) if regularise is not None else False

    def reach(self) -> np.ndarray | None:
        """The provider's ``reach()``, if it has one; None: any unknown.

        The interface unknowns its forces may touch in this step
        (:meth:`breakwater.contact.general.SurfaceForces.reach`).
        """
        reach = getattr(self.provider, "reach", None)
        return None if reach is None else reach()


class BodyGuard:
    """A slip guard on local body arrays as a guard on the interface unknowns.

    The conforming pairs' :class:`~breakwater.contact.slipguard.SlipGuard` works on local
    body arrays: the iterate's velocities ``v_pred + dv_dx x`` and the step are written
    at the interface entries, the only ones the guard reads, and the step is read back
    where the guard cut it (for the assembled provider; the nodal providers guard on the
    interface unknowns themselves).

    Args:
        guard: ``guard(v, step, dv_dx) -> corrected`` on local body arrays.
        interface: The interface unknowns.
        layout: The stacked-vector layout.
        da: The step's unknown Δa, one Function per body (the arrays' shapes).
    """

    def __init__(self, guard: Callable[[Sequence[np.ndarray], Sequence[np.ndarray], float],
                                       int], interface: InterfaceUnknowns,
                 layout: MonolithicLayout, da: Sequence[fem.Function]) -> None:
        self.guard, self.interface, self.layout = guard, interface, layout
        self._arrays = [[np.zeros_like(f.x.array) for f in da] for _ in range(2)]

    def __call__(self, x: np.ndarray, step: np.ndarray, v_pred: np.ndarray,
                 dv_dx: float, bulk: BulkStiffness | None = None) -> int:
        """Cut ``step`` in place; the nodes corrected (at every node: ``bulk`` unused)."""
        velocity = v_pred + dv_dx * x
        v_arrays, step_arrays = self._arrays
        for va, sa, (local, pos) in zip(v_arrays, step_arrays, self.interface.positions,
                                        strict=True):
            va[local] = velocity[pos]
            sa[local] = step[pos]
        corrected = self.guard(v_arrays, step_arrays, dv_dx)
        if corrected:
            owned = np.concatenate([sa[:n] for sa, n in zip(step_arrays, self.layout.sizes,
                                                            strict=True)])
            step[:] = self.interface.gather(owned)[0]
        return corrected


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

    Args:
        n: Number of interface unknowns.
        providers: The contact-force providers (the list is read at each evaluation).
        timings: Where the evaluations are timed (``interface_assembly``).
    """

    def __init__(self, n: int, providers: Sequence[ContactForces], timings: Timings) -> None:
        self.n = n
        self.providers = providers
        self.timings = timings

    @property
    def primal(self) -> bool:
        """Whether every provider's Newton solves for δ itself (the conforming pairs)."""
        return all(getattr(c, "primal", False) for c in self.providers)

    def begin(self) -> None:
        """Every provider takes the staged step's state (collective)."""
        with self.timings("interface_assembly"):
            for c in self.providers:
                c.begin()

    def end(self) -> None:
        """Every provider: the step's Newton is done."""
        for c in self.providers:
            c.end()

    def vector(self, y: np.ndarray) -> np.ndarray:
        """f_c(y) on the interface unknowns (the same on every rank)."""
        with self.timings("interface_assembly"):
            out = np.zeros(self.n)
            for c in self.providers:
                c.add_vector(y, out)
            return out

    def left_jacobian(self, y: np.ndarray, X: np.ndarray) -> np.ndarray:
        """X ∂f_c/∂y on the interface unknowns (the same on every rank).

        A provider with structure adds its product; the others' dense matrices are
        summed and multiplied once.
        """
        out = np.zeros((X.shape[0], self.n))
        dense: np.ndarray | None = None
        with self.timings("interface_assembly"):
            for c in self.providers:
                if not c.add_left_product(y, X, out):
                    m = c.matrix(y)
                    dense = m if dense is None else dense + m
        if dense is not None:
            out += X @ dense
        return out

    def active_jacobian(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """∂f_c/∂y as ``(act, A)`` (rows and columns ``act``), if every provider has it.

        The providers' active unknowns joined, their blocks summed, less the unknowns
        the block does not couple (:func:`coupled`); None if one has no such form (the
        Newton then forms the whole ``X ∂f_c/∂y``).
        """
        parts = []
        with self.timings("interface_assembly"):
            for c in self.providers:
                part = c.active_jacobian(y)
                if part is None:
                    return None
                parts.append(part)
            if len(parts) == 1:
                return coupled(*parts[0])
            act = np.unique(np.concatenate([p[0] for p in parts]))
            A = np.zeros((len(act), len(act)))
            for a, block in parts:
                at = np.searchsorted(act, a)
                A[np.ix_(at, at)] += block
            return coupled(act, A)

    def jump_jacobian(self, y: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """∂f_c/∂y as node tangents ``(W, slave, master)`` of every provider's nodes.

        :mod:`breakwater.stepping.jumpsystem`'s form; None if a provider has none.
        """
        if not self.providers or not all(hasattr(c, "jump_jacobian") for c in self.providers):
            return None
        with self.timings("interface_assembly"):
            parts = [c.jump_jacobian(y) for c in self.providers]  # type: ignore[attr-defined]
        if len(parts) == 1:
            return parts[0]
        return tuple(np.concatenate(p) for p in zip(*parts, strict=True))  # type: ignore

    def reach(self) -> np.ndarray | None:
        """The interface unknowns the providers' forces may touch in this step.

        The union of the providers' ``reach()``; None (any) if one has none.
        """
        parts = []
        for c in self.providers:
            part = getattr(c, "reach", lambda: None)()
            if part is None:
                return None
            parts.append(part)
        if len(parts) == 1:
            return parts[0]
        return np.unique(np.concatenate(parts)) if parts else None

    def resolution(self, y: np.ndarray) -> float:
        """The round-off of f_c(y), over the providers (root sum of squares)."""
        with self.timings("interface_assembly"):
            return math.sqrt(sum(c.resolution(y) ** 2 for c in self.providers))

    def precheck(self, x: np.ndarray, step: np.ndarray, v_pred: np.ndarray,
                 dv_dx: float, bulk: BulkStiffness | None = None) -> int:
        """Every provider's slip guard, in turn, on the step; the nodes corrected."""
        return sum(c.precheck(x, step, v_pred, dv_dx, bulk) for c in self.providers)

    def true_law(self, crawl: bool = True) -> bool:
        """Every provider's :meth:`ContactForces.true_law`; whether any's was not."""
        return any([c.true_law(crawl) for c in self.providers])

    def regularise(self, stretch: float) -> bool:
        """Every provider's :meth:`ContactForces.regularise`; whether any has friction."""
        return any([c.regularise(stretch) for c in self.providers])


@kernel
def coupled(act, B):  # type: ignore[no-untyped-def]
    """``(act, B)`` without the unknowns whose row and column of B are zero (compiled).

    A provider's ``act`` may hold unknowns whose rows and columns are zero (a
    general pair's friction node or closed point whose tangents vanish there); the
    Newton step's force there is zero too (``w = B δ``): solving without them gives
    the same step, with a smaller dense solve, and a Newton on the unknowns a general
    pair may reach (:class:`breakwater.stepping.reach.NearContact`) does not count
    them as reached.

    Args:
        act: The unknowns of a provider's block, shape (m,).
        B: ∂f_c/∂y on ``act``, shape (m, m).
    """
    m = len(act)
    keep = np.zeros(m, np.bool_)
    for i in range(m):
        for j in range(m):
            if B[i, j] != 0.0:
                keep[i] = True
                keep[j] = True
    index = np.flatnonzero(keep)
    if len(index) == m:
        return act, B
    out = np.empty((len(index), len(index)))
    for a in range(len(index)):
        for b in range(len(index)):
            out[a, b] = B[index[a], index[b]]
    return act[index], out
