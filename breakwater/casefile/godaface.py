"""Goda's front profile on a mesh: the part of it that the loaded face receives.

A ``[loads.X.goda]`` profile is placed in the mesh by ``still_water_level``: it spans
y = SWL − h' (the base of the upright section, p₃) to SWL + min(η*, h_c) (the crest or
η*). The mesh's loaded facets receive the part of it at their elevations, nothing else,
whatever ``toe_depth`` and ``crest_height`` say. :func:`goda_applied` integrates that
part exactly (the force and moment the run applies, reported by the summary);
:func:`check_goda_face` refuses a profile that misses the face and warns, with the
fraction, when only part of it is on the face (a crest height above the face's top, a
still water level that lifts the profile partly off the face).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from dolfinx.io import gmsh as gmshio

    from breakwater.casefile import loads as loadcase

__all__ = ["APPLIED_TOLERANCE", "GodaApplied", "check_goda_face", "goda_applied"]


@dataclass(frozen=True)
class GodaApplied:
    """The part of Goda's front profile that a mesh's loaded face receives.

    Attributes:
        force: Horizontal force applied, ∫ p |dy| over the loaded facets (N/m).
        moment: Its moment about the base of the upright section, y = SWL − h' (N m/m).
        fraction: ``force`` / Goda's P (1: the whole profile is on the face).
        face: The lowest and highest y of the loaded facets (m).
        profile: The lowest and highest y of the profile, SWL − h' and SWL + h_c* (m).

    """

    force: float
    moment: float
    fraction: float
    face: tuple[float, float]
    profile: tuple[float, float]


def facet_spans(data: gmshio.MeshData, groups: tuple[str, ...]
                ) -> list[tuple[float, float]]:
    """The lowest and highest elevation (y) of each facet of the groups owned here."""
    import dolfinx

    from breakwater.model.mesh import group_tag

    msh = data.mesh
    fdim = msh.topology.dim - 1
    assert data.facet_tags is not None
    owned = msh.topology.index_map(fdim).size_local
    spans: list[tuple[float, float]] = []
    for group in groups:
        facets = data.facet_tags.find(group_tag(data, group, fdim))
        facets = facets[facets < owned]
        if len(facets):
            y = msh.geometry.x[dolfinx.mesh.entities_to_geometry(msh, fdim, facets), 1]
            spans += zip(y.min(axis=1).tolist(), y.max(axis=1).tolist(), strict=True)
    return spans


def goda_applied(load: loadcase.LoadCase, data: gmshio.MeshData) -> GodaApplied:
    """Integrate a Goda load's front profile over its loaded facets (collective).

    Each facet (owned by one rank) receives the profile between its lowest and highest
    elevations, integrated exactly (:meth:`GodaPressure.part`); the sums over the ranks
    are the same on every rank.
    """
    import numpy as np
    from mpi4py import MPI

    assert load.goda is not None
    g = load.goda.pressure()
    swl = load.goda.still_water_level
    msh = data.mesh
    force = moment = 0.0
    lo, hi = math.inf, -math.inf
    for y0, y1 in facet_spans(data, (load.group, *load.groups)):
        f, m = g.part(y0 - swl, y1 - swl)
        force, moment = force + f, moment + m
        lo, hi = min(lo, y0), max(hi, y1)
    force, moment = (float(v) for v in msh.comm.allreduce(np.array([force, moment]),
                                                          op=MPI.SUM))
    lo, hi = msh.comm.allreduce(lo, op=MPI.MIN), msh.comm.allreduce(hi, op=MPI.MAX)
    return GodaApplied(force, moment, force / g.force, (lo, hi),
                       (swl - g.toe_depth, swl + g.wetted_crest))


APPLIED_TOLERANCE = 1e-6
"""A Goda profile is whole on its face when at least 1 − this of its force is applied
(the mesh's coordinates against the still water level, h' and h_c: round-off)."""


def check_goda_face(load: loadcase.LoadCase, data: gmshio.MeshData, warn: bool = True
                    ) -> GodaApplied:
    """Refuse a Goda profile off its loaded face; warn when only part of it is on it.

    Also warned: a face that reaches below the base of the upright section (SWL − h')
    or above its crest (SWL + h_c, when η* is higher), where the profile stops because
    ``toe_depth`` or ``crest_height`` says the upright section does: that part of the
    mesh's face is left unloaded.

    Args:
        load: A ``[loads.X]`` with a ``[goda]`` table.
        data: The mesh.
        warn: Log the one-line warnings (part of the profile off the face, part of the
            face beyond the profile).

    Raises:
        CaseError: No part of the profile is on the loaded facets (the same on every
            rank).

    """
    from breakwater.common.errors import CaseError

    applied = goda_applied(load, data)
    assert load.goda is not None
    key = f"loads.{load.name}.goda"
    names = ", ".join((load.group, *load.groups))
    face = f"{names}: y = {applied.face[0]:.4g} to {applied.face[1]:.4g} m"
    profile = (f"y = {applied.profile[0]:.4g} to {applied.profile[1]:.4g} m: "
               f"still_water_level − toe_depth to + min(η*, crest_height)")
    if not applied.fraction > APPLIED_TOLERANCE:
        raise CaseError(f"{key}.still_water_level: the pressure profile ({profile}) misses "
                        f"the loaded face ({face}): no wave load would be applied")
    if not warn:
        return applied
    log = logging.getLogger("breakwater")
    g = load.goda.pressure()
    if applied.fraction < 1.0 - APPLIED_TOLERANCE:
        log.warning(f"{key}: only {100 * applied.fraction:.1f}% of Goda's horizontal force "
                    f"is on the loaded face ({face}; the profile {profile}): the run applies "
                    f"P = {applied.force:.4g} N/m of the formula's {g.force:.4g} N/m, as "
                    f"summary.json reports")
    # The face beyond the profile's ends, where Goda's formula stops only because h' or
    # h_c says the upright section does: the mesh's face there is left unloaded.
    swl, (lo, hi) = load.goda.still_water_level, applied.face
    slack = APPLIED_TOLERANCE * (hi - lo)
    base, crest = swl - g.toe_depth, swl + g.crest_height
    if lo < base - slack and hi > base:
        log.warning(f"{key}.toe_depth: the loaded face ({face}) reaches {base - lo:.4g} m "
                    f"below the base of the upright section (still_water_level − "
                    f"toe_depth, y = {base:.4g} m), where Goda's profile stops: that part "
                    f"of the face is not loaded")
    if g.eta_star > g.crest_height and hi > crest + slack and lo < crest:
        log.warning(f"{key}.crest_height: the loaded face ({face}) reaches {hi - crest:.4g} "
                    f"m above the crest (still_water_level + crest_height, y = "
                    f"{crest:.4g} m), where Goda's profile stops below η* = "
                    f"{g.eta_star:.4g} m: that part of the face is not loaded")
    return applied
