"""The parts of a contact model: materials, bodies, boundary conditions, loads, damping.

The settings a model is built from (:class:`Material`, :class:`Body`, :class:`Fixed`,
:class:`SurfaceLoad`, :class:`Damping`) and what the model builds for a body
(:class:`BodyData`) and a load (:class:`LoadData`); the pairs are
:mod:`breakwater.model.pairs`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import ClassVar, cast

import dolfinx
import ufl
from dolfinx import fem

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.config.fields import InvalidField
from breakwater.config.frozen import assignment_hint
from breakwater.config.typecheck import check_fields
from breakwater.loads.fields import StagedField, TractionField
from breakwater.model.built import REBUILD, BuiltPart

__all__ = ["Body", "BodyData", "Damping", "Fixed", "LoadData", "Material", "StageWatch",
           "SurfaceLoad"]


@assignment_hint(REBUILD)
@dataclass(frozen=True)
class Material:
    """Linear isotropic elastic material.

    Give exactly one of ``shear_modulus`` or ``young_modulus``.

    Attributes:
        density: Mass density ρ (kg/m³).
        poisson: Poisson's ratio ν (-), in (-1, 1/2).
        shear_modulus: Shear modulus G (Pa).
        young_modulus: Young's modulus E (Pa).

    """

    density: float
    poisson: float
    shear_modulus: float | None = None
    young_modulus: float | None = None

    def __post_init__(self) -> None:
        if (self.shear_modulus is None) == (self.young_modulus is None):
            raise ValueError("give exactly one of shear_modulus and young_modulus")
        if not self.density > 0:
            raise ValueError(f"density must be > 0 (got {self.density})")
        if not -1.0 < self.poisson < 0.5:
            raise ValueError(f"poisson must be in (-1, 0.5) (got {self.poisson})")
        modulus = self.shear_modulus if self.young_modulus is None else self.young_modulus
        if not modulus > 0:  # type: ignore[operator]
            raise ValueError(f"elastic modulus must be > 0 (got {modulus})")

    @property
    def G(self) -> float:
        """Shear modulus (Pa)."""
        return self.lame[1]

    @property
    def E(self) -> float:
        """Young's modulus (Pa)."""
        return 2.0 * self.G * (1.0 + self.poisson)

    @property
    def lame(self) -> tuple[float, float]:
        """Lamé parameters (λ, μ) in Pa."""
        if self.shear_modulus is not None:
            return forms.lame_from_shear(self.shear_modulus, self.poisson)
        assert self.young_modulus is not None
        return forms.lame_from_young(self.young_modulus, self.poisson)

    @property
    def p_wave_speed(self) -> float:
        """Speed of dilatational waves, sqrt((λ + 2μ)/ρ) (m/s)."""
        λ, μ = self.lame
        return math.sqrt((λ + 2.0 * μ) / self.density)

    @property
    def constrained_modulus(self) -> float:
        """Oedometric modulus λ + 2μ (Pa): the 1D plane-strain bar modulus."""
        λ, μ = self.lame
        return λ + 2.0 * μ


@assignment_hint(REBUILD)
@dataclass(frozen=True)
class Body:
    """A deformable body: a named cell group and its material."""

    name: str
    material: Material


@assignment_hint(REBUILD)
@dataclass(frozen=True)
class Fixed:
    """Zero displacement on a named facet group, or at the vertices of a point group.

    Attributes:
        group: Facet (dimension tdim − 1) or point (dimension 0) group name.
        components: Displacement components fixed (0 = x, 1 = y, 2 = z); None for all.

    """

    group: str
    components: tuple[int, ...] | None = None


@assignment_hint(REBUILD)
@dataclass(frozen=True)
class SurfaceLoad:
    """A traction ``amplitude(t) × field`` (Pa) on a named facet group.

    Attributes:
        group: Facet group on the boundary of one body (or an interface between two
            bodies, with ``body`` naming the side loaded).
        direction: Traction per unit amplitude (a vector of the geometric dimension);
            empty when ``field`` gives it.
        amplitude: Time function t ↦ scale factor.
        field: Traction per unit amplitude as a UFL expression of the position and the
            outward normal of the body (:mod:`breakwater.loads.fields`), or one that
            changes at given times (a :class:`~breakwater.loads.fields.StagedField`);
            None: the constant ``direction``.
        body: The body loaded; None: the one body whose boundary holds the group.
        name: The load of the case it comes from (the summary's applied loads).

    """

    group: str
    direction: tuple[float, ...]
    amplitude: Callable[[float], float]
    field: TractionField | StagedField | None = None
    body: str | None = None
    name: str | None = None

    def unit_traction(self, x: ufl.core.expr.Expr, n: ufl.core.expr.Expr,
                      c: ufl.core.expr.Expr | None = None) -> ufl.core.expr.Expr:
        """The traction per unit amplitude at ``x`` (outward normal ``n``).

        Args:
            x: The position.
            n: The outward unit normal of the body.
            c: A staged field's parameters (a ``fem.Constant``; else unused).
        """
        if isinstance(self.field, StagedField):
            assert c is not None
            return self.field.traction_with(x, n, c)
        if self.field is not None:
            return self.field.traction(x, n)
        return ufl.as_vector(self.direction)


@assignment_hint("model.damping = dataclasses.replace(model.damping, {name}=...)")
@dataclass(frozen=True)
class Damping:
    """Rayleigh damping C = αM + βK (α in 1/s, β in s), the same for every body."""

    alpha: float = 0.0
    beta: float = 0.0

    def __post_init__(self) -> None:
        # As the case's [damping] (a negative coefficient feeds energy in): from Python,
        # model.damping = Damping(-1.0) ran. The types as every setting's (check_fields):
        # a NumPy number is taken, stored as a float (np.float32 was refused, 1 kept as int).
        try:
            check_fields(self)
        except InvalidField as e:
            raise ValueError(f"damping {e}") from None
        for name in ("alpha", "beta"):
            if getattr(self, name) < 0:
                raise ValueError(f"damping {name} must be a number >= 0 "
                                 f"(got {getattr(self, name)!r})")


@dataclass
class BodyData(BuiltPart):
    """What the model builds for one body; fixed (:class:`~breakwater.model.built.BuiltPart`)."""

    FIXED: ClassVar[frozenset[str]] = frozenset(
        ("spec", "index", "submesh", "cell_map", "facet_tags", "V", "dx", "ρ", "λ", "μ",
         "vertex_map"))
    WHERE: ClassVar[str] = "model.bodies[k]"

    spec: Body
    index: int
    submesh: dolfinx.mesh.Mesh
    cell_map: dolfinx.mesh.EntityMap
    facet_tags: dolfinx.mesh.MeshTags
    V: fem.FunctionSpace
    dx: ufl.Measure
    ρ: fem.Constant
    λ: fem.Constant
    μ: fem.Constant
    vertex_map: dolfinx.mesh.EntityMap | None = None  # submesh vertex -> parent vertex


@dataclass
class LoadData(BuiltPart):
    """What the model builds for one load: ``traction = amplitude × unit``.

    A staged field's ``unit`` reads its parameters from ``parameters`` (a
    ``fem.Constant``), set for the stage holding the load time by :meth:`set_stage`;
    ``version`` counts the changes, so that whoever assembled ``unit`` into a vector
    (the fast solver's load vectors, the ledger, the applied loads) knows when to
    assemble it again. Its settings and forms are fixed
    (:class:`~breakwater.model.built.BuiltPart`), its stage is not.
    """

    FIXED: ClassVar[frozenset[str]] = frozenset(
        ("spec", "body", "ds", "amplitude", "unit", "parameters", "unit_with", "traction"))
    WHERE: ClassVar[str] = "model.loads[k]"

    spec: SurfaceLoad
    body: int
    ds: ufl.Measure
    amplitude: fem.Constant
    unit: ufl.core.expr.Expr
    parameters: fem.Constant | None = None
    stage: int = 0
    version: int = 0
    unit_with: Callable[[ufl.core.expr.Expr], ufl.core.expr.Expr] | None = None
    """A staged field's traction per unit amplitude for other parameters (the ledger's
    at the start of a step); None for a fixed field."""
    traction: ufl.core.expr.Expr = field(init=False)

    def __post_init__(self) -> None:
        self.traction = self.amplitude * self.unit

    def set_stage(self, t: float) -> None:
        """Set a staged field's parameters for the stage holding time ``t``."""
        if self.parameters is None:  # a fixed field (only a staged one has parameters)
            return
        # (Not isinstance(f, StagedField): a runtime Protocol check takes 10 µs, at
        # every step of a storm.)
        f = cast(StagedField, self.spec.field)
        k = f.stage(t)
        if k != self.stage:
            self.parameters.value[:] = f.parameters(k)
            self.stage = k
            self.version += 1


class StageWatch:
    """The staged loads (``LoadData.parameters``) whose stage changed since the last look.

    Whoever assembled a staged load's ``unit`` (the fast solver's load vectors, the
    ledger's columns, the applied loads' resultants) asks :meth:`changed` which to
    assemble again.

    Args:
        loads: The model's loads (``ContactModel.loads``).
    """

    def __init__(self, loads: Sequence[LoadData]) -> None:
        self._loads = loads
        self._seen = {k: ld.version for k, ld in enumerate(loads) if ld.parameters is not None}

    def __bool__(self) -> bool:
        """Whether any load is staged."""
        return bool(self._seen)

    def changed(self) -> list[int]:
        """The indices of the loads whose stage changed since the last call (now seen)."""
        out = [k for k, seen in self._seen.items() if self._loads[k].version != seen]
        for k in out:
            self._seen[k] = self._loads[k].version
        return out
