"""Meshes of the breakwater case (gmsh geometry and format conversion)."""

from .export import convert, read
from .goda import (
    BASE,
    CAISSON,
    CAISSON_BASE,
    CAISSON_FRONT,
    CAISSON_REAR,
    CAISSON_TOP,
    CORNER_FRONT,
    CORNER_REAR,
    GAUGE_BOTTOM,
    GAUGE_TOP,
    IMPACT,
    INTERFACE,
    MOUND,
    MOUND_CREST,
    MOUND_SURFACE,
    PHYSICAL_GROUPS,
    SEPARATE_PHYSICAL_GROUPS,
    GodaGeometry,
    build_model,
    generate,
    gmsh_session,
)
from .goda3d import (
    CAISSON_SIDES,
    MOUND_SIDES,
    Goda3DGeometry,
)
from .goda3d import PHYSICAL_GROUPS as PHYSICAL_GROUPS_3D
from .goda3d import build_model as build_model3d
from .goda3d import generate as generate3d

__all__ = [
    "BASE",
    "CAISSON",
    "CAISSON_BASE",
    "CAISSON_FRONT",
    "CAISSON_REAR",
    "CAISSON_SIDES",
    "CAISSON_TOP",
    "CORNER_FRONT",
    "CORNER_REAR",
    "GAUGE_BOTTOM",
    "GAUGE_TOP",
    "IMPACT",
    "INTERFACE",
    "MOUND",
    "MOUND_CREST",
    "MOUND_SIDES",
    "MOUND_SURFACE",
    "PHYSICAL_GROUPS",
    "PHYSICAL_GROUPS_3D",
    "SEPARATE_PHYSICAL_GROUPS",
    "Goda3DGeometry",
    "GodaGeometry",
    "build_model",
    "build_model3d",
    "convert",
    "generate",
    "generate3d",
    "gmsh_session",
    "read",
]
