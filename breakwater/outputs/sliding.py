"""Whether a conforming pair slid beyond what node-to-node contact holds.

A conforming pair holds each slave node to the master node it faced in the mesh: valid
while the slip is small against the interface's element size h. The Goda caisson without
friction slid 21 mm on its 29 mm elements (0.73 h), silently: past that the pressure
acts on the master nodes the slave has left, and a slave node past the master's end
keeps its partner. Sliding that far needs a general pair (bodies meshed apart, finite
sliding: ``examples/goda_apart``).
"""

from __future__ import annotations

from collections.abc import Sequence

from dolfinx import fem

from breakwater.contact.pairstate import ConformingPair
from breakwater.model.pairs import Pair
from breakwater.outputs.quality import PairInputs

__all__ = ["SMALL_SLIDING", "sliding_warnings"]

SMALL_SLIDING = 0.1
"""A conforming pair's slip is small against its element size h below this fraction."""


def sliding_warnings(pairs: Sequence[Pair], u: Sequence[fem.Function],
                     inputs: Sequence[PairInputs]) -> list[str]:
    """One line per conforming pair whose nodes slipped beyond :data:`SMALL_SLIDING` h.

    At the state ``u`` (the run's last: the slip a slide leaves; collective).

    Args:
        pairs: The stepper's pairs (general ones are skipped: they hold finite sliding).
        u: The state (one Function per body).
        inputs: The pairs' quality inputs (their mean interface facet length h).
    """
    h = {q.name: q.element_size for q in inputs}
    out = []
    for pair in pairs:
        if not isinstance(pair, ConformingPair) or not h.get(pair.name):
            continue
        slip, size = pair.largest_slip(u), h[pair.name]
        if slip > SMALL_SLIDING * size:
            out.append(f"contact '{pair.name}': its nodes slipped up to {slip:.3g} m, "
                       f"{slip / size:.2g} of its element size h = {size:.3g} m: a conforming "
                       "(node-to-node) pair holds only slips small against h (past "
                       f"{SMALL_SLIDING:g} h the results are not reliable); mesh the bodies "
                       "apart with a general pair for finite sliding (a [contact.<pair>] with "
                       "slave_surface and master_surface; the manual's general contact page)")
    return out
