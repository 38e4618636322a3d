"""A storm load on a mesh: its waves for the summary and the probes of its per-wave record.

:func:`storm_outputs` gives, for a ``[loads.<name>.storm]`` of a case on its mesh, the
two pair probes at the ends of the caisson's base (on the contact pair whose surface
is ``uplift_group``) and the load's ``storm`` summary entry: the waves (H, T, start,
the duration of the force, the front shape and its horizontal force per unit p₁ on
the loaded face) and how :mod:`breakwater.outputs.stormrecord` reads the history.
"""

from __future__ import annotations

import itertools
from typing import TYPE_CHECKING, Any

from breakwater.casefile.godaface import FRACTION_WARNING
from breakwater.casefile.loadchecks import storm_warning
from breakwater.common.errors import CaseError
from breakwater.config.runspec import PairProbeSpec
from breakwater.loads.fields import StagedField
from breakwater.stepping.stepsize import resolved_step
from breakwater.storms.stormload import WaveHistory

if TYPE_CHECKING:
    from dolfinx.io import gmsh as gmshio

    from breakwater.casefile.loads import LoadCase
    from breakwater.casefile.settings import CaseSettings
    from breakwater.model.model import ContactModel

__all__ = ["applied_front", "face_integral", "fraction_warnings", "profile_integral",
           "storm_outputs"]


def profile_integral(points: Any, a: float, b: float) -> float:
    """∫ p(s) ds over [a, b] of a piecewise-linear profile, 0 outside its points (exact)."""
    s = [float(p[0]) for p in points]
    p = [float(q[1]) for q in points]
    lo, hi = max(min(a, b), s[0]), min(max(a, b), s[-1])
    if not hi > lo:
        return 0.0
    cuts = sorted({lo, hi, *(x for x in s if lo < x < hi)})

    def value(x: float) -> float:
        for k in range(len(s) - 1):
            if s[k] <= x <= s[k + 1]:
                return p[k] + (p[k + 1] - p[k]) * (x - s[k]) / (s[k + 1] - s[k])
        return 0.0

    return sum(0.5 * (value(x0) + value(x1)) * (x1 - x0)
               for x0, x1 in itertools.pairwise(cuts))


def face_integral(points: Any, still_water_level: float, data: gmshio.MeshData,
                  groups: tuple[str, ...]) -> float:
    """∫ shape(y − SWL) |dy| over the loaded facets (collective; the same on every rank).

    The horizontal force per unit p₁ that a vertical face receives of a front shape; in
    3D ∫ shape |n_h| dA, the whole face's (m²:
    :func:`~breakwater.casefile.godaface.section_integrals`).
    """
    from mpi4py import MPI

    from breakwater.casefile.godaface import facet_spans, facet_triangles, section_integrals

    msh = data.mesh
    if msh.topology.dim == 3:
        triangles = facet_triangles(data, groups)
        shape = tuple((float(p[0]), float(p[1])) for p in points)
        total = section_integrals(triangles, triangles[:, :, 1] - still_water_level, shape,
                                  0.0)[0]
    else:
        total = sum(profile_integral(points, y0 - still_water_level, y1 - still_water_level)
                    for y0, y1 in facet_spans(data, groups))
    return float(msh.comm.allreduce(total, op=MPI.SUM))


def applied_front(model: ContactModel, name: str, stages: int) -> list[float]:
    """The horizontal force per unit p₁ that the model applies in each stage (collective).

    ∫ t_x ds of the case load's staged front loads (with the quadrature of the load
    vectors the run assembles: :meth:`~breakwater.model.model.ContactModel.load_resultant`),
    each stage's points set in turn, then the stage the model held set back.
    """
    loads = [ld for ld in model.loads if ld.spec.name == name and ld.parameters is not None]
    forms = [model.form(model.load_resultant(ld, 0)) for ld in loads]
    out = []
    for k in range(stages):
        for ld in loads:
            assert ld.parameters is not None and isinstance(ld.spec.field, StagedField)
            ld.parameters.value[:] = ld.spec.field.parameters(k)
        out.append(sum(model.assemble(f) for f in forms))
    for ld in loads:
        assert ld.parameters is not None and isinstance(ld.spec.field, StagedField)
        ld.parameters.value[:] = ld.spec.field.parameters(ld.stage)
    return out


def _peak(load: Any) -> float:
    """A wave load's largest p₁ (Pa): its history's own ``peak``, else sampled.

    The storms' histories (:class:`~breakwater.storms.waveforce.PulseHistory`) know
    theirs; another history of τ is sampled at 401 points over its duration (its middle
    among them).
    """
    peak = getattr(load.p1, "peak", None)
    if peak is None:
        peak = max(load.p1(load.duration * k / 400) for k in range(401))
    return float(peak)


def fraction_warnings(waves: list[dict[str, Any]], forces: list[float], key: str) -> list[str]:
    """The one-line warnings of a storm whose applied front force is off (:func:`storm_outputs`).

    A wave's error counts by force: its front force error ``p₁ |F_applied − F_exact|``
    (``face_fraction``) or its front force off the face ``p₁ F_whole (1 −
    profile_fraction)``, each over the largest wave's exact front force. Warned above
    :data:`~breakwater.casefile.godaface.FRACTION_WARNING`, naming the wave of the
    largest: a wave of 0.1 m in a sea of 8 m whose profile's kink falls inside a facet
    (96 % applied) changes nothing, while a design wave 1 % off does.

    Args:
        waves: The storm summary's waves (``face_fraction``, ``profile_fraction``,
            ``height``).
        forces: Each wave's exact front force over the face at its peak p₁.
        key: The load's case key (``loads.<name>.storm``).
    """
    exact = forces
    largest = max(exact, default=0.0)
    warnings = []
    for name, what in (("profile_fraction", "of the front profile lies on the loaded face "
                        "(the rest is not applied)"),
                       ("face_fraction", "of the exact integral over the face is applied "
                        "(profile kinks inside facets: refine the face)")):
        if not largest > 0:
            break
        # The force off: the whole profile's force times (1 − profile_fraction), or the
        # exact force times (face_fraction − 1).
        off = [f * abs(1 / w[name] - 1 if name == "profile_fraction" else w[name] - 1)
               for f, w in zip(exact, waves, strict=True)]
        worst = max(range(len(waves)), key=lambda k: off[k])
        if off[worst] > FRACTION_WARNING * largest:
            warnings.append(f"{key}: wave {worst + 1} (H = {waves[worst]['height']:g} m): "
                            f"{100 * waves[worst][name]:.3g}% {what}, "
                            f"{100 * off[worst] / largest:.2g}% of the largest wave's front "
                            f"force; summary.json {key}.waves[].{name}")
    return warnings


def storm_outputs(case: CaseSettings, data: gmshio.MeshData, load: LoadCase,
                  model: ContactModel) -> tuple[tuple[PairProbeSpec, ...], dict[str, Any]]:
    """The pair probes of a storm's record and its ``storm`` summary entry (collective).

    Each wave's entry holds ``front_force_per_p1``, the horizontal force per unit p₁
    the run applies (:func:`applied_front`), ``face_fraction``, that over the exact
    integral of the wave's shape over the loaded face (off 1 where the facets do not
    resolve the profile's kinks), and ``profile_fraction``, the exact integral over the
    face over the whole shape's (below 1 where the face misses part of the profile; in
    3D the shape's part between the face's elevations);
    ``warnings`` the one-line warnings of the waves off by more than
    :data:`~breakwater.casefile.godaface.FRACTION_WARNING`. In 3D the probes lie on the
    base's mid-plane in z and the record's ``breakwater_length`` is the base's extent in
    z (1 in plane strain): the per-wave record divides the whole face's force and the
    caisson's mass and W' by it.

    Args:
        case: The case (its contact pairs).
        data: The mesh.
        load: A load with a ``[storm]``.
        model: The model built with the load.

    Returns:
        The probes (the pair at indices of the case's conforming pairs, or a general
        pair's name) and the entry.

    Raises:
        CaseError: No contact pair on ``uplift_group``; a base that is not horizontal;
            the front shape of every wave off the loaded face.
    """
    from breakwater.casefile.meshloads import base_triangle, extent, owner, storm_wave_loads

    storm = load.storm
    assert storm is not None
    key = f"loads.{load.name}.storm"
    groups = (load.group, *load.groups)
    caisson = load.body or owner(data, load.group)
    conforming = [c for c in case.contact if not c.general]
    found: tuple[Any, int, int | str] | None = None
    for c in case.contact:
        masters = c.master_surface if isinstance(c.master_surface, tuple) \
            else (c.master_surface,)
        if not c.general and c.name == storm.uplift_group:
            found = (c, 1 if c.slave == caisson else -1, conforming.index(c))
        elif c.general and c.slave_surface == storm.uplift_group:
            found = (c, 1, c.name)
        elif c.general and storm.uplift_group in masters:
            found = (c, -1, c.name)
        if found is not None:
            break
    if found is None:
        raise CaseError(f"{key}.uplift_group: no contact pair on '{storm.uplift_group}' "
                        "(the per-wave sliding is measured on the pair under the "
                        "caisson's base)")
    pair, sign, index = found
    lo, hi = extent(data, storm.uplift_group)
    width = float(hi[0] - lo[0])
    if abs(float(hi[1] - lo[1])) > 1e-9 * width:
        raise CaseError(f"{key}.uplift_group: the base '{storm.uplift_group}' is not "
                        f"horizontal (y from {lo[1]:.6g} to {hi[1]:.6g} m)")
    y = float(lo[1])
    names = (f"{load.name}_base_lo", f"{load.name}_base_hi", f"{load.name}_base_mid")
    across: tuple[float, ...] = ()  # 3D: the probes on the base's mid-plane in z
    length = 1.0  # 3D: the caisson's length along the breakwater (z), the base's
    threed = data.mesh.geometry.dim == 3
    if threed:
        across, length = (0.5 * float(lo[2] + hi[2]),), float(hi[2] - lo[2])
    probes = (PairProbeSpec(names[0], index, (float(lo[0]), y, *across)),
              PairProbeSpec(names[1], index, (float(hi[0]), y, *across)),
              PairProbeSpec(names[2], index, (0.5 * float(lo[0] + hi[0]), y, *across)))
    ends = [extent(data, g) for g in groups]  # the face's lowest and highest y
    face = (min(float(e[0][1]) for e in ends), max(float(e[1][1]) for e in ends))
    triangle, _ = base_triangle(storm.uplift_group, data, groups)
    waves: list[dict[str, Any]] = []
    warnings: list[str] = []
    wave_loads = storm_wave_loads(load, data)
    applied = applied_front(model, load.name, len(wave_loads))
    forces = []  # each wave's exact front force at its peak p₁
    for k, w in enumerate(wave_loads):
        force = face_integral(w.front, storm.still_water_level, data, groups)
        forces.append(_peak(w) * force)
        whole = profile_integral(w.front, w.front[0][0], w.front[-1][0])
        swl = storm.still_water_level
        # 3D: the part of the shape between the face's elevations (whatever its width).
        spanned = force if not threed else \
            profile_integral(w.front, face[0] - swl, face[1] - swl)
        if not force > 0:
            raise CaseError(f"{key}.still_water_level: the front pressure of wave {k + 1} "
                            f"(H = {w.wave.height:g} m) misses the loaded face "
                            f"({', '.join(groups)}): no wave load would be applied")
        waves.append({"height": w.wave.height, "period": w.wave.period,
                      "start": w.wave.start, "duration": w.duration,
                      "front": [list(p) for p in w.front],
                      "front_force_per_p1": applied[k], "face_fraction": applied[k] / force,
                      "profile_fraction": spanned / whole})
    warnings += fraction_warnings(waves, forces, key)
    t = case.time  # the step inside the waves (adaptive: the one that resolves them)
    dt = resolved_step(t.dt, t.levels, WaveHistory(wave_loads, "p1").breakpoints) \
        if t.adaptive else t.dt
    unresolved = storm_warning(load.name, wave_loads, dt, t.end_time, t.beta1)
    if unresolved is not None:
        warnings.append(unresolved)
    capped = storm.capped(width)
    if capped is not None and capped[0]:
        warnings.append(f"{key}.sea: {capped[0]} of the {capped[1]} waves drawn exceed the "
                        f"breaking height H_b = {capped[2]:.4g} m at the site and are "
                        "capped to it (broken waves; Goda's H_b at 5 H_1/3 seaward)")
    record = {"lo": names[0], "hi": names[1], "mid": names[2], "sign": sign,
              "conforming": not pair.general,
              "landward": float(triangle.axis[0]), "length": width,
              "breakwater_length": length,
              "pair": pair.name, "penetration": f"{pair.name}_penetration",
              "penalty": pair.penalty, "caisson": caisson, "friction": pair.friction,
              "toe_depth": storm.toe_depth, "density": storm.density}
    return probes, {"waves": waves, "base_width": width, "duration": storm.waves_train.duration,
                    "record": record, "warnings": warnings,
                    **({"capped_waves": capped[0], "breaking_height": capped[2]}
                       if capped is not None else {})}
