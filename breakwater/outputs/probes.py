"""Probes: fields evaluated at points, the same on every rank.

:class:`~breakwater.model.pointprobe.PointProbe` evaluates one body's field at a point;
a pair probe gives the slip and opening of a contact pair at a point, and the pair makes
it (:meth:`breakwater.model.pairs.Pair.probe`: a conforming pair's
:class:`~breakwater.contact.pairstate.ConformingProbe`, a general pair's
:class:`~breakwater.contact.slavepoints.SurfaceProbe`); :class:`Probes` holds the probes
of a run (``output.probes`` and ``output.pair_probes``) and gives their history columns.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater.config.runspec import OutputSpec
from breakwater.model.model import ContactModel
from breakwater.model.pairs import PROBE_KEYS, Pair, PairProbe, probed_pair
from breakwater.model.pointprobe import PointProbe

__all__ = ["PROBE_KEYS", "PointProbe", "Probes"]


class Probes:
    """The probes of a run: point probes and pair probes.

    Columns: ``<probe>_ux``, ``<probe>_uy`` per point probe, then
    ``<pair probe>_<key>`` per pair probe (keys of :data:`PROBE_KEYS`).

    Args:
        model: The contact model.
        output: The probes' specifications.
        pairs: The pairs (the stepper's :attr:`~breakwater.stepping.gn22.GN22.contacts`);
            a pair probe names one (:func:`breakwater.model.pairs.probed_pair`).

    """

    def __init__(self, model: ContactModel, output: OutputSpec, pairs: Sequence[Pair]) -> None:
        self._comm = model.comm
        self.points = [PointProbe(model, p.body, p.point, p.name) for p in output.probes]
        general = [p.name for p in model.surface_pairs]
        self.pairs: list[tuple[str, PairProbe]] = [
            (q.name, pairs[probed_pair(q.name, q.pair, len(model.pairs), general)].probe(
                q.point, q.name))
            for q in output.pair_probes]
        self.columns: list[str] = []
        for p in self.points:
            self.columns += [f"{p.name}_ux", f"{p.name}_uy"]
        for name, _ in self.pairs:
            self.columns += [f"{name}_{k}" for k in PROBE_KEYS]

    @property
    def names(self) -> list[str]:
        """Names of the point probes."""
        return [p.name for p in self.points]

    @property
    def pair_names(self) -> list[str]:
        """Names of the pair probes."""
        return [name for name, _ in self.pairs]

    def values(self, u: Sequence[fem.Function]) -> dict[str, float]:
        """The probes' columns for the state ``u`` (collective: one reduction for all)."""
        every = [*(p.local_value(u) for p in self.points), *(pp.local(u) for _, pp in self.pairs)]
        r: dict[str, float] = {}
        if not every:
            return r
        values = np.concatenate(every)
        if self._comm.size > 1:
            self._comm.Allreduce(MPI.IN_PLACE, values, op=MPI.SUM)
        parts = np.split(values, np.cumsum([len(x) for x in every])[:-1])
        for p, value in zip(self.points, parts, strict=False):
            r[f"{p.name}_ux"], r[f"{p.name}_uy"] = float(value[0]), float(value[1])
        for (name, pp), value in zip(self.pairs, parts[len(self.points):], strict=True):
            r.update({f"{name}_{key}": x for key, x in pp.values(value).items()})
        return r
