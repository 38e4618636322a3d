"""The state of a run between two steps, saved and restored as a whole by checkpoints.

:class:`RunState` is the run's bookkeeping (the step-size controller, the solver
statistics, the static results, the output bookkeeping) plus, in a saved copy, the
plain-number state of the objects the run steps with (the stepper's step size and
counters, the energy ledger's sums, the peak snapshot's instant, the history rows
written). :func:`save` writes it with the nodal fields to ``checkpoint.npz``
(:mod:`breakwater.outputs.checkpoint`); :func:`load` reads it back and checks that it fits
the run to resume. Floats are written with ``repr`` (JSON), so they read back exactly.
"""

from __future__ import annotations

import dataclasses
import pathlib
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater.common.parallel import on_every_rank, on_rank_zero
from breakwater.config.runspec import TimeSpec
from breakwater.outputs import checkpoint as ckpt
from breakwater.outputs.checkpoint import CheckpointError
from breakwater.outputs.quality import PairInputs
from breakwater.stepping.stepsize import StepSize

__all__ = ["Checkpoint", "RunState", "load", "save"]


@dataclass
class RunState:
    """Everything of a run that a checkpoint saves besides the nodal fields.

    Attributes:
        step: The step-size controller (time, step size, accepted steps, cut-backs).
        steps: Accepted time steps.
        iterations: Newton iterations of each accepted step.
        failed_steps: Steps that failed (and were retried with a cut-back).
        failed_iterations: Newton iterations of the failed steps.
        static: The ``static`` entry of the summary.
        static_iterations: Newton iterations of the static solve.
        contact: The static measures of each pair's contact quality.
        fields_time: Time of the last ParaView (VTX) output.
        field_parts: VTX files of the earlier parts of a resumed run.
        wall_before: Wall time of the earlier parts of a resumed run (s); in a saved
            copy, the wall time up to the checkpoint.
        resumed_from: Where each earlier part ended: ``t``, ``steps``, ``mpi_size``.
        history_rows: (Saved copy) Rows of ``history.csv`` at the checkpoint.
        stepper: (Saved copy) The stepper's ``dt`` constant, ``flips``, ``floor_accepts``.
        ledger: (Saved copy) The energy ledger's state
            (:meth:`~breakwater.energy.ledger.EnergyLedger.state`).
        snapshot: (Saved copy) ``time`` and ``value`` of the peak snapshot.
        time_loop: Wall time of the time loop (``wall``, s), its CPU time (``cpu``) and
            the wall time of its parts: ``outputs``
            (history rows, ledger, fields, checkpoints) and, for the fast solver, the
            parts of :class:`~breakwater.stepping.condensed.Timings`; summed over resumed parts.
        applied_loads: The sums of the loads applied so far
            (:class:`~breakwater.outputs.applied.AppliedLoads`).

    """

    step: StepSize
    steps: int = 0
    iterations: list[int] = field(default_factory=list)
    failed_steps: int = 0
    failed_iterations: int = 0
    static: dict[str, Any] = field(default_factory=dict)
    static_iterations: int = 0
    contact: list[PairInputs] = field(default_factory=list)
    fields_time: float = 0.0
    field_parts: list[str] = field(default_factory=list)
    wall_before: float = 0.0
    resumed_from: list[dict[str, Any]] = field(default_factory=list)
    history_rows: int = 0
    stepper: dict[str, Any] = field(default_factory=dict)
    ledger: dict[str, Any] = field(default_factory=dict)
    snapshot: dict[str, Any] = field(default_factory=dict)
    time_loop: dict[str, float] = field(default_factory=dict)
    applied_loads: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def start(cls, time: TimeSpec) -> RunState:
        """The state of a new run with the time settings ``time``."""
        return cls(StepSize(time.dt, time.end_time, time.max_cutbacks, time.dt_floor,
                            levels=time.levels,
                            tolerance=time.tolerance if time.adaptive else 0.0))

    def as_dict(self) -> dict[str, Any]:
        """Plain data (JSON): nested dataclasses as dictionaries."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any], time: TimeSpec) -> RunState:
        """The state of :meth:`as_dict`; the time settings are the run's ``time``."""
        step = {**data["step"], "dt": time.dt, "end_time": time.end_time,
                "max_cutbacks": time.max_cutbacks, "floor": time.dt_floor,
                "levels": time.levels,
                "tolerance": time.tolerance if time.adaptive else 0.0}
        return cls(**{**data, "step": StepSize(**step),
                      "contact": [PairInputs(**c) for c in data["contact"]]})


@dataclass
class Checkpoint:
    """A checkpoint read back: the run state and the checkpoint's context.

    Attributes:
        state: The run state.
        columns: The history columns of the run that wrote it.
        mpi_size: The number of ranks that wrote it.
        arrays: The nodal values (:func:`~breakwater.outputs.checkpoint.gather_nodal`).

    """

    state: RunState
    columns: list[str]
    mpi_size: int
    arrays: dict[str, np.ndarray]

    def restore_fields(self, functions: Sequence[Sequence[fem.Function]]) -> None:
        """Set the Functions (per body, in the order saved) from the checkpoint."""
        ckpt.scatter_nodal(self.arrays, functions)


def save(directory: pathlib.Path, fingerprint: str, bodies: Sequence[str],
         columns: Sequence[str], state: RunState,
         functions: Sequence[Sequence[fem.Function]], comm: MPI.Comm) -> None:
    """Write ``checkpoint.npz`` (collective: the nodal values are gathered on rank 0).

    Args:
        directory: The output folder.
        fingerprint: Identifies the case (:mod:`breakwater.outputs.checkpoint`).
        bodies: Names of the bodies.
        columns: The history columns.
        state: The run state (a saved copy).
        functions: The Functions of each body to save.
        comm: The communicator of the mesh.
    """
    arrays = ckpt.gather_nodal(functions, comm)

    def write() -> None:
        if arrays is not None:
            data = state.as_dict()
            # The per-step lists as arrays: in the JSON metadata a storm of 250 000
            # steps wrote 6 MB of text (24 MB as NumPy's string) at every checkpoint.
            per_step = {"steps_iterations": np.asarray(data.pop("iterations"), np.int64),
                        "steps_accepted": np.asarray(data["step"].pop("accepted"), float)}
            meta = {"fingerprint": fingerprint, "mpi_size": comm.size,
                    "bodies": list(bodies), "columns": list(columns), "state": data}
            ckpt.write(directory / ckpt.CHECKPOINT, meta, {**arrays, **per_step})

    on_rank_zero(comm, write)  # an OutputError (e.g. a full disk) on every rank


def load(directory: pathlib.Path, fingerprint: str, bodies: Sequence[str], time: TimeSpec,
         comm: MPI.Comm) -> Checkpoint:
    """Read the checkpoint of ``directory`` (collective); nothing in the folder changes.

    Raises:
        CheckpointError: No checkpoint, another case, a finished run, or other bodies.
    """
    # Rank 0 decides whether there is a checkpoint to resume, and its metadata is every
    # rank's; each rank then reads the nodal values, and a read that fails on one rank
    # fails on every rank (alone, that rank raised while the others went on to build
    # the stepper, a collective, and waited there for good).
    meta = on_rank_zero(comm, lambda: ckpt.check(directory, fingerprint))
    if meta["bodies"] != list(bodies):
        raise CheckpointError(f"the checkpoint's bodies {meta['bodies']} are not the "
                              "model's")

    def nodal_values() -> dict[str, np.ndarray]:
        arrays = ckpt.read(directory / ckpt.CHECKPOINT, fingerprint)[1]
        if "steps_iterations" not in arrays or "steps_accepted" not in arrays:
            raise CheckpointError(f"{directory / ckpt.CHECKPOINT}: no per-step arrays (a "
                                  "damaged checkpoint)")
        return arrays

    arrays = on_every_rank(comm, nodal_values)
    data = meta["state"]
    data["iterations"] = [int(i) for i in arrays.pop("steps_iterations")]
    data["step"]["accepted"] = [float(h) for h in arrays.pop("steps_accepted")]
    return Checkpoint(RunState.from_dict(data, time), meta["columns"], meta["mpi_size"],
                      arrays)
