"""A case's dimension: plane strain (2D) or three dimensions, from its vectors and its mesh.

A case's vectors (``gravity``, the ``direction`` of each force, traction or pulse, a
profile's ``axis`` (which may stay 2D: the x-y plane), the bodies' non-zero
``initial_velocity``, the probes' ``point``) all have 2 components (plane strain) or
all 3; ``gravity`` sets the case's dimension (its default is 2D). The mesh must then be
of the same dimension (:func:`mesh_problem`, once it is read). In 3D,
``out_of_plane_length`` does not apply (nothing is per metre) and must stay 1, and a
calibration reads its stiffness as the 3D model's (``stiffness_basis = "block"``).
General (non-matching) pairs run in 3D with ``segments`` or ``gauss`` integration
(with or without friction); ``nodes`` on one is refused in one line
(:func:`general_in_3d`). Goda's pressures and storms run in 3D: p(y) the same across
the face's width.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Protocol

from breakwater.casefile.loads import LoadCase
from breakwater.casefile.tables import (
    GODA3D,
    BodyCase,
    CalibrationCase,
    ContactCase,
    FixedCase,
    MeshCase,
    OutputCase,
)
from breakwater.config.fields import InvalidField
from breakwater.model.pairs import HEXAHEDRA, three_d_general

__all__ = ["dimension", "dimension_problem", "general_in_3d", "mesh_problem"]


class _Case(Protocol):
    """What this module reads of a case (:class:`breakwater.casefile.settings.CaseSettings`)."""

    @property
    def gravity(self) -> tuple[float, ...]: ...
    @property
    def out_of_plane_length(self) -> float: ...
    @property
    def loads(self) -> tuple[LoadCase, ...]: ...
    @property
    def bodies(self) -> tuple[BodyCase, ...]: ...
    @property
    def contact(self) -> tuple[ContactCase, ...]: ...
    @property
    def fixed(self) -> tuple[FixedCase, ...]: ...
    @property
    def output(self) -> OutputCase: ...
    @property
    def calibration(self) -> CalibrationCase: ...
    @property
    def mesh(self) -> MeshCase: ...


def dimension(case: _Case) -> int:
    """The case's dimension: 2 (plane strain) or 3, the length of its gravity vector."""
    return len(case.gravity)


def _vectors(case: _Case) -> Iterator[tuple[str, tuple[float, ...]]]:
    """Every vector of a case but gravity, by key (a zero initial velocity is none)."""
    for ld in case.loads:
        if ld.force is not None or ld.traction is not None or ld.kind == "pulse":
            yield f"loads.{ld.name}.direction", ld.direction  # (unused by pressures)
        if ld.profile is not None:
            yield f"loads.{ld.name}.profile.axis", ld.profile.axis
    for b in case.bodies:
        if any(b.initial_velocity):
            yield f"bodies.{b.name}.initial_velocity", b.initial_velocity
    for kind, probes in (("probes", case.output.probes),
                         ("pair_probes", case.output.pair_probes)):
        for p in probes:
            if p.point is not None:
                yield f"output.{kind}.{p.name}.point", p.point


def dimension_problem(case: _Case) -> None:
    """Refuse a case whose vectors disagree with its gravity's dimension.

    Raises:
        InvalidField: The first key with the wrong number of components, or a 3D case
            with gravity along z, ``out_of_plane_length`` or a per-metre calibration.
    """
    d = dimension(case)
    others = [(k, v) for k, v in _vectors(case) if not k.endswith("profile.axis")]
    zs = [f"fixed.{f.name}.components" for f in case.fixed
          if f.components is not None and max(f.components) >= 2]
    keys = [k for k, _ in others] + (zs if d == 2 else [])
    if len(keys) > 1 and all(len(v) == 5 - d for _, v in others) and (d == 2 or not zs):
        # Gravity is the odd one out of several (a 3D case given [0, -9.81]): it was the
        # first fixed group holding z, or the first vector, that the message blamed.
        raise InvalidField("gravity", f"{d} components, but the case's other vectors have "
                           f"{5 - d} ({', '.join(keys[:3])}{', ...' if len(keys) > 3 else ''})"
                           ": a case's vectors all have 2 components (plane strain) or all 3 "
                           f"(got {list(case.gravity)})")
    for f in case.fixed:
        if f.components is not None and max(f.components) >= d:
            raise InvalidField(f"fixed.{f.name}.components", f"component {max(f.components)} "
                               f"(z) in a plane-strain case (2-component gravity): 0 (x) "
                               f"and 1 (y) only (got {list(f.components)})")
    for key, vector in _vectors(case):
        if len(vector) != d and not (key.endswith("profile.axis") and d == 3):
            raise InvalidField(key, f"{len(vector)} components, but gravity has {d}: a "
                               "case's vectors all have 2 components (plane strain) or all 3 "
                               f"(got {list(vector)})")
    if d == 3:
        if case.gravity[2] != 0.0:
            raise InvalidField("gravity", "a 3D model is y-up, z across the structure (the "
                               "elevation of Goda's loads, the summary's edge pressures, "
                               "the figures' section): gravity's z component must be 0; "
                               "rotate a z-up mesh (e.g. gmsh's affineTransform (x, y, z) "
                               f"-> (x, z, -y)) (got {list(case.gravity)})")
        if case.out_of_plane_length != 1.0:
            raise InvalidField("out_of_plane_length", "a 3D case (3-component gravity) has "
                               "no out-of-plane length: forces and impulses are the bodies' "
                               "own; remove the key (or set it to 1)")
        cal = case.calibration
        if cal.enabled and cal.stiffness_basis != "block":
            raise InvalidField("calibration.stiffness_basis", "a 3D case (3-component "
                               "gravity) calibrates the model's own stiffness: \"block\"")


def general_in_3d(case: _Case) -> None:
    """Refuse what a general pair cannot do in a 3D case (once the mesh is known to be 3D).

    ``integration = "nodes"`` (:func:`breakwater.model.pairs.three_d_general`), and the
    ``goda3d`` generator's hexahedra (the 3D pair's faces are triangles: a tetrahedral
    mesh).

    Raises:
        InvalidField: The first such pair's ``integration`` or ``slave_surface``.
    """
    if dimension(case) == 3:
        for c in case.contact:
            if c.general:
                why = three_d_general(c.integration)
                if why:
                    raise InvalidField(f"contact.{c.name}.integration", why)
                if case.mesh.source == GODA3D:
                    raise InvalidField(f"contact.{c.name}.slave_surface", HEXAHEDRA)


def mesh_problem(case: _Case, gdim: int) -> str | None:
    """Why a mesh of dimension ``gdim`` does not fit the case, or None."""
    d = dimension(case)
    if gdim == d:
        return None
    if gdim < 2:  # cell groups without names (gmsh "Physical Surface(11)") are not read
        return ("the mesh has no named surface (2D) or volume (3D) physical group: name "
                "the bodies' cells in gmsh (Physical Surface(\"name\") or Physical "
                "Volume(\"name\"))")
    if gdim == 3:
        return ("the mesh is 3D but the case is plane strain (2-component gravity): give "
                "gravity, directions, points and velocities 3 components")
    return ("the mesh is 2D but the case is 3D (3-component gravity): give every vector 2 "
            "components, or a mesh with volumes")
