"""The contact pairs as the model holds them: their settings and their integration data.

:class:`ContactPair` is a conforming pair (the two bodies meet on one facet group, node
on node), :class:`SurfacePair` a general pair (two surfaces that need not match, with
finite sliding: :mod:`breakwater.contact.general`); :class:`PairData` is what the
model builds for a conforming pair (:mod:`breakwater.model.model`).

:class:`Pair` is what everything after a step asks of a pair of either kind at a
stepper's state: its history columns (``<name>_<quantity>``), its ledger terms
(:class:`EnergyTerms`), its probes (:class:`PairProbe`), its nodal state for the
snapshots and the ParaView fields (:class:`FieldNodes`) and its static measures of
contact quality (:class:`StaticMeasures`). The contact layer implements it and the
stepper builds the pairs on its state (:attr:`breakwater.stepping.gn22.GN22.contacts`).

Nothing here imports dolfinx at module level: the case file reads these settings.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Protocol

import numpy as np

from breakwater.common.errors import CaseError
from breakwater.config.fields import suggest
from breakwater.config.frozen import assignment_hint
from breakwater.model.built import REBUILD, BuiltPart

if TYPE_CHECKING:
    import ufl
    from dolfinx import fem

    from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/

__all__ = ["HEXAHEDRA", "INTEGRATIONS", "PENETRATION_TIE", "PROBE_KEYS", "PROBE_KEYS_3D",
           "ContactPair", "EnergyTerms", "FieldNodes", "Pair", "PairData", "PairProbe",
           "StaticMeasures", "SurfacePair", "check_pair_settings", "facet_size",
           "max_penetration", "pair_names", "penetration_facet", "probe_keys", "probed_pair",
           "settlement", "three_d_general"]

HEXAHEDRA = ("a 3D general pair (non-matching surfaces) needs a tetrahedral mesh (its faces "
             "are triangles); this one has hexahedra (the goda3d generator's): mesh the "
             "bodies with tetrahedra, or share the interface's nodes (a conforming pair)")
"""Why a 3-D general pair refuses a hexahedral mesh."""

INTEGRATIONS = ("segments", "gauss", "nodes")


def check_pair_settings(penalty: float, friction: float, regularisation: float, slave: str,
                        master: str) -> None:
    """Check the law's settings and bodies of a contact pair (conforming or general).

    Raises:
        ValueError: A setting out of range, or the same body on both sides.
    """
    if not penalty > 0:
        raise ValueError(f"contact penalty must be > 0 (got {penalty})")
    if not friction >= 0:
        raise ValueError(f"friction coefficient must be >= 0 (got {friction})")
    if not regularisation > 0:
        raise ValueError(f"regularisation must be > 0 (got {regularisation})")
    if slave == master:
        raise ValueError("a contact pair needs two different bodies")


@assignment_hint(REBUILD)
@dataclass(frozen=True)
class SurfacePair:
    """Penalty contact with regularised Coulomb friction between two surfaces.

    Attributes:
        name: The pair's name (the case's ``[contact.NAME]``).
        slave: Body whose integration points are projected.
        master: Body whose surface (and outward normal) they are projected on.
        slave_surface: Facet group on the slave's boundary.
        master_surface: Facet group on the master's boundary, or several making one
            surface (:attr:`master_groups`).
        penalty: Normal penalty ε_n (N/m³).
        friction: Coulomb coefficient μ (-).
        regularisation: Regularisation velocity χ (m/s).
        points: Gauss points per integration segment (``segments``, ``gauss``).
        integration: The slave's integration points: ``segments`` (each slave facet
            cut where the master facets' vertices project onto it, ``points`` Gauss
            points per segment: segment-to-segment, exact on a flat patch),
            ``gauss`` (``points`` Gauss points per slave facet: Gauss-point-to-segment)
            or ``nodes`` (the slave facet's nodes with Gauss–Lobatto weights,
            Simpson's on a P2 facet: node-to-segment, the conforming pair's
            quadrature).
        rotations: ``finite``: the normal and tangent of the current master surface
            at the projection (eq. 7); ``small``: those of the reference surface there
            (the bodies' small rotations, as the conforming pair's fixed normal; the
            projection, the gap and the slip still follow the current surfaces).
        radius: Search radius (m): a point farther from the master surface has no
            projection (out of contact); None: the longest master facet.
    """

    name: str
    slave: str
    master: str
    slave_surface: str
    master_surface: str | tuple[str, ...]
    penalty: float
    friction: float = 0.0
    regularisation: float = 1e-10
    points: int = 3
    integration: str = "segments"
    rotations: str = "finite"
    radius: float | None = None

    gap = 0.0  # the law's g_0: the geometry carries the initial gap of a general pair

    def __post_init__(self) -> None:
        check_pair_settings(self.penalty, self.friction, self.regularisation, self.slave,
                            self.master)
        if not self.points >= 1:
            raise ValueError(f"points per facet must be >= 1 (got {self.points})")
        if self.integration not in INTEGRATIONS:
            raise ValueError(f"integration must be one of {', '.join(INTEGRATIONS)} "
                             f"(got {self.integration!r})")
        if self.rotations not in ("finite", "small"):
            raise ValueError(f"rotations must be finite or small (got {self.rotations!r})")
        if not self.master_groups:
            raise ValueError("a master surface needs at least one facet group")
        if self.radius is not None and not self.radius > 0:
            raise ValueError(f"search radius must be > 0 (got {self.radius})")


    @property
    def master_groups(self) -> tuple[str, ...]:
        """The facet groups of the master surface (one or several)."""
        m = self.master_surface
        return (m,) if isinstance(m, str) else tuple(m)


@assignment_hint(REBUILD)
@dataclass(frozen=True)
class ContactPair:
    """Penalty contact with regularised Coulomb friction on a named facet group.

    Attributes:
        interface: Facet group where the two bodies meet (conforming).
        slave: Body whose displacement is penalised against the master's.
        master: Body whose outward normal defines the gap.
        penalty: Normal penalty ε_n (N/m³).
        friction: Coulomb coefficient μ (-); 0 for frictionless contact.
        regularisation: Regularisation velocity χ (m/s).
        gap: Initial normal gap g_0 (m).

    The law itself is :class:`forms.ContactLaw` (in ``forms/contact.py``), built from
    these fields by :meth:`forms.ContactLaw.of`.
    """

    interface: str
    slave: str
    master: str
    penalty: float
    friction: float = 0.0
    regularisation: float = 1e-10
    gap: float = 0.0

    def __post_init__(self) -> None:
        check_pair_settings(self.penalty, self.friction, self.regularisation, self.slave,
                            self.master)


@dataclass
class PairData(BuiltPart):
    """What the model builds for one contact pair.

    Fixed once built (:class:`~breakwater.model.built.BuiltPart`).

    Attributes:
        law: The contact law (:class:`forms.ContactLaw`) with ``fem.Constant``
            parameters; ``law.values()`` evaluates it on nodal arrays.

    """

    FIXED: ClassVar[frozenset[str]] = frozenset(
        ("spec", "slave", "master", "facet_data", "dS", "n", "law"))
    WHERE: ClassVar[str] = "model.pairs[k]"

    spec: ContactPair
    slave: int
    master: int
    facet_data: np.ndarray
    dS: ufl.Measure
    n: ufl.core.expr.Expr
    law: forms.ContactLaw

    @property
    def ε_n(self) -> fem.Constant:
        """The normal penalty (N/m³)."""
        return self.law.normal.ε_n


PROBE_KEYS = ("slip", "opening", "slave_ux", "slave_uy", "master_ux", "master_uy")
"""The values of a pair probe (its history columns ``<probe>_<key>``); in 3D also
:data:`PROBE_KEYS_3D`'s."""
PROBE_KEYS_3D = (*PROBE_KEYS, "slave_uz", "master_uz")
"""A 3D pair probe's values: the 2D ones and both sides' u_z."""


def probe_keys(gdim: int) -> tuple[str, ...]:
    """The values of a pair probe in ``gdim`` dimensions."""
    return PROBE_KEYS_3D if gdim == 3 else PROBE_KEYS


@dataclass(frozen=True)
class StaticMeasures:
    """The static measures of one pair that its contact quality is assessed from.

    Plain numbers (:class:`breakwater.outputs.quality.PairInputs` adds the pair's name).

    Attributes:
        penalty: ε_n (N/m³).
        element_size: Mean interface facet length h (m).
        young_moduli: Young's moduli (slave, master) (Pa).
        static_penetration: Largest static penetration (m).
        settlement: Static settlement (m), see :func:`settlement`.
        penetration_size: The size (:func:`facet_size`) of the facet where the static
            penetration is largest (the smallest of those meeting at its node), or the
            smallest facet of the interface when nothing penetrates (m); None: not
            measured (the mean h stands for it).
    """

    penalty: float
    element_size: float
    young_moduli: tuple[float, float]
    static_penetration: float
    settlement: float
    penetration_size: float | None = None


@dataclass(frozen=True)
class FieldNodes:
    """Where a pair's ParaView fields live (:meth:`Pair.field_values` gives their values).

    Attributes:
        group: The facet group of the fields' submesh (gmsh physical name).
        body: The body whose Lagrange degree the fields take (its index).
        x: Reference coordinates of the nodes of :meth:`Pair.field_values`, ``(n, gdim)``.
    """

    group: str
    body: int
    x: np.ndarray


class PairProbe(Protocol):
    """A pair probe: slip and opening (slave minus master) at a point of a pair.

    Its values (:data:`PROBE_KEYS`) are a function of the sums over the ranks of
    :meth:`local`, so that the probes of a run take one reduction.
    """

    def local(self, u: Sequence[fem.Function]) -> np.ndarray:
        """The rank's share of the probe's data at the state ``u`` (collective)."""
        ...

    def values(self, local: np.ndarray) -> dict[str, float]:
        """The :data:`PROBE_KEYS` from the sum over the ranks of :meth:`local`."""
        ...


class EnergyTerms(Protocol):
    """A pair's terms of the energy ledger (:class:`breakwater.energy.ledger.EnergyLedger`).

    Built once per ledger (:meth:`Pair.energy_terms`) on the ledger's copies of the
    state at the start of the step.
    """

    def local(self, step: bool) -> np.ndarray:
        """The rank's share of the pair's ledger terms, shape (3,), to be summed over the ranks.

        The penalty energy ``∫ ½ ε_n ⟨−g_n⟩₊²`` and the friction power ``P_F`` at the
        stepper's accepted state, then the interface share of the step's numerical
        dissipation (:mod:`breakwater.energy.dissipation`; 0 with ``step`` False, at
        the first record, and for a pair whose law is not a form).

        Args:
            step: The state is the end of a step, not the first record.
        """
        ...


class Pair(Protocol):
    """A contact pair at a stepper's accepted state: what everything after the step asks of it.

    Ownership: the model owns the pairs' settings and integration data
    (:attr:`breakwater.model.model.ContactModel.pairs`, conforming: :class:`PairData`;
    ``surface_pairs``, general: :class:`SurfacePair`); the stepper owns the pair
    *objects* on its state (:attr:`breakwater.stepping.gn22.GN22.contacts`, conforming
    pairs first, then the general ones, each kind in the model's order), because a
    pair is measured at a state and one model can have several steppers (the
    relaxation's and the run's). The energy ledger, the monitor, the probes, the
    fields, the snapshots and the quality report reach the pairs through
    ``stepper.contacts`` only, and never ask which kind a pair is.

    Both kinds implement it: a conforming pair
    (:class:`breakwater.contact.pairstate.ConformingPair`) and a general pair
    (:class:`breakwater.contact.general.SurfaceContact`). Everything a pair writes is
    named by the pair: history columns ``<name>_<quantity>``
    (:mod:`breakwater.outputs.monitor`).
    """

    @property
    def name(self) -> str:
        """The pair's name: the case's ``[contact.<name>]``."""
        ...

    @property
    def columns(self) -> list[str]:
        """The pair's history columns, in order."""
        ...

    def measure(self) -> dict[str, float]:
        """The values of :attr:`columns` at the accepted state (collective, every rank)."""
        ...

    def energy_terms(self, u0: Sequence[fem.Function], v0: Sequence[fem.Function]
                     ) -> EnergyTerms:
        """The pair's ledger terms (:class:`EnergyTerms`; collective).

        Args:
            u0: The ledger's displacements at the start of the step (one per body).
            v0: Its velocities there.
        """
        ...

    def snapshot(self, u: Sequence[fem.Function]) -> dict[str, np.ndarray]:
        """The pair's nodal state at ``u`` for the ``.npz`` snapshots (every rank; collective).

        ``x`` (reference coordinates of the nodes, sorted by x then y), ``normal``
        (the master's outward normal), ``gap`` (g_n), ``slip`` (2D: along
        t = (n_y, −n_x)) and ``pressure`` (ε_n ⟨−g_n⟩₊; a general pair's: its
        dual-basis nodal pressure where positive, else 0, and ``pressure_dual``
        unclipped, :func:`breakwater.contact.slavepoints.snapshot`).
        """
        ...

    def field_nodes(self) -> FieldNodes:
        """Where the pair's ParaView fields live (collective on the first call)."""
        ...

    def field_values(self, u: Sequence[fem.Function], v: Sequence[fem.Function] | None
                     ) -> dict[str, np.ndarray]:
        """The contact state at :meth:`field_nodes`, for ParaView (collective).

        ``pressure``, ``gap`` (shape ``(n,)``), ``slip``, ``slip_velocity`` and
        ``friction_traction`` (shape ``(n, gdim)``); ``v`` None: at rest.
        """
        ...

    def static_measures(self, u: Sequence[fem.Function]) -> StaticMeasures:
        """The measures of the pair's contact quality at the static state ``u`` (collective)."""
        ...

    def static_check(self) -> str | None:
        """Why the pair cannot start from the meshed configuration, or None (collective).

        The static stage calls it for every pair before it looks for the initial state
        (:class:`breakwater.statics.pseudostep.PseudoStepper`), which raises
        :class:`~breakwater.common.errors.MeshError` with the reason: a general pair's
        bodies overlapped beyond what its search sees
        (:func:`breakwater.contact.penetration.initial_overlap`).
        """
        ...

    def probe(self, point: Sequence[float], name: str) -> PairProbe:
        """A pair probe at ``point`` (reference coordinates) named ``name`` (collective).

        Raises:
            MeshError: The point is not on the pair's interface (slave surface).
        """
        ...


def pair_names(pairs: Sequence[ContactPair]) -> list[str]:
    """Names of conforming pairs: the interface group, or the index where it repeats.

    The interface group is the case's ``[contact.<name>]``.
    """
    names = [p.interface for p in pairs]
    return [n if names.count(n) == 1 else str(k) for k, n in enumerate(names)]


def probed_pair(probe: str, pair: int | str, conforming: int, general: Sequence[str]) -> int:
    """The index among the stepper's pairs of the pair a pair probe names.

    The stepper's pairs (:attr:`breakwater.stepping.gn22.GN22.contacts`) are the
    conforming pairs, then the general ones, each kind in the model's order.

    Args:
        probe: The probe's name (for the messages).
        pair: The probe's pair (:class:`breakwater.config.runspec.PairProbeSpec`): a
            conforming pair's index in ``model.pairs``, or a general pair's name.
        conforming: The number of conforming pairs.
        general: The names of the general pairs.

    Raises:
        CaseError: No such pair (one line, as a probe's unknown body: a ``ValueError``
            before, which the run reported as a crash, ``SimulationFailed``).
    """
    if isinstance(pair, str):
        if pair not in general:
            raise CaseError(f"pair probe '{probe}': no general contact pair '{pair}'"
                            f"{suggest(pair, general)} (the model has "
                            f"{', '.join(general) or 'none'})")
        return conforming + list(general).index(pair)
    if not 0 <= pair < conforming:
        raise CaseError(f"pair probe '{probe}': no contact pair {pair} in model.pairs ("
                        + (f"indices 0 to {conforming - 1})" if conforming
                           else "the model has no conforming pair)"))
    return pair


def facet_size(vertices: np.ndarray) -> np.ndarray:
    """The size h of facets from their vertices ``(..., corners, gdim)`` (m).

    As the interface's mean h (:func:`breakwater.contact.conforming.mean_facet_length`):
    in 2D the length; in 3D the side of the equilateral triangle (3 corners) or of the
    square (4 corners, dolfinx's order: v₃ opposite v₀) of the facet's area.
    """
    v = np.asarray(vertices, dtype=float)
    if v.shape[-1] == 2:
        return np.linalg.norm(v[..., 1, :] - v[..., 0, :], axis=-1)
    if v.shape[-2] == 3:
        area = 0.5 * np.linalg.norm(np.cross(v[..., 1, :] - v[..., 0, :],
                                             v[..., 2, :] - v[..., 0, :]), axis=-1)
        return np.sqrt(area * 4 / np.sqrt(3))
    area = 0.5 * np.linalg.norm(np.cross(v[..., 3, :] - v[..., 0, :],
                                         v[..., 2, :] - v[..., 1, :]), axis=-1)
    return np.sqrt(area)


def max_penetration(gap: np.ndarray) -> float:
    """The largest penetration ``max ⟨−g_n⟩₊`` of nodal normal gaps (0 if none).

    Args:
        gap: Nodal normal gaps g_n (m), negative where the bodies interpenetrate.
    """
    gap = np.asarray(gap, dtype=float)
    return float(max(0.0, -gap.min())) if gap.size else 0.0


PENETRATION_TIE = 0.01
"""Nodes whose penetration is within this fraction of the largest count as where it is
largest (:func:`penetration_facet`): the quality check compares δ/h with 1 %, and a
penetration uniform along an edge (a long block's base edge) peaks at a node that
round-off picks."""


def penetration_facet(gap: np.ndarray, sizes: np.ndarray) -> float:
    """The facet size h_δ where the nodal penetration ⟨−g_n⟩₊ is largest (inf: none).

    The smallest facet size among the nodes whose penetration is within
    :data:`PENETRATION_TIE` of the largest, so that it does not depend on which of
    nearly equal nodes round-off makes the deepest: on the goda3d block's base edge,
    uniform along z, it read 0.014 m or 0.045 m (0.17 % or 0.054 % of h) as the
    caisson's sides were free or on rollers (2026-11-29). With no penetration, the
    smallest facet size.

    Args:
        gap: Nodal normal gaps g_n (m).
        sizes: The facet size at each node (m).
    """
    gap, sizes = np.asarray(gap, dtype=float), np.asarray(sizes, dtype=float)
    δ = max_penetration(gap)
    if δ <= 0:
        return float(sizes.min(initial=np.inf))
    return float(sizes[-gap >= (1.0 - PENETRATION_TIE) * δ].min())


def settlement(u_slave: np.ndarray, u_master: np.ndarray, normal: np.ndarray) -> float:
    """Static settlement: ``|mean(½(u_s + u_m)·n)|`` over the interface nodes (m).

    Args:
        u_slave: Slave displacements at the interface nodes, shape (n, gdim).
        u_master: Master displacements at the same nodes, shape (n, gdim).
        normal: Unit normals at the nodes, shape (n, gdim).
    """
    u = 0.5 * (np.asarray(u_slave, float) + np.asarray(u_master, float))
    if not len(u):
        return 0.0
    return float(abs(np.mean(np.sum(u * np.asarray(normal, float), axis=1))))


def three_d_general(integration: str) -> str | None:
    """Why a general pair with this integration cannot run in 3-D (None: it can).

    3-D general pairs (:mod:`breakwater.contact.general3d`) run with ``segments`` or
    ``gauss`` integration: ``nodes`` has no 3-D analogue on 6-node faces (a quadratic
    triangle's vertex weights integrate to zero).
    """
    if integration == "nodes":
        return ("integration = \"nodes\" has no 3D analogue (a 6-node triangle's vertex "
                "weights integrate to zero): \"segments\" or \"gauss\"")
    return None
