"""Whether a general pair's meshes start apart, the static state closing the gap.

:func:`meshed_gap3d` and :func:`meshed_gap2d` warn of it (one line, the same text), as
:func:`breakwater.contact.penetration.meshed_overlap` (2-D) and
:meth:`breakwater.contact.general3d.SurfaceContact3D.static_check` warn of an overlap.
"""

from __future__ import annotations

import numpy as np

from breakwater.common.arrays import first_by_position
from breakwater.contact.general import SurfaceContact
from breakwater.contact.general3d import SurfaceContact3D, nodal_gaps
from breakwater.contact.penetration import OVERLAP, meshed_gaps
from breakwater.model.pairs import facet_size

__all__ = ["meshed_gap2d", "meshed_gap3d"]


def meshed_gap3d(contact: SurfaceContact3D) -> str | None:
    """A warning where a 3-D general pair's meshes start apart, the static state closing it.

    Collective: call it on every rank, after the stepper's initialise.

    Every slave node that projects onto the master as meshed lies off it by more than
    :data:`OVERLAP` of the face under it, and the pair carries a force in the static
    state: the bodies moved together by the gap as rigid bodies, silently before, so
    that their displacements, the settlement and the penalty's quality check include it
    (a block meshed 10 mm above its slab: the check said "ok" where the block meshed on
    the slab said "too soft"), as :func:`breakwater.contact.penetration.meshed_overlap` warns of an
    overlap.

    Returns:
        One line (the nearest slave node and its gap), the same on every rank; None
        when a node starts on the master, none projects, or the pair carries nothing.
    """
    carried = bool(np.any(contact.resultant() != 0.0))
    X = np.ascontiguousarray(contact.node_X)
    gap, facet, _ = nodal_gaps(contact, X, contact._mX)
    on = np.flatnonzero(facet >= 0)
    if not carried or not len(on):
        return None
    size = facet_size(contact._mX[facet[on], :3])
    if np.any(gap[on] <= OVERLAP * size):
        return None
    k = first_by_position(X, on[gap[on] <= gap[on].min() + 1e-9 * size.max()])  # the nearest
    return _apart(contact.spec.name, contact.spec.master, X[k], float(gap[k]))


def meshed_gap2d(contact: SurfaceContact) -> str | None:
    """:func:`meshed_gap3d` of a 2-D general pair (collective, after the initialise).

    Every slave node that projects onto the master's surface within the search radius
    (:func:`~breakwater.contact.penetration.meshed_gaps`) lies off it by more than
    :data:`OVERLAP` of the facet under it, and the pair carries a force in the static
    state. Before, a 2-D block meshed 2 mm above its base dropped onto it in the static
    state without a word (the 3-D pair warned).

    Collective through the pair's resultant only: the gaps are measured on the surfaces
    the pair gathered when it was built (on every rank), and not at all when the pair
    carries nothing (before, both surfaces were gathered again at every call).

    Returns:
        One line, the same on every rank; None otherwise.
    """
    if not np.any(contact.resultant() != 0.0):
        return None
    found = meshed_gaps(contact.slave, contact.master, contact.radius)
    if found is None:
        return None
    X, gap, length = found
    on = np.flatnonzero(np.isfinite(gap))
    if not len(on) or np.any(gap[on] <= OVERLAP * length[on]):
        return None
    k = first_by_position(X, on[gap[on] <= gap[on].min() + 1e-9 * length.max()])
    return _apart(contact.spec.name, contact.spec.master, X[k], float(gap[k]))


def _apart(name: str, master: str, x: np.ndarray, gap: float) -> str:
    """The warning of :func:`meshed_gap3d` and :func:`meshed_gap2d`."""
    at = ", ".join(f"{c:.4g}" for c in x)
    return (f"contact '{name}': the meshes start apart: the slave's nearest "
            f"node, at ({at}) m, is {gap:.3g} m off the master "
            f"'{master}', and the static state closed the gap: the bodies "
            "moved together by it, and the displacements, the settlement and the "
            "penalty's quality check include it: mesh the bodies in contact")
