"""Goda's front profile on a mesh: the part of it that the loaded face receives.

A ``[loads.X.goda]`` profile is placed in the mesh by ``still_water_level``: it spans
y = SWL − h' (the base of the upright section, p₃) to SWL + min(η*, h_c) (the crest or
η*). The mesh's loaded facets receive the part of it at their elevations, nothing else,
whatever ``toe_depth`` and ``crest_height`` say. :func:`goda_applied` integrates that
part exactly, and :func:`goda_quadrature` measures what the run's load vectors apply
of it (their facet quadrature is not exact where a kink falls inside a facet);
:func:`check_goda_face` refuses a profile that misses the face and warns, with the
fraction, when only part of it is on the face (a crest height above the face's top, a
still water level that lifts the profile partly off the face).

In plane strain a facet is a segment and its horizontal force ∫ p |dy| (N/m). In 3D a
facet is a triangle or a quadrilateral (split into two triangles: exact for a planar
one) and the pressure p(y) is the same across the face's width: the horizontal force
is ∫ p |n_h| dA = ∫ p(y) ℓ(y) dy (N), with n_h the horizontal part of the facet's unit
normal and ℓ(y) the length of the facet's horizontal section at the elevation y
(:func:`section_integrals`). ℓ is linear between the facet's vertices' elevations and p
between the profile's points, so that the integral between those breakpoints is a
quadratic's, and the moment's a cubic's: Simpson's rule is exact.
"""

from __future__ import annotations

import itertools
import logging
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np
    from dolfinx.io import gmsh as gmshio

    from breakwater.casefile import loads as loadcase
    from breakwater.loads.wavepressure import GodaPressure
    from breakwater.model.model import ContactModel

__all__ = ["APPLIED_TOLERANCE", "FRACTION_WARNING", "GodaApplied", "check_goda_face",
           "facet_triangles", "goda_applied", "goda_quadrature", "section_integrals"]


@dataclass(frozen=True)
class GodaApplied:
    """The part of Goda's front profile that a mesh's loaded face receives.

    Attributes:
        force: Horizontal force applied, ∫ p |dy| over the loaded facets (N/m); in 3D
            ∫ p |n_h| dA (N: the whole face's).
        moment: Its moment about the base of the upright section, y = SWL − h' (N m/m;
            in 3D N m, about the horizontal line at that elevation).
        fraction: ``force`` / Goda's P (1: the whole profile is on the face); in 3D the
            part of P between the face's lowest and highest elevations over P (the
            profile the face spans, whatever its width).
        face: The lowest and highest y of the loaded facets (m).
        profile: The lowest and highest y of the profile, SWL − h' and SWL + h_c* (m).
        width: 3D: ``force`` over the part of P between the face's elevations, the
            face's width weighted by the pressure (m; a rectangular face's width); None
            in plane strain.

    """

    force: float
    moment: float
    fraction: float
    face: tuple[float, float]
    profile: tuple[float, float]
    width: float | None = None


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


def facet_triangles(data: gmshio.MeshData, groups: tuple[str, ...]) -> np.ndarray:
    """The vertices of the facets of the groups owned here, as triangles ``(k, 3, 3)``.

    A 3D mesh's triangular facets, and its quadrilateral ones split along a diagonal
    into two (their vertices in the reference order (0, 0), (1, 0), (0, 1), (1, 1): the
    diagonal 0–3). Only the vertices are read: a curved facet is taken as flat.
    """
    import dolfinx
    import numpy as np

    from breakwater.model.mesh import facet_type, group_tag

    msh = data.mesh
    fdim = msh.topology.dim - 1
    assert data.facet_tags is not None and fdim == 2
    quads = facet_type(msh) == dolfinx.mesh.CellType.quadrilateral
    owned = msh.topology.index_map(fdim).size_local
    out = [np.zeros((0, 3, 3))]
    for group in groups:
        facets = data.facet_tags.find(group_tag(data, group, fdim))
        facets = facets[facets < owned]
        if not len(facets):
            continue
        x = msh.geometry.x[dolfinx.mesh.entities_to_geometry(msh, fdim, facets)]
        if quads:
            out += [x[:, [0, 1, 3]], x[:, [0, 3, 2]]]
        else:
            out.append(x[:, :3])
    return np.concatenate(out)


def section_integrals(triangles: np.ndarray, s: np.ndarray,
                      points: tuple[tuple[float, float], ...], about: float
                      ) -> tuple[float, float]:
    """∫ p(s) ℓ(s) ds and ∫ p(s) (s − about) ℓ(s) ds over triangles, exactly.

    ℓ(s) is the length of a triangle's section where the coordinate s (given at its
    vertices, linear over it) is constant: ∫ p ℓ ds = ∫ p |∇s| dA, with ∇s the
    gradient of s in the triangle's plane (for s the elevation y, |∇s| = |n_h|: the
    horizontal force of a pressure p(y)). ℓ rises linearly from 0 at the lowest s to
    its largest at the middle vertex and falls to 0 at the highest; p is linear between
    the profile's ``points`` and 0 outside them, so that between the breakpoints the
    integrands are quadratic and cubic: Simpson's rule is exact.

    Args:
        triangles: Vertices ``(k, 3, 3)``.
        s: The coordinate at the vertices ``(k, 3)``.
        points: The profile's (s, p) points, increasing s.
        about: The s of the moment's axis.

    """
    knots = [p[0] for p in points]
    values = [p[1] for p in points]

    def pressure(u: float, m: float, v: float) -> tuple[float, float, float]:
        """P at u, m, v on the profile's piece holding m (0 outside the profile)."""
        if m < knots[0] or m > knots[-1]:
            return 0.0, 0.0, 0.0
        j = next(i for i in range(len(knots) - 1) if m <= knots[i + 1])
        slope = (values[j + 1] - values[j]) / (knots[j + 1] - knots[j])
        return (values[j] + slope * (u - knots[j]), values[j] + slope * (m - knots[j]),
                values[j] + slope * (v - knots[j]))

    force = moment = 0.0
    for tri, st in zip(triangles, s, strict=True):
        a, b, c = (int(i) for i in st.argsort())
        sa, sb, sc = (float(st[i]) for i in (a, b, c))
        if not sc > sa or sc <= knots[0] or sa >= knots[-1]:
            continue
        # The section through the middle vertex: from it to the opposite edge.
        across = tri[a] + (sb - sa) / (sc - sa) * (tri[c] - tri[a])
        lb = float(((tri[b] - across) ** 2).sum() ** 0.5)
        cuts = sorted({sa, sb, sc, *(k for k in knots if sa < k < sc)})
        for u, v in itertools.pairwise(cuts):
            m = 0.5 * (u + v)
            pu, pm, pv = pressure(u, m, v)
            # ℓ on this piece: rising from sa to sb, or falling from sb to sc (m may
            # round to sb when v − u is an ulp: a knot an ulp off a vertex).
            if m < sb or sc == sb:
                lu, lm, lv = (lb * (w - sa) / (sb - sa) for w in (u, m, v))
            else:
                lu, lm, lv = (lb * (sc - w) / (sc - sb) for w in (u, m, v))
            force += (v - u) / 6.0 * (pu * lu + 4.0 * pm * lm + pv * lv)
            moment += (v - u) / 6.0 * (pu * lu * (u - about) + 4.0 * pm * lm * (m - about)
                                       + pv * lv * (v - about))
    return force, moment


def goda_applied(load: loadcase.LoadCase, data: gmshio.MeshData) -> GodaApplied:
    """Integrate a Goda load's front profile over its loaded facets (collective).

    Each facet (owned by one rank) receives the profile between its lowest and highest
    elevations, integrated exactly (:meth:`GodaPressure.part`; in 3D
    :func:`section_integrals`); the sums over the ranks are the same on every rank.
    """
    import numpy as np
    from mpi4py import MPI

    assert load.goda is not None
    g = load.goda.pressure()
    swl = load.goda.still_water_level
    msh = data.mesh
    if msh.topology.dim == 3:
        return _applied3d(g, swl, data, (load.group, *load.groups))
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


def _applied3d(g: GodaPressure, swl: float, data: gmshio.MeshData, groups: tuple[str, ...]
               ) -> GodaApplied:
    """:func:`goda_applied` on a 3D mesh (collective)."""
    import numpy as np
    from mpi4py import MPI

    triangles = facet_triangles(data, groups)
    z = triangles[:, :, 1] - swl  # the elevation above the SWL
    force, moment = section_integrals(triangles, z, g.front_points(), -g.toe_depth)
    comm = data.mesh.comm
    force, moment = (float(v) for v in comm.allreduce(np.array([force, moment]), op=MPI.SUM))
    lo = comm.allreduce(float(triangles[:, :, 1].min()) if len(z) else math.inf, op=MPI.MIN)
    hi = comm.allreduce(float(triangles[:, :, 1].max()) if len(z) else -math.inf, op=MPI.MAX)
    spanned = g.part(lo - swl, hi - swl)[0] if hi > lo else 0.0
    return GodaApplied(force, moment, spanned / g.force, (lo, hi),
                       (swl - g.toe_depth, swl + g.wetted_crest),
                       force / spanned if spanned > 0 else 0.0)


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
        applies = (f"P = {applied.force:.4g} N/m of the formula's {g.force:.4g} N/m"
                   if applied.width is None else
                   f"{applied.force:.4g} N, {applied.fraction * g.force:.4g} N/m of the "
                   f"formula's P = {g.force:.4g} N/m over the face's width")
        log.warning(f"{key}: only {100 * applied.fraction:.1f}% of Goda's horizontal force "
                    f"is on the loaded face ({face}; the profile {profile}): the run applies "
                    f"{applies}, as summary.json reports")
    if applied.fraction > 1.0 + APPLIED_TOLERANCE and applied.width is None:
        log.warning(f"{key}: the loaded faces ({face}) receive {100 * applied.fraction:.1f}% "
                    f"of Goda's horizontal force: some elevations are loaded more than once "
                    f"(several faces at one height), P = {applied.force:.4g} N/m against the "
                    f"formula's {g.force:.4g} N/m")
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


FRACTION_WARNING = 0.01
"""A Goda front (or a storm wave's) whose load vectors apply a force or moment off its
exact integral over the face, or whose profile lies partly off the face, by more than
this fraction is warned about."""


def goda_quadrature(load: loadcase.LoadCase, model: ContactModel, exact: GodaApplied
                    ) -> tuple[dict[str, float], str | None]:
    """The horizontal force and moment the run applies of a Goda front (collective).

    The run applies the front's load vectors, whose facet quadrature
    (:meth:`~breakwater.model.model.ContactModel.load_resultant`) does not integrate a
    kink of the profile inside a facet (at the still water level, η* or the crest)
    exactly; ``exact`` (:func:`goda_applied`) is the profile's integral over the same
    facets. The horizontal resultant F_h of the front's load vectors (x, and z in 3D)
    and their moment Σ_k (y_k − y₀) b_k · F_h/|F_h| about y₀ = SWL − h' (b_k the nodal
    forces at the nodes' elevations y_k).

    Returns:
        The summary's entries (``horizontal_force_per_length`` and
        ``horizontal_moment_per_length`` what the run applies, ``exact_force_per_length``
        and ``exact_moment_per_length`` the exact integrals, ``face_fraction`` the
        applied force over the exact) and a one-line warning when that fraction is off
        1 by more than :data:`FRACTION_WARNING`, or None.
    """
    import numpy as np

    front = {load.group, *load.groups}
    y0 = exact.profile[0]
    axes = (0,) if model.gdim == 2 else (0, 2)
    force, moment = np.zeros(len(axes)), np.zeros(len(axes))
    for ld in model.loads:
        if ld.spec.name == load.name and ld.spec.group in front:
            for k, i in enumerate(axes):
                force[k] += model.assemble(model.form(model.load_resultant(ld, i)))
                moment[k] += model.assemble(model.form(model.load_resultant(
                    ld, i, lambda x: x[1] - y0)))
    size = float(np.linalg.norm(force))
    lever = float(moment @ force / size) if size > 0 else 0.0
    fraction = size / exact.force if exact.force > 0 else math.nan
    moment_fraction = lever / exact.moment if exact.moment > 0 else math.nan
    entries = {"horizontal_force_per_length": size, "horizontal_moment_per_length": lever,
               "exact_force_per_length": exact.force,
               "exact_moment_per_length": exact.moment, "face_fraction": fraction,
               "face_moment_fraction": moment_fraction}
    warning = None
    worst = max((fraction, moment_fraction), key=lambda f: abs(f - 1.0))
    if not abs(worst - 1.0) <= FRACTION_WARNING:
        what = "force" if worst == fraction else "moment"
        warning = (f"loads.{load.name}.goda: the facets apply {100 * worst:.4g}% of the "
                   f"{what} of the profile over the loaded face (its kinks, or its end at "
                   "the crest, fall inside facets, whose quadrature does not integrate them "
                   "exactly: refine the face there); summary.json face_fraction, "
                   "face_moment_fraction")
    return entries, warning
