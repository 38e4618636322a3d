"""The rigid-body modes that a case's ``[fixed]`` groups leave free.

A body's rigid modes are its translations along x, y (and z) and its rotations (about z
in plane strain; about x, y and z in 3D). A fixed group holds a mode when some node it
holds moves along a held component in it: rollers ``components = [0]`` on a base hold
the translation along x and the rotations that move the base along x, not the
translation along y or z. With G = Σ rᵀr over the held (node, component) pairs (r the
modes' displacement there, rotations scaled by the bodies' extent), a mode is free
when it is in G's null space.

Two checks, on the bodies that contact pairs join into groups (as
:func:`~breakwater.statics.initial.unsupported` joins them, which refuses a group with
no fixed group at all):

- :func:`free_mode` — a group free in some mode even were its pairs bonded: nothing
  holds it there, and the static stiffness is singular (rollers in x only on the Goda
  mound's base: its static Newton had nothing to factorise along y). Refused when the
  run needs a static state, warned by :func:`loose_modes` when it does not (the
  dynamics' mass holds it: it drifts).
- :func:`loose_modes` — a body whose own fixed groups leave a mode free that the group
  holds: only its contact holds it there, by friction along the interface and the
  normal contact across it (a frictionless or detached body drifts): warned.

And one on a static state: :func:`drift` — a body held by contact alone that a
frictionless state moved sideways (nearly indeterminate there): refused where friction
would hold it (the frictional loading), warned where μ = 0.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING

import numpy as np
from mpi4py import MPI

from breakwater.common.errors import BreakwaterError

if TYPE_CHECKING:
    from dolfinx import fem

    from breakwater.model.model import ContactModel

__all__ = ["DRIFT", "FREE", "DriftError", "drift", "free_mode", "joined", "loose_modes",
           "sideways", "static_needed"]

FREE = 1e-9
"""A mode is free when G's eigenvalue along it is below this times G's largest (G counts
held nodes: a held mode's eigenvalue is of the order of one node's, ≥ 1e-3 of the largest
on the meshes measured)."""

DRIFT = 0.1
"""A body held by contact alone that a frictionless static state moves sideways by more
than this times its sinking is refused where friction would hold it, else warned about
(:func:`drift`; the shipped frictionless cases move by 1e-4 of it or less)."""

_AXES = "xyz"


def static_needed(model: ContactModel) -> bool:
    """Whether the run solves for a static state (gravity or initial loads, not undeformed)."""
    spec = model.initial
    loaded = (spec.loads is None and bool(model.loads)) or bool(spec.loads)
    return not spec.undeformed and bool(np.any(model.gravity.value) or loaded)


def joined(model: ContactModel) -> list[int]:
    """Each body's group: the index of one body of the bodies its contact pairs join."""
    group = list(range(len(model.bodies)))

    def root(i: int) -> int:
        while group[i] != i:
            i = group[i]
        return i

    for s, m, _ in model.pair_bodies():
        group[root(s)] = root(m)
    return [root(i) for i in range(len(group))]


def _names(gdim: int) -> list[str]:
    rotations = ["rotation about z"] if gdim == 2 else [f"rotation about {a}" for a in _AXES]
    return [f"translation along {_AXES[c]}" for c in range(gdim)] + rotations


def _modes(x: np.ndarray, centre: np.ndarray, scale: float) -> np.ndarray:
    """The rigid modes' displacements at points x: (points, modes, components)."""
    n, gdim = x.shape
    d = (x - centre) / scale
    if gdim == 2:
        r = np.zeros((n, 3, 2))
        r[:, 0, 0] = r[:, 1, 1] = 1.0
        r[:, 2, 0], r[:, 2, 1] = -d[:, 1], d[:, 0]
        return r
    r = np.zeros((n, 6, 3))
    for c in range(3):
        r[:, c, c] = 1.0
    r[:, 3, 1], r[:, 3, 2] = -d[:, 2], d[:, 1]  # about x
    r[:, 4, 0], r[:, 4, 2] = d[:, 2], -d[:, 0]  # about y
    r[:, 5, 0], r[:, 5, 1] = -d[:, 1], d[:, 0]  # about z
    return r


def _free(model: ContactModel, bodies: set[int],
          fixed: list[tuple[str, int, tuple[int, ...], np.ndarray]]) -> list[str]:
    """The rigid modes of ``bodies`` (moving as one) that their fixed groups leave free.

    Collective: every rank returns the same names.
    """
    gdim = model.gdim
    x = np.vstack([np.zeros((0, gdim))] + [b.V.tabulate_dof_coordinates()[:, :gdim]
                                           for b in model.bodies if b.index in bodies])
    lo = x.min(axis=0) if len(x) else np.full(gdim, np.inf)
    hi = x.max(axis=0) if len(x) else np.full(gdim, -np.inf)
    model.comm.Allreduce(MPI.IN_PLACE, lo, op=MPI.MIN)  # elementwise over the ranks
    model.comm.Allreduce(MPI.IN_PLACE, hi, op=MPI.MAX)
    centre, scale = 0.5 * (lo + hi), max(float(np.max(hi - lo)), 1e-300)
    names = _names(gdim)
    g = np.zeros((len(names), len(names)))
    for _, index, comps, points in fixed:
        if index in bodies and len(points):
            r = _modes(points, centre, scale)
            for c in comps:
                g += r[:, :, c].T @ r[:, :, c]
    g = model.comm.allreduce(g, op=MPI.SUM)
    values, vectors = np.linalg.eigh(g)
    null = vectors[:, values <= FREE * max(float(values.max()), 1.0)]
    if not null.shape[1]:
        return []
    share = np.sum(null ** 2, axis=1)  # each mode's part in the null space (sums to its rank)
    order = np.argsort(-share, kind="stable")[:null.shape[1]]
    return [names[k] for k in sorted(order)]


def _groups(model: ContactModel, bodies: set[int]) -> list[tuple[str, tuple[int, ...]]]:
    """The fixed groups on ``bodies`` and the components each holds."""
    return [(group, comps) for i in sorted(bodies)
            for group, comps in model.fixed_on(model.bodies[i].spec.name)]


def _held(model: ContactModel, bodies: set[int]) -> str:
    """What the fixed groups on ``bodies`` hold: ``"base: x; mound_sides: z"``."""
    return "; ".join(f"{group}: {''.join(_AXES[c] for c in comps)}"
                     for group, comps in _groups(model, bodies))


def _fix(model: ContactModel, bodies: set[int], mode: str) -> str:
    """How to hold a free mode: which component to add to which fixed group."""
    gdim = model.gdim
    if mode.startswith("translation"):
        need = [_AXES.index(mode[-1])]
    else:  # a rotation about an axis: the components across it
        axis = 2 if gdim == 2 else _AXES.index(mode[-1])
        need = [c for c in range(gdim) if c != axis]
    groups = _groups(model, bodies)
    lacking = [(g, [c for c in need if c not in comps]) for g, comps in groups]
    lacking = [(g, cs) for g, cs in lacking if cs]
    if mode.startswith("translation"):
        where = f" (add {need[0]} to fixed.{lacking[0][0]}.components)" if lacking else ""
        return f"hold {_AXES[need[0]]} on a [fixed] group{where}"
    parts = " or ".join(_AXES[c] for c in need)
    where = (f" (add {', '.join(str(c) for c in lacking[0][1])} to fixed.{lacking[0][0]}."
             "components, if it does not lie on the axis)" if lacking else "")
    return f"hold {parts} on a [fixed] group away from the axis{where}"


def _and(names: list[str]) -> str:
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"


def _line(model: ContactModel, body: int, bodies: set[int], modes: list[str]) -> str:
    """One line: the body (and those it touches), what is held, the free modes, the fix."""
    name = model.bodies[body].spec.name
    others = ", ".join(model.bodies[i].spec.name for i in sorted(bodies) if i != body)
    who = (f"bodies.{name} and the bodies it touches ({others}): their" if others
           else f"bodies.{name}: its")
    return (f"{who} [fixed] groups ({_held(model, bodies)}) leave the rigid "
            f"{_and(modes)} free: {_fix(model, bodies, modes[0])}")


def _held_groups(model: ContactModel) -> Iterator[tuple[set[int], list[int]]]:
    """The groups of bodies joined by contact pairs that some fixed group holds.

    Each as (its bodies, those of them with a fixed group, in order).
    """
    roots = joined(model)
    for root in sorted(set(roots)):
        bodies = {i for i, r in enumerate(roots) if r == root}
        held = [i for i in sorted(bodies) if model.fixed_on(model.bodies[i].spec.name)]
        if held:
            yield bodies, held


def free_mode(model: ContactModel, calibrating: bool = False) -> str | None:
    """Why the static state (or the calibration) cannot exist: a group left free in a mode.

    Only groups with some fixed group (:func:`~breakwater.statics.initial.unsupported`
    refuses the others), and only when the run needs a static state
    (:func:`static_needed`) or, with ``calibrating``, the shear modulus is to be
    calibrated: the calibration's stiffness (:mod:`breakwater.statics.calibrate`, its
    pairs bonded, which join the bodies as here) is singular in that mode, whatever the
    run's initial state (a 3-D case with rollers in x only failed its first stiffness
    solve, after the mesh and the model were built). Collective.
    """
    if not (calibrating or static_needed(model)):
        return None
    fixed = model.fixed_nodes()
    for bodies, first in _held_groups(model):
        modes = _free(model, bodies, fixed)
        if modes:
            why = ("the stiffness the calibration solves, its interfaces bonded, is singular"
                   if calibrating else "the static stiffness is singular; or start it at "
                   "rest undeformed: [initial] undeformed = true")
            return _line(model, first[0], bodies, modes) + f" (nothing holds it there, and {why})"
    return None


def loose_modes(model: ContactModel) -> list[str]:
    """One warning per body whose own fixed groups leave a rigid mode free (collective).

    A mode its group holds only through its contact pairs (named, with their friction):
    friction along the interface and the normal contact across it hold it, a
    frictionless or detached body drifts. A group free in a mode where the run needs no
    static state (:func:`free_mode` refuses it otherwise): the dynamics' mass alone
    holds it, and it drifts.
    """
    out: list[str] = []
    fixed, static = model.fixed_nodes(), static_needed(model)
    for bodies, with_fixed in _held_groups(model):
        group_free = _free(model, bodies, fixed)
        if group_free and not static:
            out.append(_line(model, with_fixed[0], bodies, group_free)
                       + " (nothing holds it there: it may drift)")
            continue
        for i in with_fixed:
            own = [m for m in _free(model, {i}, fixed) if m not in group_free]
            if not own:
                continue
            pairs = [p for p in model.pairs if i in (p.slave, p.master)]
            law = ", ".join(f"'{p.spec.interface}' μ = {float(p.law.friction.μ.value):g}"
                            for p in pairs) or "its general contact pairs"
            out.append(_line(model, i, {i}, own) + f": only its contact ({law}) holds it "
                       "there (a frictionless or detached body drifts)")
    return out


class DriftError(BreakwaterError):
    """A frictionless static state moved a body that friction would hold (:func:`drift`)."""


def sideways(model: ContactModel, u: list[fem.Function]) -> dict[str, tuple[float, float]]:
    """Each body with no fixed group: its sideways move and sinking (m) in a state (collective).

    Sideways is across gravity, sinking along it; the move is the mean of the body's
    nodal displacements (owned nodes, every rank). Empty without gravity.
    """
    g = np.asarray(model.gravity.value, dtype=float)
    if not np.linalg.norm(g) > 0:
        return {}
    down = g / np.linalg.norm(g)
    out = {}
    for body, f in zip(model.bodies, u, strict=True):
        if model.fixed_on(body.spec.name):
            continue
        owned = f.x.array.reshape(-1, model.gdim)[:f.function_space.dofmap.index_map.size_local]
        mean = model.comm.allreduce(owned.sum(axis=0)) / max(model.comm.allreduce(len(owned)), 1)
        sink = float(mean @ down)
        out[body.spec.name] = (float(np.linalg.norm(mean - sink * down)), sink)
    return out


def _friction(model: ContactModel, name: str) -> list[tuple[str, float]]:
    """The contact pairs of a body and their friction coefficients μ."""
    i = model.body(name).index
    pairs = [(p.spec.interface, float(p.law.friction.μ.value)) for p in model.pairs
             if i in (p.slave, p.master)]
    return pairs + [(s.name, float(s.friction)) for s in model.surface_pairs
                    if i in (model.body(s.slave).index, model.body(s.master).index)]


def drift(model: ContactModel, moved: dict[str, tuple[float, float]]
          ) -> tuple[str | None, list[str]]:
    """Bodies a frictionless static state moved sideways by more than DRIFT of their sinking.

    ``moved`` is :func:`sideways` of the state. A body held by contact alone,
    frictionless, is held along the interface by nothing but the shape of its support:
    its state is nearly indeterminate there, and the discretisation's tangential
    out-of-balance moves it. Measured (2026-11-28): the Goda caisson meshed apart
    (``examples/goda_apart``, triangles) moved 1.4e-9 m, 9.3e-6 of its sinking; the
    same ``.geo`` meshed in quadrilaterals moved 0.90 mm, 5.9 times its 0.15 mm
    sinking, and its gauges' peaks read 1.54 mm for 2.44. Where one of the body's pairs
    has friction and the case asked for ``[initial] loading = "frictionless"``, the
    frictional state would hold it: refused (the run would start from a state the case
    could have had right). Where none has (μ = 0), the drift is the physics (no
    frictionless equilibrium holds it better): warned.

    Returns:
        The refusal (one line, or None) and the warnings (one line each).
    """
    refusal, warnings = None, []
    for name, (side, sink) in moved.items():
        if not (side > DRIFT * abs(sink) and side > 0):
            continue
        pairs = _friction(model, name)
        rough = [(p, mu) for p, mu in pairs if mu > 0]
        what = (f"bodies.{name}: the frictionless static state moved it {side * 1e3:.3g} mm "
                f"sideways, {side / max(abs(sink), 1e-300):.3g} times as far as it sank "
                f"({sink * 1e3:.3g} mm): held by contact alone")
        if rough and model.initial.loading == "frictionless":
            law = ", ".join(f"'{p}' μ = {mu:g}" for p, mu in rough)
            refusal = refusal or (
                f"{what}, its frictionless equilibrium is nearly indeterminate along the "
                "interface, and the run would start from where the mesh's asymmetry left "
                f"it; [initial] loading = \"frictional\" (the default with friction: {law}) "
                "gives the state friction holds")
        elif not rough:
            law = ", ".join(f"'{p}'" for p, _ in pairs)
            warnings.append(f"{what}, without friction ({law} μ = 0) nothing but the shape "
                            "of its support holds it along the interface: the run starts "
                            "from there (its probes' displacements include the move)")
    return refusal, warnings
