"""The bodies a relaxation holds up to t = 0, and their release at t = 0.

Stage 3 of :mod:`breakwater.statics.relaxation` (models with general pairs):

- :func:`held_bodies`: the slave bodies whose pair carries a tangential resultant
  above μN in the held state (μ = :data:`HELD_FRICTION`), each with its sliding
  direction d (against the held friction, along its free components).
- :func:`moving_body`: which body of a pair slides when released (its slave, or its
  master where the slave is fixed and the master is not).
- :func:`release`: the slave nodes in contact of each such pair start sliding at
  :data:`~breakwater.contact.conforming.RELEASE` χ along d's part in their tangent, so
  that the law carries the sliding friction μλ (to 5e-5) at t = 0 and a₀ is the sliding
  acceleration (:meth:`~breakwater.contact.general.SurfaceContact.sliding_velocities`).
  A slave node with a held component (a ``[fixed]`` group holds it, a roller: the edge
  nodes of a 3-D block whose side faces are held along their normal) starts too: its
  free components take the slip, and a held component's share of it, if any, is its
  master's (:func:`~breakwater.contact.newtonaids.sliding_velocities`). Before, such a
  node got no release velocity and carried no friction at t = 0: a block pushed with
  F = 1.5 μN between rollers started with a₀ 32 % above (F − μN)/m, the friction
  resultant 0.839 μN (``tests/test_pair3d_friction.py``).

The state of incipient sliding itself (the pseudo steps with the real μ) is
:func:`breakwater.statics.relaxation._slide`.
"""

from __future__ import annotations

import logging

import numpy as np
from dolfinx import fem

from breakwater.contact.conforming import RELEASE
from breakwater.model.model import ContactModel
from breakwater.model.pairs import SurfacePair
from breakwater.statics.pseudostep import PseudoStepper

__all__ = ["HELD_FRICTION", "free_part", "held_bodies", "moving_body", "release"]

log = logging.getLogger("breakwater.statics.relaxation")  # the relaxation's warnings

HELD_FRICTION = 100.0
"""Friction coefficient of every pair while the bodies are held (stage 3); χ is multiplied
by it too: the stick tangent μp/χ stays that of μ = 1 (a step converges as in stage 2)."""


def held_bodies(ps: PseudoStepper) -> tuple[list[str], dict[int, np.ndarray]]:
    """The slave bodies whose pair's tangential resultant exceeds μN (held state).

    Returns:
        Their names, each in a warning, and (general pairs) each body's sliding direction
        (against the held friction, less the components its ``[fixed]`` groups hold:
        :func:`free_part`), for
        :func:`~breakwater.statics.relaxation._slide` and :func:`release`.
    """
    out: list[str] = []
    sliding: dict[int, np.ndarray] = {}
    ps.rest()
    with ps.friction(HELD_FRICTION, HELD_FRICTION):
        forces = [p.resultants(accepted=False) for p in ps.providers]
    for p, (normal, friction) in zip(ps.providers, forces, strict=True):
        N, T = float(np.linalg.norm(normal)), float(np.linalg.norm(friction))
        μ = p.spec.friction
        if T - μ * N > 1e-6 * max(N, T):
            body = moving_body(ps.model, p.spec)
            if ps.model.comm.rank == 0:
                u = "N" if ps.model.gdim == 3 else "N/m"
                log.warning("initial state: body '%s' cannot be held by friction on '%s' "
                            "(tangential force %.4g %s, μN = %.4g %s): held in place up "
                            "to t = 0 and released at t = 0", body, p.spec.name, T, u, μ * N, u)
            index = ps.model.body(body).index
            # Against the friction on it (the master's is the slave's, reversed).
            sign = 1.0 if body == p.spec.slave else -1.0
            sliding[index] = sliding.get(index, 0.0) - sign * friction
            if body not in out:
                out.append(body)
    for index in list(sliding):
        sliding[index] = free_part(ps.model, index, sliding[index])
        if not np.any(sliding[index]):  # held by its [fixed] groups along it: no slide
            del sliding[index]
    if not out:  # the conforming pairs' bodies (not checked one by one)
        for pair in ps.model.pairs:
            body = ps.model.bodies[pair.slave].spec.name
            if ps.model.comm.rank == 0:
                log.warning("initial state: body '%s' cannot be held by friction on "
                            "'%s': held in place up to t = 0 and released at t = 0",
                            body, pair.spec.interface)
            out.append(body)
    return out, sliding


def free_part(model: ContactModel, index: int, total: np.ndarray) -> np.ndarray:
    """A body's sliding direction (unnormalised) less the components its groups hold.

    A body with a ``[fixed]`` group translates along its free components only. The
    held state's friction resultant has a component along a held direction where the
    mesh is not symmetric about it (a block between rollers on the planes z = const:
    −1.59 N along z against 339 N along x). Left in d, the state of incipient sliding
    accelerated the body along it too: its resultant along d, and so α, took the
    friction along z as a drive along x, and :func:`~breakwater.statics.relaxation._slide`
    stalled at 2.4e-6 of the load (a rigid drift of 3.5e-6 m per pseudo step: no state,
    the block released from the held state with its bonded shear, +8 % on its
    acceleration at the second step); at t = 0 the block accelerated at 0.057 m/s²
    along z. The conforming pairs' release (:func:`breakwater.statics.initial._release`)
    takes its direction from here too.
    """
    out = np.array(total, dtype=float)
    held = sorted({c for _, comps in model.fixed_on(model.bodies[index].spec.name)
                   for c in comps})
    out[held] = 0.0
    return out


def moving_body(model: ContactModel, spec: SurfacePair) -> str:
    """The body of a pair that slides when released (:func:`held_bodies`).

    Its slave, or its master when the slave is fixed and the master is not (roles
    swapped: a block as the master surface of a fixed base's slave surface; before, the
    base was released and the block kept the held state's shear: a block on a 30°
    slope slid 2.9 % too far).
    """
    if model.fixed_on(spec.slave) and not model.fixed_on(spec.master):
        return spec.master
    return spec.slave


def release(ps: PseudoStepper, sliding: dict[int, np.ndarray], v: list[fem.Function]
            ) -> None:
    """Start the held bodies' slave nodes in contact sliding (added to ``v``).

    Each slips at :data:`~breakwater.contact.conforming.RELEASE` χ along its tangent, in
    the body's sliding direction (``sliding``: :func:`held_bodies`; the module doc), its
    held components included.
    """
    ps.rest()
    y = np.zeros(ps.solver.n)
    for p in ps.providers:
        body = moving_body(ps.model, p.spec)
        d = sliding.get(ps.model.body(body).index)
        if d is None:
            continue
        d = d / np.linalg.norm(d)
        if body != p.spec.slave:  # the slave's slip relative to a sliding master
            d = -d
        pos, vel = p.sliding_velocities(d, RELEASE * p.spec.regularisation)
        y[pos] = vel
    ps.add_slave_velocities(v, y)
