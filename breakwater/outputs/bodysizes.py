"""The bodies' sizes as the mesh gives them: extent, volume, mass (``summary.json``).

breakwater reads coordinates in metres. A mesh drawn in millimetres runs as a structure
1000 times larger (a 0.2 m block on its mound: a 200 m cube of 1.85e7 t, its weight
1.8e11 N), every number consistent and none flagged. The summary gives each body's
extent, volume and mass, to be checked against the drawing, and a mesh spanning more
than :data:`LARGEST_EXTENT` is warned about, or in 3D a body of more than
:data:`LARGEST_VOLUME`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from breakwater.model.model import ContactModel

__all__ = ["DENSITY_RANGE", "LARGEST_EXTENT", "LARGEST_VOLUME", "body_sizes",
           "density_warnings", "gravity_warning", "initial_motion", "size_warning",
           "unit_checks"]

LARGEST_EXTENT = 2000.0
"""m: a mesh wider than this is warned about (drawn in mm?). A breakwater's caisson is
10-40 m, its mound up to a few hundred metres; the same caisson in mm is 10-40 km."""


LARGEST_VOLUME = 1e7
"""m³: a 3D body of more than this (a 215 m cube) is warned about. A laboratory model
drawn in mm spans less than :data:`LARGEST_EXTENT` (Goda's 1.16 m mound: 1160 m) but its
volume is 1e9 times its own (the mound's 0.03 m³: 3e7 m³); a prototype mound 100 m wide
and 15 m high is 1e7 m³ over 7 km of breakwater."""


DENSITY_RANGE = (10.0, 23000.0)
"""kg/m³: a body's density outside this is warned about. The lightest fill a
breakwater or an embankment is built of, EPS geofoam, is 10-40 kg/m³; osmium, the
densest element, 22 590. A density typed in g/cm³ or t/m³ (concrete 2.4, sand 1.6-2.1)
is 1000 times too small: the run took a 2.4 kg/m³ caisson without a word (its weight,
the contact's pressure and its inertia 1000 times too small)."""


def body_sizes(model: ContactModel) -> dict[str, dict[str, Any]]:
    """Each body's bounding box extent (m), volume and mass (collective).

    In plane strain the volume is the cross-section's area (m²) and the mass per metre
    (kg/m), as the model's weights are per metre.

    Returns:
        By body name: ``extent`` (m, along x, y and z in 3D), ``volume`` (m³; m² in plane
        strain), ``mass`` (kg; kg/m in plane strain).
    """
    out = {}
    for b in model.bodies:
        lo, hi = model.bounding_box(b.index)
        mass = model.assemble(model.form(b.ρ * b.dx))
        out[b.spec.name] = {"extent": [float(v) for v in hi - lo],
                            "volume": float(mass / b.spec.material.density),
                            "mass": float(mass)}
    return out


def size_warning(sizes: dict[str, dict[str, Any]]) -> str | None:
    """One line if a body spans more than :data:`LARGEST_EXTENT`, else None."""
    if not sizes:
        return None
    name = max(sizes, key=lambda n: max(sizes[n]["extent"]))
    largest = max(sizes[name]["extent"])
    if largest > LARGEST_EXTENT:
        what = f"spans {largest:.4g} m"
    else:  # 3D: a laboratory model drawn in mm (its extents those of a prototype)
        name = max(sizes, key=lambda n: sizes[n]["volume"])
        volume = sizes[name]["volume"]
        if len(sizes[name]["extent"]) < 3 or volume <= LARGEST_VOLUME:
            return None
        what = f"is {volume:.3g} m³"
    return (f"mesh: body '{name}' {what}: breakwater reads coordinates in metres "
            f"(a mesh drawn in mm is 1000 times too large; scale it, e.g. gmsh's "
            f"Mesh.ScalingFactor = 0.001); the bodies' sizes and masses: summary.json, "
            f"mesh.bodies")


def density_warnings(densities: dict[str, float]) -> list[str]:
    """One line per body whose density is outside :data:`DENSITY_RANGE` (kg/m³ by name)."""
    lo, hi = DENSITY_RANGE
    lines = []
    for name, ρ in densities.items():
        if ρ < lo:
            lines.append(f"bodies.{name}: density {ρ:g} kg/m³, below any solid's (EPS "
                         f"geofoam, the lightest fill: 10-40): in g/cm³ or t/m³? breakwater "
                         f"reads kg/m³ ({ρ:g} g/cm³ = {1000 * ρ:g} kg/m³)")
        elif ρ > hi:
            lines.append(f"bodies.{name}: density {ρ:g} kg/m³, above any material's "
                         f"(osmium: 22 590): in g/m³? breakwater reads kg/m³")
    return lines


def gravity_warning(gravity: tuple[float, ...]) -> str | None:
    """One line if |g| is within 5 % of 9810 (g in mm/s²: breakwater is SI), else None.

    A case written in mm (its gravity 9810) ran 1000 g without a word, its only trace a
    penalty found too soft (a centrifuge model runs at up to a few hundred g).
    """
    g = math.sqrt(sum(c * c for c in gravity))
    if abs(g / 9810.0 - 1.0) > 0.05:
        return None
    return (f"gravity: |g| = {g:g} m/s², 1000 times the Earth's: g in mm/s²? breakwater "
            "reads SI units (m, kg, s, Pa): gravity = [0.0, -9.81"
            + (", 0.0]" if len(gravity) == 3 else "]"))


def unit_checks(model: ContactModel) -> dict[str, Any]:
    """The bodies' sizes and the lines of a case whose units look off (collective).

    What a case file's build adds to the summary's ``mesh`` entry, for any model (one
    built in Python too: its mesh in mm, g in mm/s² or a density in g/cm³ ran without a
    word).

    Returns:
        ``bodies`` (:func:`body_sizes`) and, where any, ``warnings``: the lines of
        :func:`size_warning`, :func:`gravity_warning` and :func:`density_warnings`.
    """
    sizes = body_sizes(model)
    gravity = tuple(float(g) for g in model.gravity.value)
    lines = [size_warning(sizes), gravity_warning(gravity),
             *density_warnings({b.spec.name: b.spec.material.density for b in model.bodies})]
    out: dict[str, Any] = {"bodies": sizes}
    if any(lines):
        out["warnings"] = [line for line in lines if line]
    return out


def initial_motion(bodies: dict[str, dict[str, Any]],
                   velocities: tuple[tuple[str, tuple[float, ...]], ...]) -> None:
    """Put each moving body's ``initial_velocity`` and ``initial_momentum`` m v in its entry.

    The velocities the run applies (its model's ``initial.velocities``, set after a case's
    build too), not the case's: the entries of bodies at rest lose theirs.

    Args:
        bodies: :func:`body_sizes`'s entries (updated in place).
        velocities: ``(body, vector)`` pairs, a body's uniform initial velocity (m/s).
    """
    moving = dict(velocities)
    for name, entry in bodies.items():
        v = moving.get(name)
        if v is not None and any(v):
            entry["initial_velocity"] = [float(c) for c in v]
            entry["initial_momentum"] = [entry["mass"] * float(c) for c in v]
        else:
            entry.pop("initial_velocity", None)
            entry.pop("initial_momentum", None)
