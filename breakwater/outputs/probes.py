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

from breakwater.common.jit import kernel
from breakwater.config.runspec import OutputSpec
from breakwater.model.model import ContactModel
from breakwater.model.pairs import PROBE_KEYS, Pair, PairProbe, probe_keys, probed_pair
from breakwater.model.pointprobe import PointProbe

__all__ = ["PROBE_KEYS", "PointProbe", "Probes"]


@kernel
def probe_sums(arrays: tuple[np.ndarray, ...], body: np.ndarray, entry: np.ndarray,
               weight: np.ndarray, slot: np.ndarray, out: np.ndarray) -> np.ndarray:
    """``out[slot_q] += weight_q arrays[body_q][entry_q]`` over the terms q, in order.

    The point probes' values Σ_j φ_j(x) u_j, a term per (probe, component, block).
    """
    out[:] = 0.0
    for q in range(body.shape[0]):
        out[slot[q]] += weight[q] * arrays[body[q]][entry[q]]
    return out


def _point_terms(probes: Sequence[PointProbe]) -> list[np.ndarray]:
    """The terms of :func:`probe_sums` of point probes: their values in turn."""
    terms: list[tuple[int, int, float, int]] = []
    start = 0
    for p in probes:
        for c in range(p.size):
            terms += [(p.body.index, int(e), float(w), start + c)
                      for e, w in zip(p._entries[:, c], p._phi, strict=True)]
        start += p.size
    return [np.array([t[k] for t in terms], dtype=d).reshape(-1)
            for k, d in enumerate((np.int64, np.int64, np.float64, np.int64))]


class Probes:
    """The probes of a run: point probes and pair probes.

    Columns: ``<probe>_ux``, ``<probe>_uy`` (3D: and ``_uz``) per point probe, then
    ``<pair probe>_<key>`` per pair probe (keys of :func:`probe_keys`).

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
        self._axes = ("ux", "uy", "uz")[:model.gdim]
        for p in self.points:
            self.columns += [f"{p.name}_{a}" for a in self._axes]
        for name, _ in self.pairs:
            self.columns += [f"{name}_{k}" for k in probe_keys(model.gdim)]
        # The point probes, and the pair probes made of two (a conforming pair's: its
        # local values are its slave's then its master's), in one compiled sum.
        self._fused = [isinstance(getattr(pp, "slave", None), PointProbe)
                       and isinstance(getattr(pp, "master", None), PointProbe)
                       for _, pp in self.pairs]
        points = [*self.points, *(q for (_, pp), f in zip(self.pairs, self._fused, strict=True)
                                  if f for q in (pp.slave, pp.master))]  # type: ignore[attr-defined]
        self._terms = body, entry, weight, slot = _point_terms(points)
        self._sums = np.zeros(sum(p.size for p in points))
        self._arrays: tuple[list[fem.Function], tuple[np.ndarray, ...]] | None = None
        if len(self._terms[0]):  # compiled (or loaded from numba's cache) now
            probe_sums(tuple(np.zeros(1) for _ in model.bodies), body[:0], entry[:0],
                       weight[:0], slot[:0], self._sums)

    @property
    def names(self) -> list[str]:
        """Names of the point probes."""
        return [p.name for p in self.points]

    @property
    def pair_names(self) -> list[str]:
        """Names of the pair probes."""
        return [name for name, _ in self.pairs]

    def local(self, u: Sequence[fem.Function]) -> list[np.ndarray]:
        """Each probe's values on this rank (its share): the point probes', the pair probes'.

        The point probes' (and the conforming pair probes', two point probes each) from
        one :func:`probe_sums`, the others' from their ``local``.
        """
        if self._arrays is None or any(a is not b for a, b in zip(self._arrays[0], u,
                                                                   strict=True)):
            self._arrays = (list(u), tuple(f.x.array for f in u))  # views
        body, entry, weight, slot = self._terms
        sums = probe_sums(self._arrays[1], body, entry, weight, slot, self._sums) \
            if len(body) else self._sums
        out, k = [], 0
        for p in self.points:
            out.append(sums[k:k + p.size])
            k += p.size
        for (_, pp), fused in zip(self.pairs, self._fused, strict=True):
            if fused:
                n = pp.slave.size + pp.master.size  # type: ignore[attr-defined]
                out.append(sums[k:k + n])
                k += n
            else:
                out.append(pp.local(u))
        return out

    def values(self, u: Sequence[fem.Function]) -> dict[str, float]:
        """The probes' columns for the state ``u`` (collective: one reduction for all)."""
        r: dict[str, float] = {}
        every = self.local(u)
        if not every:
            return r
        values = np.concatenate(every)
        if self._comm.size > 1:
            self._comm.Allreduce(MPI.IN_PLACE, values, op=MPI.SUM)
        parts, k = [], 0  # (slices: np.split took 10 µs a row)
        for x in every:
            parts.append(values[k:k + len(x)])
            k += len(x)
        for p, value in zip(self.points, parts, strict=False):
            for a, x in zip(self._axes, value, strict=True):
                r[f"{p.name}_{a}"] = float(x)
        for (name, pp), value in zip(self.pairs, parts[len(self.points):], strict=True):
            r.update({f"{name}_{key}": x for key, x in pp.values(value).items()})
        return r

    def local_reference(self, u: Sequence[fem.Function]) -> list[np.ndarray]:
        """:meth:`local` from each probe's ``local_value``/``local`` (the reference)."""
        return [*(p.local_value(u) for p in self.points), *(pp.local(u) for _, pp in self.pairs)]
