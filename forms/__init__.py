"""The physics of breakwater in pure UFL.

Every function here takes UFL objects (arguments, coefficients, constants, measures,
normals) and returns a UFL expression or form; the contact law
(:mod:`forms.contact`, objects with the law's parameters) also evaluates on NumPy
arrays of nodal values. Nothing here creates a mesh, a function
space or a solver, so the same physics serves the static solve, the GN22 stepper, the
energy ledger and the tests. The functions are dimension-agnostic (plane strain in 2D,
3D alike).
"""

from .contact import (
    ContactLaw,
    PenaltyContact,
    RegularisedCoulomb,
    contact_residual,
    parameter_value,
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
from .gn22_energy import gn22_bulk_dissipation, gn22_contact_dissipation

__all__ = [
    "ContactLaw",
    "PenaltyContact",
    "RegularisedCoulomb",
    "body_force",
    "contact_residual",
    "elastic_residual",
    "external_power",
    "friction_power",
    "gn22_bulk_dissipation",
    "gn22_contact_dissipation",
    "inertia",
    "kinetic_energy",
    "lame_from_shear",
    "lame_from_young",
    "parameter_value",
    "penalty_energy",
    "rayleigh_damping",
    "rayleigh_power",
    "strain",
    "strain_energy",
    "stress",
    "stress_3d",
    "surface_traction",
    "tangential_part",
    "von_mises",
]
