"""Probes: fields evaluated at points, the same on every rank.

:class:`PointProbe` evaluates one body's field at a point; :class:`PairProbe` gives
the slip and opening of a conforming contact interface at a point (a general pair's:
:class:`~breakwater.outputs.surfaceoutputs.SurfaceProbe`); :class:`Probes` holds the probes of
a run (``output.probes`` and ``output.pair_probes``) and gives their history columns.
"""

from __future__ import annotations

from collections.abc import Sequence

import dolfinx
import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater.common.errors import MeshError
from breakwater.config.runspec import OutputSpec, PairProbeSpec
from breakwater.contact.conforming import InterfaceNodes
from breakwater.contact.general import SurfaceContact
from breakwater.model.model import ContactModel
from breakwater.outputs.surfaceoutputs import SurfaceProbe

__all__ = ["PairProbe", "PointProbe", "Probes"]


class PointProbe:
    """Evaluate a body's fields at a fixed point of the reference configuration.

    Points on a boundary or an interface are allowed: the field of the named body
    is taken (its trace), so two probes at one interface node, one per body, give
    the slip and opening of the interface there.

    Args:
        model: The contact model.
        body: Name of the body to evaluate.
        point: Coordinates (gdim or 3 values).
        name: Label for outputs.
    """

    def __init__(self, model: ContactModel, body: str, point: Sequence[float],
                 name: str | None = None) -> None:
        self.model = model
        self.body = b = model.body(body)
        self.name = name or f"{body}@{tuple(point)}"
        x = np.zeros(3)
        x[: len(point)] = point
        self.point = x
        msh = b.submesh
        tdim = msh.topology.dim
        owned = np.arange(msh.topology.index_map(tdim).size_local, dtype=np.int32)
        tree = dolfinx.geometry.bb_tree(msh, tdim, entities=owned)
        candidates = dolfinx.geometry.compute_collisions_points(tree, x.reshape(1, 3))
        cells = dolfinx.geometry.compute_colliding_cells(msh, candidates, x.reshape(1, 3))
        local = cells.links(0)
        comm = model.comm
        self.owner = comm.allreduce(comm.rank if len(local) else comm.size, op=MPI.MIN)
        if self.owner == comm.size:
            raise MeshError(f"probe '{self.name}': point {tuple(point)} is not in body "
                            f"'{body}'")
        self._cell = int(local[0]) if len(local) else -1
        # The value is Σ φ_j(x) u_j over the cell's DOF blocks: the basis functions at
        # the point, found once by evaluating each of them (the owner only).
        V = b.V
        self.size = V.dofmap.index_map_bs
        self._blocks = np.zeros(0, np.int32)
        self._phi = np.zeros(0)
        unit = fem.Function(V)  # collective (its vector's scatter), on every rank
        if comm.rank == self.owner:
            self._blocks = V.dofmap.cell_dofs(self._cell).copy()
            phi = []
            for blk in self._blocks:
                unit.x.array[:] = 0.0
                unit.x.array[blk * self.size] = 1.0
                phi.append(unit.eval(x.reshape(1, 3), np.array([self._cell], np.int32)).ravel()[0])
            self._phi = np.array(phi)

    def local_value(self, functions: Sequence[fem.Function] | fem.Function) -> np.ndarray:
        """The value at the point on the owning rank; zeros on the others (no reduction)."""
        f = functions if isinstance(functions, fem.Function) else functions[self.body.index]
        if not len(self._blocks):
            return np.zeros(self.size)
        return self._phi @ f.x.array.reshape(-1, self.size)[self._blocks]

    def value(self, functions: Sequence[fem.Function] | fem.Function) -> np.ndarray:
        """The value at the point of the body's Function (or of a list, one per body)."""
        out = self.local_value(functions)
        self.model.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.SUM)
        return out


def _tangent(n: np.ndarray) -> np.ndarray:
    """2D unit tangent t = (n_y, −n_x): +x on a horizontal interface with n = +y."""
    return np.array([n[1], -n[0]])


class PairProbe:
    """Slip and opening (slave minus master) at an interface point.

    The normal is the master's outward normal at the nearest interface node;
    slip is along ``t = (n_y, −n_x)`` in 2D (the tangential magnitude in 3D).

    Args:
        model: The contact model.
        spec: The probe's name, contact pair (index) and point.
        nodes: Interface nodes of every pair.

    """

    KEYS = ("slip", "opening", "slave_ux", "slave_uy", "master_ux", "master_uy")

    def __init__(self, model: ContactModel, spec: PairProbeSpec,
                 nodes: Sequence[InterfaceNodes]) -> None:
        if not isinstance(spec.pair, int) or not 0 <= spec.pair < len(model.pairs):
            raise ValueError(f"pair probe '{spec.name}': no contact pair {spec.pair} "
                             f"(the model has {len(model.pairs)})")
        self.name = spec.name
        pair = model.pairs[spec.pair]
        self.slave = PointProbe(model, model.bodies[pair.slave].spec.name, spec.point,
                                f"{spec.name}_slave")
        self.master = PointProbe(model, model.bodies[pair.master].spec.name, spec.point,
                                 f"{spec.name}_master")
        nd = nodes[spec.pair]
        x = np.zeros(model.gdim)
        x[:] = np.asarray(spec.point, dtype=float)[: model.gdim]
        self.normal = nd.normal[np.argmin(np.linalg.norm(nd.x - x, axis=1))]
        self.gdim = model.gdim

    def value(self, u: Sequence[fem.Function]) -> dict[str, float]:
        """Slip, opening and both sides' displacements for the state ``u``.

        Returns:
            Keys ``slip``, ``opening``, ``slave_ux``, ``slave_uy``, ``master_ux``,
            ``master_uy``.
        """
        return self.from_values(self.slave.value(u), self.master.value(u))

    def from_values(self, us: np.ndarray, um: np.ndarray) -> dict[str, float]:
        """:meth:`value` from the two sides' displacements at the point."""
        jump = us - um
        opening = float(jump @ self.normal)
        if self.gdim == 2:
            slip = float(jump @ _tangent(self.normal))
        else:
            slip = float(np.linalg.norm(jump - opening * self.normal))
        return {"slip": slip, "opening": opening,
                "slave_ux": float(us[0]), "slave_uy": float(us[1]),
                "master_ux": float(um[0]), "master_uy": float(um[1])}


class Probes:
    """The probes of a run: point probes and interface (pair) probes.

    Columns: ``<probe>_ux``, ``<probe>_uy`` per point probe, then
    ``<pair probe>_<key>`` per pair probe (keys of :attr:`PairProbe.KEYS`).

    Args:
        model: The contact model.
        output: The probes' specifications.
        nodes: Interface nodes of every pair.
        surfaces: The general pairs (the stepper's providers), for the pair probes
            that name one.

    """

    def __init__(self, model: ContactModel, output: OutputSpec,
                 nodes: Sequence[InterfaceNodes],
                 surfaces: Sequence[SurfaceContact] = ()) -> None:
        self._comm = model.comm
        self.points = [PointProbe(model, p.body, p.point, p.name) for p in output.probes]
        general = {c.spec.name: c for c in surfaces}
        self.pairs: list[PairProbe | SurfaceProbe] = []
        for q in output.pair_probes:
            if isinstance(q.pair, str):
                if q.pair not in general:
                    raise ValueError(f"pair probe '{q.name}': no general contact pair "
                                     f"'{q.pair}' (the model has "
                                     f"{', '.join(general) or 'none'})")
                self.pairs.append(SurfaceProbe(general[q.pair], q))
            else:
                self.pairs.append(PairProbe(model, q, nodes))
        self.columns: list[str] = []
        for p in self.points:
            self.columns += [f"{p.name}_ux", f"{p.name}_uy"]
        for pp in self.pairs:
            self.columns += [f"{pp.name}_{k}" for k in PairProbe.KEYS]

    @property
    def names(self) -> list[str]:
        """Names of the point probes."""
        return [p.name for p in self.points]

    @property
    def pair_names(self) -> list[str]:
        """Names of the pair probes."""
        return [pp.name for pp in self.pairs]

    def values(self, u: Sequence[fem.Function]) -> dict[str, float]:
        """The probes' columns for the state ``u`` (collective: one reduction for all)."""
        conforming = [pp for pp in self.pairs if isinstance(pp, PairProbe)]
        every = [*self.points, *(q for pp in conforming for q in (pp.slave, pp.master))]
        r: dict[str, float] = {}
        if every:
            values = np.array([p.local_value(u) for p in every])
            if self._comm.size > 1:
                self._comm.Allreduce(MPI.IN_PLACE, values, op=MPI.SUM)
            for p, value in zip(self.points, values, strict=False):
                r[f"{p.name}_ux"], r[f"{p.name}_uy"] = float(value[0]), float(value[1])
            sides = values[len(self.points):]
            for k, pp in enumerate(conforming):
                r.update({f"{pp.name}_{key}": x for key, x in
                          pp.from_values(sides[2 * k], sides[2 * k + 1]).items()})
        for sp in self.pairs:
            if isinstance(sp, SurfaceProbe):
                r.update({f"{sp.name}_{key}": x for key, x in sp.value(u).items()})
        return r
