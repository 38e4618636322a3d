"""Whether a general pair's slave surface faces its master surface at all (t = 0).

A general pair (:mod:`breakwater.contact.general`) presses a slave point onto the master
surface in front of it. A slave surface named by mistake (the caisson's top or its rear
face for its base: a group that exists, on the right body, of the right dimension) has
no master in front of it: the bodies could touch only through each other. Before this
check such a pair ran: with the caisson's top as the slave surface the static state
sank the caisson through its mound until its top met the crest, exit 0, a settlement of
0.1 m; with its rear face the run ended "no static equilibrium". :func:`facing` refuses
it before the static state, naming the key and the slave body's groups that do face the
master.

A slave facet *faces* a master facet when their outward normals oppose (n_s · n_m <
−0.1: within 84° of opposite, :data:`OPPOSED`; a face at right angles to the master, a
caisson's rear face on its crest, is not) and each lies in front of the other, to within
the two facets' lengths (n_s · (x_m − x_s) and n_m · (x_s − x_m) not below
−(ℓ_s + ℓ_m)/2: surfaces meshed in contact have their midpoints side by side). One
facing pair of facets anywhere is enough: the check refuses only surfaces that cannot
meet, never a surface partly off its master. In 3D a facet is the triangle of its
vertices (its centroid, normal and longest edge): a 3-D pair with the block's top as its
slave surface ran, the pair carrying nothing (or failed in the static state).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from breakwater.contact.surfaces import Surface, SurfacePair, gather_surface

if TYPE_CHECKING:
    from breakwater.model.model import ContactModel

__all__ = ["OPPOSED", "faces", "facing"]

OPPOSED = -0.1
"""n_s · n_m below this: the facets' outward normals oppose (within 84° of opposite)."""
_BLOCK = 512
"""Slave facets compared with every master facet at once (memory ~ _BLOCK × masters)."""


def _frames(surface: Surface) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each facet's midpoint, outward unit normal and length.

    2D: the chord's midpoint, normal and length; 3D: the triangle of its vertices'
    centroid, normal and longest edge.
    """
    a, b = surface.X[:, 0], surface.X[:, 1]
    if surface.X.shape[2] == 3:
        c = surface.X[:, 2]
        cross = np.cross(b - a, c - a)
        normal = cross / np.linalg.norm(cross, axis=1)[:, None]
        length = np.max([np.linalg.norm(e, axis=1) for e in (b - a, c - b, a - c)], axis=0)
        mid = (a + b + c) / 3.0
    else:
        chord = b - a
        length = np.linalg.norm(chord, axis=1)
        normal = np.stack([chord[:, 1], -chord[:, 0]], axis=1) / length[:, None]
        mid = 0.5 * (a + b)
    outward = np.sign(np.sum((mid - surface.interior) * normal, axis=1))
    return mid, normal * np.where(outward == 0, 1.0, outward)[:, None], length


def faces(slave: Surface, master: Surface, ahead: bool = True) -> bool:
    """Whether a facet of ``slave`` faces a facet of ``master`` (module docstring).

    With ``ahead`` False, whether their normals oppose only (wherever they lie).
    """
    if not len(slave.X) or not len(master.X):
        return False
    xs, ns, ls = _frames(slave)
    xm, nm, lm = _frames(master)
    for k in range(0, len(xs), _BLOCK):
        x, n, ell = xs[k:k + _BLOCK, None], ns[k:k + _BLOCK, None], ls[k:k + _BLOCK, None]
        d = xm[None] - x  # slave midpoint → master midpoint
        tol = -0.5 * (ell + lm[None])
        ok = np.sum(n * nm[None], axis=2) < OPPOSED
        if ahead:
            ok &= (np.sum(n * d, axis=2) >= tol) & (np.sum(nm[None] * -d, axis=2) >= tol)
        if ok.any():
            return True
    return False


def facing(model: ContactModel, spec: SurfacePair, overlapped: bool = False) -> str | None:
    """Why the pair's slave surface cannot meet its master surface, or None (collective).

    Args:
        model: The model.
        spec: The pair.
        overlapped: Whether the slave starts inside the master body
            (:func:`breakwater.contact.penetration.initial_overlap`): surfaces turned
            towards each other but passed through are then the overlap's case (None).

    Returns:
        One line naming the key to change (``slave_surface``, or ``master_surface``
        when only another master group would face it), the groups, the slave body's
        facet groups that face the master surface and the master body's that the slave
        surface faces (the same on every rank); None when a slave facet faces a master
        facet.
    """
    slave = gather_surface(model, None, spec.slave, (spec.slave_surface,))
    master = gather_surface(model, None, spec.master, spec.master_groups)
    if faces(slave, master) or (overlapped and faces(slave, master, ahead=False)):
        return None
    slaves = [g for g in model.facet_groups_on(spec.slave) if g != spec.slave_surface
              and faces(gather_surface(model, None, spec.slave, (g,)), master)]
    masters = [g for g in model.facet_groups_on(spec.master) if g not in spec.master_groups
               and faces(slave, gather_surface(model, None, spec.master, (g,)))]
    key = "master_surface" if masters and not slaves else "slave_surface"
    named = ", ".join(f"'{g}'" for g in spec.master_groups)
    return (f"contact.{spec.name}.{key}: slave_surface '{spec.slave_surface}' does not face "
            f"master_surface {named} anywhere (no facet of one has a facet of the other in "
            "front of it, turned towards it: the bodies could touch only through each "
            f"other); groups of '{spec.slave}' that face {named}: "
            f"{', '.join(slaves) or 'none'}; groups of '{spec.master}' that "
            f"'{spec.slave_surface}' faces: {', '.join(masters) or 'none'}")
