"""The interface Newton's continuation in the friction law's regularisation χ.

The regularised Coulomb law ``φ(c) = c / sqrt(|c|² + χ²)`` with the paper's χ = 1e-10 m/s
is a sign function at any slip velocity a step resolves: its force turns from −μλ to
+μλ across a slip velocity of a few χ. Where a slave surface is finer than its master
(a general pair's slave nodes, several on one master facet, coupled through it), the
nodes at a stick/slip boundary take their stick or slip state from each other, and
Newton with the slip guards (:mod:`breakwater.contact.guardkernels`) may cycle between
patterns of them: on Goda's caisson of 6 mm elements on a mound of 30 mm ones
(``examples/goda_apart/goda_apart.geo`` with those sizes), as the base starts sliding at
t ≈ 0.052 s, a cluster of ten neighbouring slave nodes with slip velocities of 1e-6 to
1e-4 m/s went round a cycle of ten iterates, the residual repeating to four digits
(12 → 1.5e3 → 51 → 30 → 45 → 37 → 36 → 2.4e2 → 44 → 39 → 12 → ...), in the first
try and in the rescue with halved steps alike; five steps were cut back to 0.06 s. A
line search on ‖F‖ does not help: along Newton's direction ‖F‖ falls as predicted over
1e-4 of the step and has grown 3–50 times at 1e-2 of it, the law's kink within.

With χ larger the law is smooth at those velocities and Newton converges; from that
solution, a Newton on a χ ten times smaller starts where the law's states have moved
little, and so on down to the law's own χ, whose solve is tested as any other (the
accepted state is a solution of the law itself; the stages are only the way there). On
the case above every step converged, no cut-back (five before). The first stage's χ,
:data:`TOP`, was chosen by the Newton iterations of that case's whole run (1500 steps,
31 solves continued, every headline digit the same): 8530 from 1e6 χ, 8159 from 1e5,
7931 from 1e4, 7993 from 1e3, 8005 from 1e2 (the stages from 1e6 χ took 5–14
iterations at the first and as many at the next two, whose smaller χ each started
far from their solution); ten times apart, 7931, against 8183 at 30 and 8117 at 5.

:func:`solve` is the interface Newton's first rescue (before the halved steps of
:func:`~breakwater.stepping.interfacenewton.damped_step`): a first stage that does not
converge is tried again from Newton's start with χ :data:`RAISE` times larger (up to
:data:`CEILING` times the law's); a later stage that does not converge is tried again
halfway (in log χ) between the last converged χ and the one that failed, until the
stages are closer than :data:`FINEST`, or after :data:`MAX_STAGES`. Conforming pairs do
not take part: their nodes' slips, each on one master node, converge with the slip guard
alone (their providers' ``regularise`` changes nothing, and then :func:`solve` is not
tried).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from breakwater.stepping.interface import ContactSum

__all__ = ["CEILING", "DECADE", "FINEST", "MAX_STAGES", "RAISE", "TOP", "Stages", "solve"]

#: The first stage's χ, as a multiple of the law's: 1e-6 m/s for the paper's χ, within
#: the slip velocities of the stick/slip boundary measured in the module doc (chosen by
#: measurement, the module doc; a first stage that fails is raised by :data:`RAISE`).
TOP = 1e4
#: A first stage that fails is tried again with χ this many times larger...
RAISE = 100.0
#: ... up to this multiple of the law's χ.
CEILING = 1e10
#: Each stage's χ is this many times smaller than the last (at most).
DECADE = 10.0
#: A stage that fails is tried again halfway (in log χ) to the last converged one, until
#: the ratio of their χ falls below this.
FINEST = 1.5

#: At most this many stages (a stage that fails in a cycle costs a few iterations,
#: :func:`~breakwater.stepping.interfacenewton.cycle`; one that converges, a few more).
MAX_STAGES = 50

#: One Newton solve from a start: (its convergence reason, residual norms, (y, f_c, F)).
Iterate = Callable[[np.ndarray], tuple[int, list[float], tuple[np.ndarray, ...]]]


class Stages:
    """What a continuation did: its stages' χ multiples and iterations.

    Attributes:
        stretches: The χ multiple of each stage tried, in order.
        iterations: Newton iterations over all stages.
    """

    def __init__(self) -> None:
        self.stretches: list[float] = []
        self.iterations = 0

    def describe(self) -> str:
        """The stages in one phrase (for a failed solve's message)."""
        n = len(self.stretches)
        if not n:
            return "no stage"
        return (f"{n} stage{'s' if n > 1 else ''} from {self.stretches[0]:.0e} χ to "
                f"{self.stretches[-1]:.3g} χ, {self.iterations} iterations")


def solve(iterate: Iterate, contact: ContactSum, y0: np.ndarray
          ) -> tuple[int, list[float], tuple[np.ndarray, ...], Stages]:
    """Newton on the law's own χ, reached by stages of larger χ (the module doc).

    Args:
        iterate: A Newton solve from a start, at the providers' current χ.
        contact: The providers (:meth:`ContactSum.regularise`); put back at their own χ
            whatever happens.
        y0: Newton's start.

    Returns:
        The last stage's reason (> 0: converged, at the law's own χ), residual norms and
        (y, f_c, F); the stages.
    """
    stages = Stages()

    def stage(stretch: float, y: np.ndarray) -> tuple[int, list[float], tuple[np.ndarray, ...]]:
        contact.regularise(stretch)
        reason, norms, state = iterate(y)
        stages.stretches.append(stretch)
        stages.iterations += len(norms) - 1
        return reason, norms, state

    try:
        stretch = TOP
        while True:  # the first stage, from Newton's start
            reason, norms, state = stage(stretch, y0)
            if reason > 0 or stretch * RAISE > CEILING:
                break
            stretch *= RAISE
        ratio = DECADE
        while reason > 0 and stretch > 1.0 and len(stages.stretches) < MAX_STAGES:
            y = state[0]
            target = stretch / ratio if stretch / ratio >= FINEST else 1.0
            reason, norms, state = stage(target, y)
            if reason > 0:
                stretch = target
            elif ratio > FINEST:
                ratio = math.sqrt(ratio)
                reason, state = 1, (y,)  # again from the last converged stage
        if stretch > 1.0:  # out of stages
            reason = min(reason, 0)
        return reason, norms, state, stages
    finally:
        contact.regularise(1.0)
