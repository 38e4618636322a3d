"""A case's loads on a mesh: the model's surface loads, the loaded lengths, the summary.

The mesh side of the ``[loads.<name>]`` tables (:mod:`breakwater.casefile.loads`):
:func:`surface_loads` turns a load into the model's
:class:`~breakwater.model.model.SurfaceLoad` (two for a Goda load with uplift: the
uplift under the base, :func:`uplift_profile`); :func:`load_summary` describes it for
the run's summary (a pulse's patch length and peak traction, Goda's pressures and the
part of the profile the face receives). All are collective.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from breakwater.casefile.godaface import check_goda_face, goda_applied
from breakwater.loads.fields import Pressure, PressureProfile, TractionField

if TYPE_CHECKING:
    from dolfinx.io import gmsh as gmshio

    from breakwater.casefile.loads import GodaCase, LoadCase
    from breakwater.model.model import SurfaceLoad
    from breakwater.storms.waves import WaveLoad

__all__ = ["base_triangle", "extent", "group_length", "load_length", "load_summary", "owner",
           "storm_loads", "storm_wave_loads", "surface_loads", "uplift_applied",
           "uplift_profile"]


def group_length(data: gmshio.MeshData, group: str) -> float:
    """Length (m; in 3D area, m²) of a facet group (exterior or interface), all ranks'."""
    import dolfinx
    import ufl
    from dolfinx import fem
    from mpi4py import MPI

    from breakwater.common.errors import CaseError
    from breakwater.model.mesh import group_tag

    msh = data.mesh
    fdim = msh.topology.dim - 1
    tag = group_tag(data, group, fdim)
    ds = ufl.Measure("ds", domain=msh, subdomain_data=data.facet_tags)(tag)
    one = fem.Constant(msh, dolfinx.default_scalar_type(1.0))
    # Interface facets (not on the boundary: ds leaves them out) by dS: their areas in
    # 3D (their diameters, msh.h, were once summed), each on the rank that owns it.
    dS = ufl.Measure("dS", domain=msh, subdomain_data=data.facet_tags)(tag)
    length = msh.comm.allreduce(fem.assemble_scalar(fem.form(one * ds))
                                + fem.assemble_scalar(fem.form(one * dS)), op=MPI.SUM)
    if not length > 0:
        raise CaseError(f"facet group '{group}' has zero {'length' if fdim == 1 else 'area'}")
    return float(length)


def load_length(load: LoadCase, data: gmshio.MeshData) -> float:
    """Length (m; in 3D area, m²) of a load's groups (``group``, then ``groups``)."""
    return sum(group_length(data, g) for g in (load.group, *load.groups))


def group_nodes(data: gmshio.MeshData, group: str) -> Any:
    """The coordinates of a facet group's geometry nodes on this rank, ``(n, 3)``."""
    import dolfinx

    from breakwater.model.mesh import group_tag

    msh = data.mesh
    fdim = msh.topology.dim - 1
    assert data.facet_tags is not None
    facets = data.facet_tags.find(group_tag(data, group, fdim))
    return msh.geometry.x[dolfinx.mesh.entities_to_geometry(msh, fdim, facets).ravel()]


def extent(data: gmshio.MeshData, group: str) -> tuple[Any, Any]:
    """Smallest and largest coordinates (x, y[, z]) of a facet group's vertices (all ranks)."""
    import numpy as np

    msh = data.mesh
    gdim = msh.geometry.dim
    x = group_nodes(data, group)[:, :gdim]
    lo = x.min(axis=0) if len(x) else np.full(gdim, np.inf)
    hi = x.max(axis=0) if len(x) else np.full(gdim, -np.inf)
    return (np.min(msh.comm.allgather(lo), axis=0), np.max(msh.comm.allgather(hi), axis=0))


def base_triangle(uplift_group: str, data: gmshio.MeshData, front: tuple[str, ...],
                  pressure: float = 1.0) -> tuple[PressureProfile, float]:
    """The triangular uplift on the base and the base width B (m).

    ``pressure`` at the base's edge nearest the front face, falling linearly to 0 at
    the heel.
    """
    lo, hi = extent(data, uplift_group)
    ends = [extent(data, g) for g in front]
    front_x = 0.5 * (min(e[0][0] for e in ends) + max(e[1][0] for e in ends))
    width = float(hi[0] - lo[0])
    _check_base(data, uplift_group, front[0], lo, hi)
    if abs(front_x - lo[0]) <= abs(front_x - hi[0]):
        origin, axis = (float(lo[0]), 0.0), (1.0, 0.0)
    else:
        origin, axis = (float(hi[0]), 0.0), (-1.0, 0.0)
    return PressureProfile(((0.0, pressure), (width, 0.0)), axis, origin), width


def _check_base(data: gmshio.MeshData, group: str, front: str, lo: Any, hi: Any) -> None:
    """Refuse an uplift group that is not the horizontal base of the loaded body.

    The uplift pushes into the body: on its top it pushed down, adding to the friction
    (the summary still called it uplift), and on a vertical face the triangle had no
    width (a traceback). Collective.
    """
    import dolfinx
    import numpy as np

    from breakwater.common.errors import CaseError
    from breakwater.model.mesh import group_tag

    width = float(hi[0] - lo[0])
    if not width > 0 or abs(float(hi[1] - lo[1])) > 1e-6 * width:
        raise CaseError(f"uplift_group: '{group}' is not a horizontal base (x from "
                        f"{lo[0]:.6g} to {hi[0]:.6g} m, y from {lo[1]:.6g} to {hi[1]:.6g} m)")
    msh = data.mesh
    tdim = msh.topology.dim
    assert data.cell_tags is not None
    body = owner(data, front)
    cells = data.cell_tags.find(group_tag(data, body, tdim))
    cells = cells[cells < msh.topology.index_map(tdim).size_local]
    y = msh.geometry.x[dolfinx.mesh.entities_to_geometry(msh, tdim, cells).ravel(), 1]
    total, count = msh.comm.allreduce(float(np.sum(y))), msh.comm.allreduce(len(y))
    if count and total / count < float(lo[1]):
        raise CaseError(f"uplift_group: '{group}' is not the base of '{body}' (the body "
                        f"lies below it, at mean y = {total / count:.4g} m against "
                        f"{float(lo[1]):.4g} m): the uplift would push it down")


def uplift_profile(goda: GodaCase, data: gmshio.MeshData, front: tuple[str, ...]
                   ) -> tuple[PressureProfile, float]:
    """Goda's triangular uplift on the base (p_u at the front edge) and the base width B."""
    assert goda.uplift_group is not None
    return base_triangle(goda.uplift_group, data, front, goda.pressure().uplift)


def storm_wave_loads(load: LoadCase, data: gmshio.MeshData) -> tuple[WaveLoad, ...]:
    """Each wave's load of a storm, on the base width of the mesh (collective).

    Raises:
        CaseError: A wave the force-time profile refuses (named).
    """
    from breakwater.common.errors import CaseError

    assert load.storm is not None
    _, width = base_triangle(load.storm.uplift_group, data, (load.group, *load.groups))
    try:
        return load.storm.wave_loads(width)
    except ValueError as e:
        raise CaseError(f"loads.{load.name}.storm: {e}") from None


def surface_loads(load: LoadCase, data: gmshio.MeshData, out_of_plane_length: float
                  ) -> list[SurfaceLoad]:
    """The model loads of a case's load on a mesh.

    One per group (``group``, then ``groups``), plus the uplift of a Goda load.

    Raises:
        CaseError: A Goda profile entirely off its loaded face (:func:`check_goda_face`;
            part of it off: a warning).

    """
    from breakwater.model.model import SurfaceLoad

    if load.goda is not None:
        check_goda_face(load, data, warn=False)  # warned by casefile.build.build

    groups = (load.group, *load.groups)
    if load.storm is not None:
        return storm_loads(load, data, storm_wave_loads(load, data))
    if load.kind == "pulse":
        pulse = load.pulse(out_of_plane_length, load_length(load, data))
        return [SurfaceLoad(g, load.direction, pulse, body=load.body, name=load.name)
                for g in groups]
    factor = load.time_factor()
    d = load.direction
    field: TractionField | None = None
    t = 0.0
    if load.force is not None:
        t = load.force / out_of_plane_length / load_length(load, data)
    elif load.traction is not None:
        t = load.traction
    elif load.pressure is not None:
        field = Pressure(load.pressure)
    elif load.profile is not None:
        field = load.profile.field()
    else:
        assert load.goda is not None
        field = load.goda.front()
    direction = tuple(t * c for c in d) if field is None else ()
    loads = [SurfaceLoad(g, direction, factor, field, load.body, load.name) for g in groups]
    if load.goda is not None and load.goda.uplift_group is not None:
        profile, _ = uplift_profile(load.goda, data, groups)
        body = load.body or owner(data, load.group)
        loads.append(SurfaceLoad(load.goda.uplift_group, (), factor, profile, body, load.name))
    return loads


def storm_loads(load: LoadCase, data: gmshio.MeshData, waves: Sequence[WaveLoad]
                ) -> list[SurfaceLoad]:
    """A storm's model loads: the front (its shape staged per wave) × p₁, the uplift × p_u.

    Raises:
        CaseError: Waves that do not follow one another
            (:func:`~breakwater.storms.stormload.check_wave_loads`).
    """
    from breakwater.common.errors import CaseError
    from breakwater.model.model import SurfaceLoad
    from breakwater.storms.stormload import WaveHistory, front_field

    storm = load.storm
    assert storm is not None
    groups = (load.group, *load.groups)
    try:
        field = front_field(waves, storm.still_water_level)
    except ValueError as e:
        raise CaseError(f"loads.{load.name}.storm: {e}") from None
    p1, pu = WaveHistory(tuple(waves), "p1"), WaveHistory(tuple(waves), "uplift")
    loads = [SurfaceLoad(g, (), p1, field, load.body, load.name) for g in groups]
    triangle, _ = base_triangle(storm.uplift_group, data, groups)
    body = load.body or owner(data, load.group)
    loads.append(SurfaceLoad(storm.uplift_group, (), pu, triangle, body, load.name))
    return loads


def owner(data: gmshio.MeshData, group: str) -> str:
    """The name of the one cell group next to a facet group (the loaded body)."""
    from breakwater.common.errors import CaseError
    from breakwater.model.mesh import group_tag

    msh = data.mesh
    tdim = msh.topology.dim
    assert data.facet_tags is not None and data.cell_tags is not None
    msh.topology.create_connectivity(tdim - 1, tdim)
    f2c = msh.topology.connectivity(tdim - 1, tdim)
    cell_tag = dict(zip(data.cell_tags.indices.tolist(), data.cell_tags.values.tolist(),
                        strict=True))
    values = {cell_tag[c] for f in data.facet_tags.find(group_tag(data, group, tdim - 1))
              for c in f2c.links(f).tolist() if c in cell_tag}
    values = set().union(*msh.comm.allgather(values))
    names = [name for name, (dim, tag) in data.physical_groups.items()
             if dim == tdim and tag in values]
    if len(names) != 1:
        raise CaseError(f"facet group '{group}' borders {len(names)} bodies: name the body "
                        "loaded (body = ...)")
    return names[0]


def load_summary(load: LoadCase, data: gmshio.MeshData, out_of_plane_length: float
                 ) -> dict[str, Any]:
    """The load as the run's summary describes it."""
    h = load_length(load, data)
    info: dict[str, Any] = {"group": load.group}
    if load.groups:
        info["groups"] = list(load.groups)
    if load.kind == "pulse":
        pulse = load.pulse(out_of_plane_length, h)
        info.update({
            "impulse": load.total_impulse,
            "impulse_per_length": load.total_impulse / out_of_plane_length,
            "patch_length": h,
            "shape": load.shape,
            "duration": load.duration,
            "start": load.start,
            "peak_traction": pulse.maximum,
            "peak_force_per_length": pulse.maximum * h,
            "direction": list(load.direction),
        })
        if load.pendulum is not None:
            info["impact_velocity"] = load.pendulum.velocity
        return info
    if load.storm is not None:
        info.update({"time_function": "storm", "magnitude": "storm", "patch_length": h})
        return info  # and its "storm" entry: casefile.stormbuild.storm_outputs
    info.update({"time_function": load.kind, "magnitude": load.magnitude,
                 "patch_length": h, "start": load.start})
    if load.rise is not None:
        info["rise"] = load.rise
    if load.force is not None:
        info["force_per_length"] = load.force / out_of_plane_length
        info["traction"] = load.force / out_of_plane_length / h
    elif load.traction is not None:
        info["traction"] = load.traction
        info["force_per_length"] = load.traction * h
    elif load.pressure is not None:
        info["pressure"] = load.pressure
    elif load.goda is not None:
        info.update(_goda_summary(load, data))
    return info


def _goda_summary(load: LoadCase, data: gmshio.MeshData) -> dict[str, Any]:
    """A Goda load's summary entries (collective).

    In plane strain the forces and moments are per metre (``_per_length``); in 3D
    :func:`breakwater.outputs.summary.whole_body_keys` drops that suffix: the applied
    front force and moment are then the whole face's (:func:`goda_applied`), the uplift
    the whole base's (:func:`uplift_applied`), and the formula's own P and M_P, per
    metre of breakwater, are ``goda_force_per_metre`` and ``goda_moment_per_metre``.
    """
    assert load.goda is not None
    g = load.goda.pressure()
    applied = goda_applied(load, data)
    per = "_per_length" if applied.width is None else "_per_metre"
    info: dict[str, Any] = {
        "wavelength": g.wavelength, "alpha1": g.alpha1, "alpha2": g.alpha2,
        "alpha3": g.alpha3, "eta_star": g.eta_star, "p1": g.p1, "p3": g.p3, "p4": g.p4,
        "uplift_pressure": g.uplift, "horizontal_force_per_length": applied.force,
        "horizontal_moment_per_length": applied.moment,
        "applied_fraction": applied.fraction, "face_elevations": list(applied.face),
        "profile_elevations": list(applied.profile), f"goda_force{per}": g.force,
        f"goda_moment{per}": g.moment}
    if applied.width is not None:
        info["face_width"] = applied.width
    if g.alpha_impulsive is not None:
        info.update({"alpha_impulsive": g.alpha_impulsive, "alpha_star": g.alpha_star})
    if load.goda.uplift_group is not None:
        profile, width = uplift_profile(load.goda, data, (load.group, *load.groups))
        force, moment = (uplift_applied(profile, width, data, load.goda.uplift_group)
                         if applied.width is not None else
                         (g.uplift_force(width), g.uplift_moment(width)))
        info.update({"base_width": width, "uplift_force_per_length": force,
                     "uplift_moment_per_length": moment})
    return info


def uplift_applied(profile: PressureProfile, width: float, data: gmshio.MeshData,
                   group: str) -> tuple[float, float]:
    """The vertical force (N) of a 3D uplift on its base, and its moment about the heel.

    ∫ p |n_y| dA over the base's facets: their projections on a horizontal plane, where
    p (a function of x only) is integrated exactly
    (:func:`~breakwater.casefile.godaface.section_integrals`); the moment (N m) about
    the horizontal line across the base at its heel, s = B (collective).
    """
    import numpy as np
    from mpi4py import MPI

    from breakwater.casefile.godaface import facet_triangles, section_integrals

    triangles = facet_triangles(data, (group,))
    s = profile.coordinate(triangles)
    triangles[:, :, 1] = 0.0  # the projection on a horizontal plane
    force, moment = section_integrals(triangles, s, profile.points, width)
    force, moment = data.mesh.comm.allreduce(np.array([force, -moment]), op=MPI.SUM)
    return float(force), float(moment)

