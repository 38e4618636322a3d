"""From a case to a run: the mesh, the calibration, the model, the time and output specs.

The functions behind :meth:`Case.mesh_file <breakwater.casefile.case.Case.mesh_file>`,
:meth:`~breakwater.casefile.case.Case.read_mesh`,
:meth:`~breakwater.casefile.case.Case.build_model`,
:meth:`~breakwater.casefile.case.Case.calibrate` and
:meth:`~breakwater.casefile.case.Case.build`. The case is never changed: :func:`build`
returns the case as run (with a calibrated modulus written in) in its :class:`BuiltCase`.
They take the case's settings (:class:`~breakwater.casefile.settings.CaseSettings`, the
data of a :class:`~breakwater.casefile.case.Case`): reading a case does not import
this module, which needs the solver stack.
"""

from __future__ import annotations

import pathlib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from mpi4py import MPI

from breakwater.casefile.dimension import mesh_problem
from breakwater.casefile.godaface import check_goda_face, goda_quadrature
from breakwater.casefile.loadchecks import (
    face_problems,
    landing_problems,
    late_peak_warning,
    pulling_warning,
    pulse_warning,
    start_warning,
    table_warning,
)
from breakwater.casefile.meshloads import load_summary, surface_loads
from breakwater.casefile.stormbuild import storm_outputs
from breakwater.casefile.tables import GODA3D
from breakwater.common.errors import CaseError, MeshError
from breakwater.config.runspec import InitialSpec, OutputSpec, PairProbeSpec, ProbeSpec, TimeSpec
from breakwater.contact.surfaces import SurfacePair, check_faces
from breakwater.model.mesh import group_points, group_tag, mesh_geo
from breakwater.model.mesh import read_mesh as _read_msh
from breakwater.model.model import Body, ContactModel, ContactPair, Damping, Fixed, SurfaceLoad
from breakwater.outputs.bodysizes import unit_checks
from breakwater.statics.initial import unsupported, velocity_conflict
from breakwater.statics.rigidmodes import loose_modes
from breakwater.stepping.stepsize import resolved_step

if TYPE_CHECKING:
    from dolfinx.io import gmsh as gmshio

    from breakwater.casefile.settings import CaseSettings
    from breakwater.statics.calibrate import CalibrationResult

__all__ = ["BuiltCase", "build", "build_model", "calibrate", "mesh_file", "read_mesh"]


@dataclass(frozen=True)
class BuiltCase:
    """What the run layer needs, built from a case; unpacks as ``model, time, output, extra``.

    Attributes:
        case: The case as run: after a calibration, the calibrated shear modulus is
            written into its body and ``calibration.enabled`` is false, so that
            ``case.resolved()`` reproduces the run without calibrating again.
        model: The contact model.
        time: Time integration settings.
        output: What to write and where.
        extra: The mesh, the loads and the calibration (if any), for the run's summary.

    """

    case: CaseSettings
    model: ContactModel
    time: TimeSpec
    output: OutputSpec
    extra: dict[str, Any]

    def __iter__(self) -> Iterator[Any]:
        """``model, time, output, extra`` (the case stays an attribute)."""
        return iter((self.model, self.time, self.output, self.extra))


def mesh_file(case: CaseSettings, comm: MPI.Comm, directory: str | pathlib.Path | None = None
              ) -> pathlib.Path:
    """The gmsh ``.msh`` file of the case (collective).

    The Goda mesh is generated into ``<directory>/mesh/goda.msh`` (the 3D one into
    ``goda3d.msh``) and a ``.geo`` script
    is meshed into ``<directory>/mesh/<stem>.msh`` (default directory: the output
    folder; nothing is written beside the user's script); a ``.msh`` source is the
    case's file. A ``.geo`` with curved curves is meshed to the displacement's degree
    (:func:`breakwater.model.mesh.mesh_geo`: curved P2 cells).

    Raises:
        MeshError: gmsh cannot mesh the ``.geo`` script.

    """
    source = pathlib.Path(case.mesh.source)
    if not case.mesh.generated and source.suffix != ".geo":
        return source
    folder = pathlib.Path(directory) if directory is not None else case.output_directory
    if not case.mesh.generated:
        return mesh_geo(source, folder / "mesh" / f"{source.stem}.msh", comm,
                        order=case.mesh.degree)
    from breakwater import meshes  # type: ignore[attr-defined]  # breakwater.meshes maps to meshes/

    if case.mesh.source == GODA3D:
        return meshes.generate3d(folder / "mesh" / "goda3d.msh", case.mesh.goda3d,
                                 refinement=case.mesh.refinement, comm=comm)
    return meshes.generate(folder / "mesh" / "goda.msh", case.mesh.goda,
                           refinement=case.mesh.refinement, comm=comm)


def read_mesh(case: CaseSettings, comm: MPI.Comm, directory: str | pathlib.Path | None = None
              ) -> gmshio.MeshData:
    """Generate (or find) and read the mesh of the case, distributed over ``comm``.

    Raises:
        CaseError: The mesh cannot be made or read (``mesh.source: ...``).

    """
    msh = None
    try:
        msh = mesh_file(case, comm, directory)
        data = _read_msh(msh, comm)
    except MeshError as e:
        text, source = str(e), pathlib.Path(case.mesh.source)
        if msh is not None and msh != source and text.startswith(f"{msh}:"):
            # A .geo's mesh refused: the user's file first (they wrote the .geo).
            text = f"{source} (meshed into {msh}){text[len(str(msh)):]}"
        raise CaseError(f"mesh.source: {text}") from e
    problem = mesh_problem(case, data.mesh.geometry.dim)
    if problem is not None:
        raise CaseError(f"mesh.source: {problem}")
    return data


def build_model(case: CaseSettings, data: gmshio.MeshData,
                shear_moduli: Mapping[str, float] | None = None,
                dynamic: bool = True, calibrating: bool = False) -> ContactModel:
    """The contact model of the case on a mesh.

    Args:
        case: The case.
        data: The mesh (see :func:`read_mesh`).
        shear_moduli: Shear moduli (Pa) replacing the case's, by body name (the
            calibrated body gives none: it must be here).
        dynamic: Include the loads, gravity and damping (False: the bare elastic
            bodies, contact pairs and fixed boundaries, for the calibration).
        calibrating: A shear modulus is calibrated on the case first: bodies held by
            nothing and free rigid modes are refused whatever the initial state
            (:func:`~breakwater.statics.initial.unsupported`).

    """
    moduli = shear_moduli or {}
    bodies = [Body(b.name, b.material(moduli.get(b.name))) for b in case.bodies]
    pairs = [ContactPair(c.name, c.slave, c.master, c.penalty, c.friction,
                         c.regularisation, c.gap) for c in case.contact if not c.general]
    surface_pairs = [SurfacePair(c.name, c.slave, c.master, c.slave_surface or "",
                                 c.master_surface or "", c.penalty, c.friction,
                                 c.regularisation, c.points, c.integration,
                                 c.rotations)
                     for c in case.contact if c.general]
    fixed = [Fixed(f.name, f.components) for f in case.fixed]
    loads: list[SurfaceLoad] = []
    owner: list[str] = []  # the case load each model load comes from
    if dynamic:
        for ld in case.loads:
            if ld.enabled:
                made = surface_loads(ld, data, case.out_of_plane_length)
                owner += [ld.name] * len(made)
                loads += made
    model = ContactModel(data, bodies, pairs, fixed, loads,
                         gravity=case.gravity if dynamic else None,
                         damping=Damping(case.damping.alpha, case.damping.beta)
                         if dynamic else None,
                         degree=case.mesh.degree, surface_pairs=surface_pairs)
    check_faces(model)  # (before any search: the rigid modes, a calibration)
    if dynamic:
        names = case.initial.loads
        model.initial = InitialSpec(
            velocities=tuple((b.name, b.initial_velocity) for b in case.bodies
                             if any(b.initial_velocity)),
            loads=None if names is None else tuple(k for k, name in enumerate(owner)
                                                   if name in names),
            loading=case.initial.loading, tolerance=case.initial.tolerance,
            undeformed=case.initial.undeformed)
        for b in case.bodies:
            why = velocity_conflict(model, b.name, b.initial_velocity) \
                if any(b.initial_velocity) else None
            if why is not None:
                raise CaseError(f"bodies.{b.name}.initial_velocity: {why}")
        why = unsupported(model, calibrating)
        if why is not None:
            raise CaseError(why)
    return model


def calibrate(case: CaseSettings, data: gmshio.MeshData, target: float | None = None
              ) -> CalibrationResult:
    """Calibrate the shear modulus of ``calibration.body`` (see :mod:`.calibrate`).

    The case is checked first, as the run checks it (:func:`_checked_model`, which
    ``python -m breakwater calibrate`` and a run that calibrates share): a body held by
    nothing or a free rigid mode (whose stiffness is singular) is refused in one line
    before any solve.

    Args:
        case: The case.
        data: The mesh.
        target: Target stiffness (N/m), read as ``calibration.stiffness_basis`` says
            (``"block"``: divided by ``out_of_plane_length``); ``calibration.stiffness``
            if None.

    """
    from breakwater.statics.calibrate import calibrate_shear_modulus

    cal = case.calibration
    k = _calibration_target(case, target)
    _checked_model(case, data, guess=cal.body)
    model = build_model(case, data, {cal.body: cal.initial_guess}, dynamic=False)
    return calibrate_shear_modulus(model, cal.body, cal.structure,
                                   cal.per_metre(k, case.out_of_plane_length), cal.tolerance,
                                   cal.initial_guess, cal.tangential_penalty,
                                   cal.max_iterations)


def _calibration_target(case: CaseSettings, target: float | None = None) -> float:
    """The calibration's target stiffness, its bodies checked (a :class:`CaseError`)."""
    cal = case.calibration
    names = [b.name for b in case.bodies]
    for key in ("body", "structure"):  # checked by the case only when enabled
        if getattr(cal, key) not in names:
            raise CaseError(f"calibration.{key}: no body named '{getattr(cal, key)}' "
                            f"(bodies: {', '.join(names)})")
    k = cal.stiffness if target is None else target
    if k is None:
        raise CaseError("calibration.stiffness: missing (the target stiffness, N/m)")
    if not k > 0:
        raise CaseError(f"calibration target stiffness must be > 0 (got {k:g})")
    return k


def _checked_model(case: CaseSettings, data: gmshio.MeshData,
                   guess: str | None = None) -> ContactModel:
    """The case's dynamic model, refused in one line if it cannot run (collective).

    Every check of the model that its moduli do not change: the bodies' supports and
    free rigid modes, gravity's direction (:func:`~breakwater.statics.initial.
    unsupported`), a body strained by its own weight, a load that applies nothing, two
    storms. With ``guess`` (the body to calibrate, then at its initial guess) they run
    before the calibration (a goda3d case with gravity up calibrated 24 s before its
    refusal), with the calibration's own (a free rigid mode whatever the initial state):
    its own weight's strain is checked after, with its calibrated modulus.
    """
    moduli = {} if guess is None else {guess: case.calibration.initial_guess}
    try:
        model = build_model(case, data, moduli, dynamic=True, calibrating=guess is not None)
    except MeshError as e:
        raise CaseError(f"{'mesh' if case.mesh.generated else case.mesh.source}: {e}") from e
    strained = _self_weight_problem(model, skip=guess)
    if strained is not None:
        raise CaseError(strained)
    for ld in case.loads:
        if ld.enabled:
            error, _ = face_problems(ld, model)
            if error is not None:
                raise CaseError(error)
    storms = [ld.name for ld in case.loads if ld.enabled and ld.storm is not None]
    if len(storms) > 1:
        raise CaseError(f"loads.{storms[1]}.storm: one storm per case (loads.{storms[0]} "
                        "is one): waves.csv records one")
    return model


def build(case: CaseSettings, comm: MPI.Comm | None = None) -> BuiltCase:
    """Mesh, calibrate (if asked) and build what the run layer needs (collective).

    The Goda mesh is generated into ``<output directory>/mesh/goda.msh`` (a ``.geo``
    script is meshed into ``<output directory>/mesh/<stem>.msh``).

    Returns:
        The :class:`BuiltCase` (``model, time, output, extra = build(case)``).

    Raises:
        CaseError: The mesh does not fit the case (e.g. a Goda profile off its loaded
            face, :func:`~breakwater.casefile.godaface.check_goda_face`; warned when partly off).
        CalibrationError: The calibration failed.
        TypeError: ``comm`` not a communicator (one line; ``case.build("x")`` failed in
            dolfinx with ``'str' object has no attribute 'size'``).

    """
    if comm is not None and not isinstance(comm, MPI.Intracomm):
        raise TypeError("build: comm: expected an MPI communicator (e.g. MPI.COMM_WORLD, or "
                        f"None: every rank), got {type(comm).__name__}")
    comm = MPI.COMM_WORLD if comm is None else comm
    data = read_mesh(case, comm)
    # Before the calibration: a misplaced Goda profile fails fast (its exact integral
    # over the face kept for goda_quadrature below).
    exact = {ld.name: check_goda_face(ld, data) for ld in case.loads
             if ld.enabled and ld.goda is not None}
    extra: dict[str, Any] = {"mesh": _mesh_summary(case, data)}
    probes, pair_probes = _probe_points(case, data)  # checked before the heavy work
    if case.calibration.enabled:
        result = calibrate(case, data)  # the case checked first, as the calibrate command
        case = case.calibrated(result.body, result.shear_modulus)
        extra["calibration"] = result.summary()
    model = _checked_model(case, data)
    loose = loose_modes(model)  # rigid modes only contact holds: logged when the run starts
    if loose:
        extra["mesh"].setdefault("warnings", []).extend(loose)
    units = unit_checks(model)
    extra["mesh"]["bodies"] = units["bodies"]
    if "warnings" in units:
        extra["mesh"].setdefault("warnings", []).extend(units["warnings"])
    extra["loads"] = {ld.name: load_summary(ld, data, case.out_of_plane_length)
                      for ld in case.loads if ld.enabled}
    for ld in case.loads:
        if not ld.enabled:
            continue
        _, warning = face_problems(ld, model)  # its error: refused in _checked_model
        t = case.time
        dt = t.dt  # the step inside a pulse: adaptive steps resolve its segments
        if t.adaptive and ld.kind == "pulse":
            dt = resolved_step(t.dt, t.levels, ld.pulse(1.0, 1.0).breakpoints)
        in_state = case.initial.loads is None or ld.name in case.initial.loads
        pulse, sampled = pulse_warning(ld, dt, t.end_time, t.beta1, in_state)
        start = start_warning(ld, in_state, t.dt)
        landing = late = None
        if ld.kind == "table" and ld.table is not None:
            late = late_peak_warning(ld, t.end_time)
            steps = (resolved_step(t.dt, t.levels, ld.table.history(ld.start).breakpoints)
                     if t.adaptive else t.dt)
            pulse = table_warning(ld, steps, t.end_time)
            error, landing = (landing_problems(ld, t.dt, t.end_time, t.max_steps)
                              if t.adaptive else (None, None))
            if error is not None:
                raise CaseError(error)
        if sampled:
            extra["loads"][ld.name]["sampled"] = sampled
        quadrature = None
        if ld.goda is not None:  # what the facets apply, beside the exact integral
            entries, quadrature = goda_quadrature(ld, model, exact[ld.name])
            extra["loads"][ld.name].update(entries)
        # Logged when the run starts (not again when it resumes), kept in the summary.
        lines = [line for line in (warning, start, pulse, late, landing, quadrature,
                                   pulling_warning(ld, model)) if line is not None]
        if lines:
            extra["loads"][ld.name]["warnings"] = lines

    for ld in case.loads:  # a storm's record: probes at the ends of the caisson's base
        if ld.enabled and ld.storm is not None:
            more, info = storm_outputs(case, data, ld, model)
            extra["loads"][ld.name]["storm"] = info
            if info["warnings"]:  # logged when the run starts
                extra["loads"][ld.name].setdefault("warnings", []).extend(info["warnings"])
            taken = {q.name for q in pair_probes} & {q.name for q in more}
            if taken:
                raise CaseError(f"output.pair_probes.{sorted(taken)[0]}: the name is the "
                                f"probe of loads.{ld.name}'s per-wave record (rename it)")
            pair_probes += more
    o = case.output
    output = OutputSpec(directory=case.output_directory, field_interval=o.field_interval,
                        probes=probes, pair_probes=pair_probes, figures=o.figures,
                        case_name=case.name, checkpoint_interval=o.checkpoint_interval)
    return BuiltCase(case, model, case.time, output, extra)


def _probe_points(case: CaseSettings, data: gmshio.MeshData
                  ) -> tuple[tuple[ProbeSpec, ...], tuple[PairProbeSpec, ...]]:
    """The probes' points (given, or their point groups'), each checked in its bodies.

    A point outside its body (or a conforming pair's probe off its interface) is refused
    in one line naming the key and the body's extent, before the calibration and the
    static state (it was found when the run's probes were built, after both: minutes
    in 3D, then a failed run's three lines).
    """
    gdim = data.mesh.geometry.dim

    def where(name: str, group: str | None, point: tuple[float, ...] | None
              ) -> tuple[float, ...]:
        if point is not None:
            return tuple(point)
        assert group is not None
        try:
            x = group_points(data, group)
        except MeshError as e:
            raise CaseError(f"{name}: {e}") from e
        if len(x) != 1:
            raise CaseError(f"{name}: point group '{group}' holds {len(x)} points, "
                            "expected one")
        return tuple(float(c) for c in x[0, :gdim])

    contact = {c.name: c for c in case.contact}
    # A conforming pair by its index in model.pairs, a general pair by its name.
    pair_index: dict[str, int | str] = {
        c.name: k for k, c in enumerate(c for c in case.contact if not c.general)}
    pair_index.update({c.name: c.name for c in case.contact if c.general})
    o = case.output
    probes = []
    for p in o.probes:
        key = f"output.probes.{p.name}"
        x = where(key, p.group, p.point)
        outside = _outside(data, p.body, x)
        if outside:
            raise CaseError(f"{key}.{_what(p.group, p.point, x)} is not in body "
                            f"'{p.body}' ({outside})")
        probes.append(ProbeSpec(p.name, p.body, x))
    pair_probes = []
    for q in o.pair_probes:
        key = f"output.pair_probes.{q.name}"
        x = where(key, q.group, q.point)
        c = contact[q.pair]
        for body in (c.slave,) if c.general else (c.slave, c.master):
            outside = _outside(data, body, x)
            if outside:
                on = (f"the slave surface of '{q.pair}'" if c.general else
                      f"the interface '{c.name}'")
                raise CaseError(f"{key}.{_what(q.group, q.point, x)} is not on {on} (not "
                                f"in body '{body}': {outside})")
        pair_probes.append(PairProbeSpec(q.name, pair_index[q.pair], x))
    return tuple(probes), tuple(pair_probes)


def _what(group: str | None, point: tuple[float, ...] | None, x: tuple[float, ...]) -> str:
    """``point: (x, y, z)`` or ``group: point group 'g' at (x, y, z)``, for a message."""
    at = f"({', '.join(f'{c:g}' for c in x)})"
    return f"point: {at}" if point is not None else f"group: point group '{group}' at {at}"


def _outside(data: gmshio.MeshData, body: str, x: tuple[float, ...]) -> str | None:
    """None if x lies in the body's cells (or touches them); else the body's extent.

    (A body the mesh does not have is left to the model's own message.)
    """
    from breakwater.model.pointprobe import locate_point

    msh, comm = data.mesh, data.mesh.comm
    tdim = msh.topology.dim
    if data.physical_groups.get(body, (-1, 0))[0] != tdim or data.cell_tags is None:
        return None
    cells = data.cell_tags.find(group_tag(data, body, tdim))
    cells = cells[cells < msh.topology.index_map(tdim).size_local].astype(np.int32)
    point = np.zeros(3)
    point[: len(x)] = x
    if comm.allreduce(len(locate_point(msh, cells, point, comm)), op=MPI.MAX):
        return None
    gdim = msh.geometry.dim
    nodes = msh.geometry.x[msh.geometry.dofmaps[0][cells].ravel(), :gdim]
    lo = np.min(comm.allgather(nodes.min(axis=0) if len(nodes) else np.full(gdim, np.inf)),
                axis=0)
    hi = np.max(comm.allgather(nodes.max(axis=0) if len(nodes) else np.full(gdim, -np.inf)),
                axis=0)
    span = ", ".join(f"{'xyz'[k]} {lo[k]:g}..{hi[k]:g}" for k in range(gdim))
    return f"which spans {span} m"


#: A body whose own weight would strain it by more than this is refused: linear
#: elasticity's results would be off by as much (a modulus given in MPa, 2e3 for 2e9 Pa,
#: strained a 5 cm block by 0.24, and the static state failed advising an undeformed
#: start). A soft soil layer, 20 m of clay at E = 5 MPa, is 0.07.
SELF_WEIGHT_STRAIN = 0.1


def _self_weight_problem(model: ContactModel, skip: str | None = None) -> str | None:
    """Why a body's own weight would strain it beyond small strains, or None (collective).

    The strain of a column of the body's height H along g under its weight, ρ g H / E
    (not of the body ``skip``, whose modulus is not known yet).
    """
    g = np.asarray(model.gravity.value, dtype=float)
    norm = float(np.linalg.norm(g))
    if norm == 0:
        return None
    for body in model.bodies:
        if body.spec.name == skip:
            continue
        along = body.submesh.geometry.x[:, :len(g)] @ (g / norm)
        lo = model.comm.allreduce(float(along.min()) if along.size else np.inf, op=MPI.MIN)
        hi = model.comm.allreduce(float(along.max()) if along.size else -np.inf, op=MPI.MAX)
        material = body.spec.material
        strain = material.density * norm * (hi - lo) / material.E
        if strain > SELF_WEIGHT_STRAIN:
            return (f"bodies.{body.spec.name}: its own weight would strain it by about "
                    f"ρ g H / E = {strain:.2g} (ρ = {material.density:g} kg/m³, H = "
                    f"{hi - lo:.3g} m its height, E = {material.E:.3g} Pa), beyond the "
                    "model's small strains (linear elasticity): is its modulus in Pa?")
    return None


def _mesh_summary(case: CaseSettings, data: gmshio.MeshData) -> dict[str, Any]:
    msh = data.mesh
    tdim = msh.topology.dim
    nlocal = msh.topology.index_map(tdim).size_local
    cells = {}
    assert data.cell_tags is not None
    for b in case.bodies:
        found = data.cell_tags.find(group_tag(data, b.name, tdim))
        cells[b.name] = int(msh.comm.allreduce(int((found < nlocal).sum())))
    info: dict[str, Any] = {"source": case.mesh.source, "degree": case.mesh.degree,
                            "cells": cells}
    # Cell groups that no body names are left out of the model: say so (a third body
    # of a user's mesh was dropped silently).
    left_out = {}
    for name, (dim, tag) in data.physical_groups.items():
        if dim == tdim and name not in cells:
            found = data.cell_tags.find(int(tag))
            left_out[name] = int(msh.comm.allreduce(int((found < nlocal).sum())))
    if getattr(data, "ungrouped", 0):  # cells in no physical group (warned when read)
        info["ungrouped_cells"] = data.ungrouped  # type: ignore[attr-defined]
    if left_out:
        info["left_out"] = left_out
        info["warnings"] = [f"mesh: cell group '{name}' ({n} cells) is no body of the case "
                            f"and is left out (add [bodies.{name}] to include it)"
                            for name, n in left_out.items()]
    if case.mesh.generated:
        info["refinement"] = case.mesh.refinement
    return info
