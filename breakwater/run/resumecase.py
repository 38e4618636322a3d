"""The case of a run to resume: its calibrated modulus taken from the killed run.

A calibrated shear modulus is computed by the run, and its last digits depend on the
partition (the Goda mound's: 2277894.708936863 Pa serially, 2277894.7089616703 Pa on 2
ranks, 1.1e-11 apart). A run resumed on another number of ranks calibrated again, and
the case fingerprint (floats to 12 digits) then found another case: ``run --resume``
was refused ("the case differs ... in bodies.mound.shear_modulus"), and a study's case
failed on every rerun with another ``--ranks-per-case``.

:func:`build_to_resume` builds the resumed run with the killed run's calibrated modulus
(its folder's ``case.toml``) instead of calibrating again, when the case with that
modulus is the checkpoint's (its fingerprint): the same model as before the kill, on
any number of ranks, and no calibration solves. A case that is not the checkpoint's (a
key edited since the kill) is refused before the case is meshed and calibrated, naming
the keys that differ: calibrated again, on another number of ranks it was refused after
the calibration's solves, naming ``bodies.mound.shear_modulus`` beside the key edited.
"""

from __future__ import annotations

import contextlib
import pathlib
from typing import TYPE_CHECKING, Any

from breakwater.common import files
from breakwater.common.parallel import on_rank_zero
from breakwater.outputs import checkpoint

if TYPE_CHECKING:
    from mpi4py import MPI

    from breakwater.casefile.build import BuiltCase
    from breakwater.casefile.case import Case

__all__ = ["build_to_resume"]


def _saved(case: Case, folder: pathlib.Path) -> tuple[float, Any] | None:
    """The killed run's calibrated modulus and calibration summary, if its case is this one.

    On rank 0 (files). None when the folder holds no readable checkpoint or
    ``case.toml`` (the run then says why it cannot resume), or when the case calibrates
    nothing or the killed run's ``case.toml`` has no modulus.

    Raises:
        checkpoint.CaseMismatch: The case (with the killed run's modulus) is not the
            checkpoint's: refused here, before meshing and calibrating, naming the keys
            that differ (calibrated again, the modulus was named too: its last digits
            depend on the partition).
    """
    meta: dict[str, Any] | None = None
    with contextlib.suppress(OSError, checkpoint.CheckpointError):
        meta = checkpoint.check(folder)
    saved = files.read_toml(folder / files.CASE)
    if meta is None or saved is None:
        return None
    modulus = _modulus(case, saved)
    if case.calibration.enabled and modulus is None:
        return None  # the run calibrates and compares
    try:
        candidate = case if modulus is None else case.calibrated(case.calibration.body,
                                                                 modulus)
        resolved = candidate.resolved()
        same = checkpoint.case_fingerprint(resolved) == meta.get("fingerprint")
    except (ValueError, KeyError, TypeError):
        return None  # the run builds the case and compares
    if not same:
        raise checkpoint.CaseMismatch.of(folder / checkpoint.CHECKPOINT,
                                         checkpoint.case_differences(saved, resolved))
    if modulus is None:
        return None
    return modulus, (files.read_json(folder / files.SUMMARY) or {}).get("calibration")


def _modulus(case: Case, saved: dict[str, Any]) -> float | None:
    """The calibrated body's shear modulus in the killed run's ``case.toml`` (or None)."""
    if not case.calibration.enabled:
        return None
    try:
        modulus = saved["bodies"][case.calibration.body]["shear_modulus"]
    except (KeyError, TypeError):
        return None
    if not isinstance(modulus, float | int) or isinstance(modulus, bool):
        return None
    return float(modulus)


def build_to_resume(case: Case, comm: MPI.Comm) -> BuiltCase:
    """Build a case to resume in its output folder (collective).

    With calibration, the killed run's calibrated modulus is used (see the module
    docstring); the built case's ``extra`` then keeps the killed run's calibration
    summary. Otherwise, :meth:`Case.build`. A case that is not the checkpoint's is
    refused first (:class:`~breakwater.outputs.checkpoint.CaseMismatch`, on every rank).
    """
    found = on_rank_zero(comm, lambda: _saved(case, case.output_directory))
    if found is None:
        return case.build(comm)
    modulus, calibration = found
    built = case.calibrated(case.calibration.body, modulus).build(comm)
    if isinstance(calibration, dict):
        built.extra["calibration"] = calibration
    return built
