"""Typed run configuration shared by the case layer and the run layer.

The run layer (:mod:`breakwater.simulation`) never reads TOML: it receives
these frozen dataclasses, built by the case layer (:mod:`breakwater.case`).
"""

from __future__ import annotations

import pathlib
from dataclasses import dataclass

__all__ = ["OutputSpec", "PairProbeSpec", "ProbeSpec", "TimeSpec"]


@dataclass(frozen=True)
class ProbeSpec:
    """Displacement history of a material point of one body.

    Attributes:
        name: Probe name, used in the output column names (e.g. ``"gauge_top"``).
        body: Name of the body the point belongs to (e.g. ``"caisson"``).
        point: Coordinates of the point.
    """

    name: str
    body: str
    point: tuple[float, ...]


@dataclass(frozen=True)
class PairProbeSpec:
    """Relative slip and opening at an interface point (slave minus master).

    Attributes:
        name: Probe name (e.g. ``"corner_front"``).
        pair: Index of the contact pair in ``model.pairs``.
        point: Coordinates of the interface point.
    """

    name: str
    pair: int
    point: tuple[float, ...]


@dataclass(frozen=True)
class TimeSpec:
    """Time integration and nonlinear solver settings.

    Attributes:
        dt: Nominal time step (s).
        end_time: Final time (s).
        beta1: GN22 parameter β1.
        beta2: GN22 parameter β2.
        allow_conditional: Allow conditionally stable (β1, β2).
        max_cutbacks: A failing step is retried with dt/2, up to this many halvings.
        newton_rtol: Newton relative residual tolerance.
        newton_atol: Newton absolute tolerance, as a fraction of the load-vector norm.
        newton_max_it: Maximum number of Newton iterations per step.
    """

    dt: float
    end_time: float
    beta1: float = 0.6
    beta2: float = 0.605
    allow_conditional: bool = False
    max_cutbacks: int = 4
    newton_rtol: float = 1e-9
    newton_atol: float = 1e-9
    newton_max_it: int = 40


@dataclass(frozen=True)
class OutputSpec:
    """What to write and where.

    Attributes:
        directory: Output directory (created if missing).
        field_interval: Write VTX fields every N steps (0: never).
        probes: Point displacement probes.
        pair_probes: Interface slip/opening probes.
        figures: Draw the figures at the end of the run.
        progress: Progress bar; ``None``: only when stderr is a TTY.
        case_name: Name of the case, used in reports.
        checkpoint_interval: Write a checkpoint every N steps (0: never); see
            :mod:`breakwater.checkpoint` and ``run(..., resume=True)``.
    """

    directory: pathlib.Path
    field_interval: int = 10
    probes: tuple[ProbeSpec, ...] = ()
    pair_probes: tuple[PairProbeSpec, ...] = ()
    figures: bool = True
    progress: bool | None = None
    case_name: str = "case"
    checkpoint_interval: int = 0
