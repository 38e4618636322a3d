"""The step solver a run takes: the condensed one while its dense interface fits.

The fast solver (:mod:`breakwater.stepping.condensed`) eliminates the bulk once per Δt and
runs Newton on the n_I interface unknowns, with dense n_I × n_I matrices on every rank:
X_II and S = X_II⁻¹ of the factorisation, the round-off estimate's |X_II| and |S|, and the
Newton's systems on the closed unknowns (with their LU copies). Their memory grows as
n_I² per rank (every rank holds them), faster than the sparse factors. The full-system
Newton (``"reference"``, :class:`~breakwater.stepping.solver.NewtonSolver`: SNES on the
whole residual, the contact terms in its Jacobian, a sparse LU per iteration) holds
sparse matrices only, but factorises at every Newton iteration: on ``goda3d`` at
refinement 1 it took 81.5 times the fast solver's CPU time per step
(benchmarks/records/2026-11-29-solver-choice.md), and n_I back-solves per Δt (the fast
path's X) cost less than its factorisations per step at every size measured. An iterative
full system (GMRES and GAMG, the interface's tangential unknowns rotated into their pairs'
mean and difference) failed at the 13th step of ``goda3d`` at refinement 1, took 5 times
MUMPS's CPU time per Newton iteration over the 12 before (rising with the slip) and 3.3
times per linear system at refinement 2, with less memory there (0.5 against 4.2 GB;
record 2026-11-29-iterative-full-system): it is not offered (the sizes where "auto"
switches, n_I of 9000 and more, were not measured). So the choice is by memory, not time:
``time.solver = "auto"`` (the default) takes ``"fast"`` unless :data:`DENSE_COPIES` × 8
n_I² bytes per rank exceed :data:`DENSE_MEMORY` of a node's available memory, and then
``"reference"``, with one warning line. General pairs have no full-system solver (their
forces are not UFL forms): where theirs does not fit the run is refused in one line,
before the static state.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from breakwater.common.errors import BreakwaterError
from breakwater.common.memory import available_bytes, fits
from breakwater.model.layout import MonolithicLayout
from breakwater.stepping.bulk import interface_dofs

if TYPE_CHECKING:
    from breakwater.model.model import ContactModel

__all__ = ["DENSE_COPIES", "DENSE_MEMORY", "Choice", "choose", "dense_bytes"]

DENSE_COPIES = 8
"""n_I × n_I arrays of doubles the fast solver holds per rank at its peak, counted from the
code (X_II, S, |X_II| and |S|, a Newton system and its LU copy, the inverse's workspace)
and measured: numpy's traced peak in the fast solver over its first steps on ``goda3d``
(benchmarks/solver_choice.py, record 2026-11-29-solver-choice)."""

DENSE_MEMORY = 0.5
"""The share of a node's available memory the ranks' dense interface matrices may take
(as :attr:`~breakwater.stepping.elimination.Elimination.X_MEMORY` for X)."""

Choice = tuple[str, str | None]
"""The solver (``"fast"`` or ``"reference"``) and, where ``"auto"`` took the reference
solver, the line that says why."""


def dense_bytes(n_interface: int) -> float:
    """The fast solver's dense interface matrices per rank (bytes), :data:`DENSE_COPIES`."""
    return DENSE_COPIES * 8.0 * n_interface**2


def choose(model: ContactModel, requested: str, available: float | None = None) -> Choice:
    """The solver a run takes for ``time.solver = requested`` (collective).

    Args:
        model: The contact model.
        requested: ``"fast"``, ``"reference"`` or ``"auto"``.
        available: A node's available memory (bytes; None: measured,
            :func:`~breakwater.common.memory.available_bytes`; a test sets it).

    Returns:
        The solver and, where ``"auto"`` chose the reference solver, its warning line.

    Raises:
        BreakwaterError: ``"auto"`` with general pairs whose dense interface does not fit.
    """
    if requested != "auto":
        return requested, None
    if not (model.pairs or model.surface_pairs):
        return "fast", None
    n = len(interface_dofs(model, MonolithicLayout(model)))
    need = dense_bytes(n)
    if fits(model.comm, need, DENSE_MEMORY, available):
        return "fast", None
    have = available_bytes() if available is None else available
    room = "unknown" if have is None else f"{have / 1e9:.3g} GB"
    what = (f"the fast solver's dense interface matrices ({n} interface unknowns: "
            f"{need / 1e9:.3g} GB on each rank) do not fit in {DENSE_MEMORY:.0%} of this "
            f"node's available memory ({room}, shared by its ranks)")
    if model.surface_pairs:
        raise BreakwaterError(f"{what}, and general contact pairs have no other solver: "
                              "run fewer ranks per node (each holds them) or on a node with "
                              "more memory, or mesh the contact surfaces coarser")
    return "reference", (f"time.solver = \"auto\": {what}: the full-system Newton "
                         "(\"reference\": a sparse LU per Newton iteration, much slower per "
                         "step) instead")
