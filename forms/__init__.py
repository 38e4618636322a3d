"""The physics of breakwater in pure UFL.

Every function here takes UFL objects (arguments, coefficients, constants, measures,
normals) and returns a UFL expression or form. Nothing here creates a mesh, a function
space or a solver, so the same physics serves the static solve, the GN22 stepper, the
energy ledger and the tests. The functions are dimension-agnostic (plane strain in 2D,
3D alike).
"""

from .contact import (
    contact_residual,
    contact_traction,
    friction_traction,
    normal_gap,
    penalty_pressure,
    slip_direction,
    tangential_part,
)
from .elasticity import (
    body_force,
    elastic_residual,
    inertia,
    lame_from_shear,
    lame_from_young,
    rayleigh_damping,
    strain,
    stress,
    stress_3d,
    surface_traction,
    von_mises,
)
from .energy import (
    external_power,
    friction_power,
    kinetic_energy,
    penalty_energy,
    rayleigh_power,
    strain_energy,
)

__all__ = [
    "body_force",
    "contact_residual",
    "contact_traction",
    "elastic_residual",
    "external_power",
    "friction_power",
    "friction_traction",
    "inertia",
    "kinetic_energy",
    "lame_from_shear",
    "lame_from_young",
    "normal_gap",
    "penalty_energy",
    "penalty_pressure",
    "rayleigh_damping",
    "rayleigh_power",
    "slip_direction",
    "strain",
    "strain_energy",
    "stress",
    "stress_3d",
    "surface_traction",
    "tangential_part",
    "von_mises",
]
