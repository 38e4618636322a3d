"""The search of a 3-D general contact pair: its faces, integration points and projections.

The 3-D counterpart of :class:`breakwater.contact.surfacesearch.SurfaceSearch` (issue 25):
the pair's two surfaces are gathered on every rank
(:func:`~breakwater.contact.surfaces.gather_surface`: triangles of 3 or 6 nodes, a P2
tetrahedron's facet closure, :mod:`breakwater.contact.projection3d`'s order), each face
oriented so that ``(x₁ − x₀) × (x₂ − x₀)`` points out of its cell. The slave is cut into
integration points in the current configuration:

- ``segments`` (mortar segmentation, Puso & Laursen 2004,
  :mod:`breakwater.contact.clip3d` / :func:`~breakwater.contact.searchkernels3d.segment_points`):
  each master face's corners projected onto the plane of a slave face's corners and
  clipped against it, the polygon fanned into triangles, each with a triangle Gauss rule
  of degree ``2 points − 1`` (that of a line rule of ``points`` points); exact for the
  flat patch;
- ``gauss``: that rule on each slave face (Gauss-point-to-segment).

The weight of a point is its rule weight times the slave face's reference area element
``|X_ξ × X_η|``. Each point's current position is projected onto the master surface
(closest point, :func:`breakwater.contact.searchkernels3d.project`), which gives its
master face and (ξ̄, η̄); the forces are :mod:`breakwater.contact.forcekernels3d`'s.
``nodes`` is refused in 3-D (a quadratic triangle's vertex weights integrate to zero).

A Newton iterate is checked before it is searched (:meth:`SurfaceSearch3D.check_iterate`):
non-finite values, a contact face's corner edge stretched beyond :data:`STRETCH` times
its meshed length, or more integration points than :data:`POINTS_GROWTH` times the
meshed configuration's are a diverging iterate, a ConvergenceError (the step is cut
back, the static relaxation retried smaller or failed in one line), not a search: a
diverged static Newton (master nodes 8.78 m away in a 0.3 m block) made 3.1e5
integration points and 6.1e7 projection candidates, 30–50 s per search inside compiled
code, where SIGTERM waits. A stop signal (SIGTERM, Ctrl-C) is also looked at before
each search (collectively), so that a run stops between searches, not at the next step.
"""

from __future__ import annotations

import math
import signal
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common.arrays import key_of, unchanged
from breakwater.common.console import stop_requested
from breakwater.common.errors import ConvergenceError, Interrupted
from breakwater.contact import forcekernels3d, searchkernels3d
from breakwater.contact.clip3d import SLIVER, rule
from breakwater.contact.projection import INSIDE
from breakwater.contact.projection3d import FLIP, shape, surface
from breakwater.contact.searchkernels import current
from breakwater.contact.surfaces import Surface, SurfacePair, gather_surface
from breakwater.contact.surfacesearch import InterfaceValues, LawFloats

if TYPE_CHECKING:
    from breakwater.common.timings import Timings
    from breakwater.model.layout import MonolithicLayout
    from breakwater.model.model import ContactModel

__all__ = ["POINTS_GROWTH", "STRETCH", "SurfaceSearch3D", "orient"]

STRETCH = 3.0
"""A contact face's corner edge longer than this times its meshed length (a strain of
200 %, far beyond a linear elastic body's) is a diverging iterate, not a state."""

POINTS_GROWTH = 10.0
"""An iterate's integration points beyond this times the meshed configuration's (plus
one rule per slave face) are a diverging iterate: the search's cost stays bounded."""

DIVERGED = -4
"""The ConvergenceError's reason of a diverging iterate (SNES's DIVERGED_FNORM_NAN)."""


def edge_lengths(x: np.ndarray) -> np.ndarray:
    """The corner edges' lengths ``(F, 3)`` of faces ``x`` ``(F, nn, 3)``."""
    corners = x[:, :3]
    return np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2)  # type: ignore[no-any-return]


def orient(s: Surface) -> None:
    """Turn each face so that ``(x₁ − x₀) × (x₂ − x₀)`` points out of its cell (in place)."""
    if not len(s.X):
        return
    n = np.cross(s.X[:, 1] - s.X[:, 0], s.X[:, 2] - s.X[:, 0])
    flip = np.sum((s.interior - s.X[:, :3].mean(axis=1)) * n, axis=1) > 0
    order = FLIP[: s.X.shape[1]]
    s.X[flip] = s.X[flip][:, order]
    s.dofs[flip] = s.dofs[flip][:, order]


def area_element(X: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """``|X_ξ × X_η|`` of faces ``X`` ``(K, nn, 3)`` at ``xi`` ``(K, 2)``."""
    _, dx, _ = surface(X, xi)
    return np.linalg.norm(np.cross(dx[:, 0], dx[:, 1]), axis=1)


class SurfaceSearch3D(InterfaceValues, LawFloats):
    """A 3-D general pair's faces, integration points and projections (the module doc).

    Args: those of :class:`breakwater.contact.surfacesearch.SurfaceSearch`.
    """

    def __init__(self, model: ContactModel, spec: SurfacePair, layout: MonolithicLayout,
                 interface: np.ndarray,
                 state: tuple[Sequence[fem.Function], Sequence[fem.Function],
                              Sequence[fem.Function], Sequence[fem.Function]],
                 dt: fem.Constant, beta1: float, beta2: float) -> None:
        super().__init__(model.comm, layout, interface, state, dt, beta1, beta2)
        self.model, self.spec = model, spec
        self.small_rotations = spec.rotations == "small"
        self.law = forms.ContactLaw.of(spec)
        slave = gather_surface(model, layout, spec.slave, (spec.slave_surface,))
        master = gather_surface(model, layout, spec.master, spec.master_groups)
        orient(slave)
        orient(master)
        self.slave, self.master = slave, master
        self.pos_s, self.pos_m = (self._positions(interface, x.dofs) for x in (slave, master))
        self.radius = search_radius3d(spec, master)
        self.searches = 0
        self.search_seconds = 0.0
        self.timings: Timings | None = None
        _, first, node_of = np.unique(slave.dofs[..., 0], return_index=True,
                                      return_inverse=True)
        self.node_of = node_of.reshape(slave.dofs.shape[:2])
        self.node_pos = self.pos_s.reshape(-1, 3)[first]
        self.node_X = slave.X.reshape(-1, 3)[first]
        self._sX, self._mX = (np.ascontiguousarray(x.X, dtype=float) for x in (slave, master))
        self._ps, self._pm = (np.ascontiguousarray(p, dtype=np.int64)
                              for p in (self.pos_s, self.pos_m))
        self._node_of = np.ascontiguousarray(self.node_of, dtype=np.int64)
        self._node_pos = np.ascontiguousarray(self.node_pos, dtype=np.int64)
        self._rule = rule(2 * spec.points - 1)
        self._law_floats = None
        self._fixed: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        if spec.integration == "gauss":
            g, w = self._rule
            S = len(slave.X)
            f = np.repeat(np.arange(S), len(w))
            xi = np.tile(g, (S, 1))
            self._fixed = (f, xi, np.tile(w, S))
        self._normal_key: np.ndarray | None = None
        self._normal_points: dict[str, Any] = {}
        self._edges = (edge_lengths(self._sX), edge_lengths(self._mX))
        self._max_points = math.inf
        if self._fixed is None and len(self._sX) and len(self._mX):
            meshed = len(searchkernels3d.segment_points(self._sX, self._mX, self.radius,
                                                        *self._rule, SLIVER, False)[0])
            self._max_points = POINTS_GROWTH * meshed + len(self._rule[1]) * len(self._sX)

    def check_iterate(self, xs: np.ndarray, xm: np.ndarray) -> None:
        """Refuse a diverging iterate (current faces ``xs``, ``xm``) before its search.

        The same on every rank (the gathered state).

        Raises:
            ConvergenceError: Non-finite positions, or a face's corner edge stretched
                beyond :data:`STRETCH` times its meshed length.
        """
        name = f"contact '{self.spec.name}'"
        if not (np.isfinite(xs).all() and np.isfinite(xm).all()):
            raise ConvergenceError(f"{name}: a diverging iterate (non-finite positions of "
                                   "its faces), not searched", DIVERGED, 0)
        for x, meshed, side in zip((xs, xm), self._edges, ("slave", "master"), strict=True):
            if not len(x):
                continue
            ratio = edge_lengths(x) / meshed
            k = int(np.argmax(ratio))
            if ratio.flat[k] > STRETCH:
                f = k // 3
                where = ", ".join(f"{c:.4g}" for c in x[f, :3].mean(axis=0))
                raise ConvergenceError(
                    f"{name}: a diverging iterate (a {side} face at ({where}) m stretched "
                    f"×{ratio.flat[k]:.3g}, beyond ×{STRETCH:g} of its meshed size), not "
                    "searched", DIVERGED, 0)

    def _stop(self) -> None:
        """Stop between searches on a signal (SIGTERM, SIGINT; collective)."""
        signum = self.comm.allreduce(stop_requested(), op=MPI.MAX)
        if signum:
            raise Interrupted(f"interrupted by {signal.Signals(signum).name} during the "
                              f"contact search of '{self.spec.name}'")

    def _points(self, u1: np.ndarray) -> dict[str, Any]:
        """The integration points at the state u1 and the projections of those that have one.

        Returns:
            ``index`` (the points with a projection), ``facet`` (their master face),
            ``slave_facet``, ``Ns``, ``xi`` ((ξ̄, η̄)), ``weight`` (theirs), ``all_x``,
            ``all_weight`` (every point's current position and weight).
        """
        self._stop()
        t0 = time.perf_counter()
        xs = current(self._sX, self._ps, u1)
        xm = current(self._mX, self._pm, u1)
        self.check_iterate(xs, xm)
        if self._fixed is not None:
            f_s, xi, w = self._fixed
        elif len(xs) and len(xm):
            g, gw = self._rule
            f_s, xi, w, _ = searchkernels3d.segment_points(xs, xm, self.radius, g, gw,
                                                           SLIVER, False)
        else:
            f_s, xi, w = np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros(0)
        if len(f_s) > self._max_points:
            raise ConvergenceError(
                f"contact '{self.spec.name}': a diverging iterate ({len(f_s)} integration "
                f"points, beyond {POINTS_GROWTH:g} times the meshed surfaces'), not searched",
                DIVERGED, 0)
        weight = w * area_element(self._sX[f_s], xi) if len(f_s) else np.zeros(0)
        Ns = shape(xi, self._sX.shape[1])[0] if len(f_s) else np.zeros((0, self._sX.shape[1]))
        x = np.einsum("kn,knd->kd", Ns, xs[f_s])
        if len(xm):
            facet, xi_bar = searchkernels3d.project(x, xm, self.radius, INSIDE)
        else:
            facet, xi_bar = np.full(len(x), -1, np.int64), np.zeros((len(x), 2))
        on = np.flatnonzero(facet >= 0)
        self.searches += 1
        elapsed = time.perf_counter() - t0
        self.search_seconds += elapsed
        if self.timings is not None:
            self.timings.seconds["contact_search"] += elapsed
        return {"index": on, "facet": np.ascontiguousarray(facet[on]),
                "slave_facet": np.ascontiguousarray(f_s[on], dtype=np.int64),
                "Ns": np.ascontiguousarray(Ns[on]), "xi": np.ascontiguousarray(xi_bar[on]),
                "weight": np.ascontiguousarray(weight[on]), "all_x": x, "all_weight": weight}

    def normal_forces(self, u1: np.ndarray) -> np.ndarray:
        """The slave nodes' normal forces λ_k = ∫ p N_k at the state u1 (node order)."""
        return np.asarray(self._normal(u1)["lam"])

    def _normal(self, u1: np.ndarray) -> dict[str, Any]:
        """The normal part of the state u1 (cached: the search once per state).

        Returns:
            :meth:`_points`' dict with ``out`` (f_c), ``lam`` (the slave nodes' normal
            forces ∫ p N_k), ``forces`` (each point's nodal forces), ``gap`` and
            ``xi_bar`` (the points' g_n and refined (ξ̄, η̄)).
        """
        if unchanged(self._normal_key, u1):
            return self._normal_points
        p = self._points(u1)
        eps, g0, _, _ = self._law
        p["out"], p["lam"], p["forces"], p["gap"], p["xi_bar"] = forcekernels3d.residual(
            self._sX, self._mX, self._ps, self._pm, u1, p["slave_facet"], p["facet"], p["Ns"],
            p["xi"], p["weight"], self.small_rotations, eps, g0, self._node_of,
            len(self.node_pos))
        self._normal_key, self._normal_points = key_of(u1), p
        return p


def search_radius3d(spec: SurfacePair, master: Surface) -> float:
    """The pair's search radius: ``spec.radius``, else the longest master face edge."""
    if spec.radius is not None:
        return spec.radius
    if not len(master.X):
        return 1.0
    corners = master.X[:, :3]
    edges = corners - np.roll(corners, 1, axis=1)
    return float(np.linalg.norm(edges, axis=2).max())
