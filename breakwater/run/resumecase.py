"""The case of a run to resume: its calibrated modulus taken from the killed run.

A calibrated shear modulus is computed by the run, and its last digits depend on the
partition (the Goda mound's: 2277894.708936863 Pa serially, 2277894.7089616703 Pa on 2
ranks, 1.1e-11 apart). A run resumed on another number of ranks calibrated again, and
the case fingerprint (floats to 12 digits) then found another case: ``run --resume``
was refused ("the case differs ... in bodies.mound.shear_modulus"), and a study's case
failed on every rerun with another ``--ranks-per-case``.

:func:`resume_case` builds the resumed run with the killed run's calibrated modulus
(its folder's ``case.toml``) instead of calibrating again, when the case with that
modulus is the checkpoint's (its fingerprint): the same model as before the kill, on
any number of ranks, and no calibration solves.
"""

from __future__ import annotations

import contextlib
import pathlib
import tomllib
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

    On rank 0 (files); None when the case calibrates nothing, the folder holds no
    readable checkpoint or ``case.toml``, or the case with that modulus is not the
    checkpoint's (then the run refuses it, naming the keys).
    """
    body = case.calibration.body
    with contextlib.suppress(OSError, ValueError, KeyError, TypeError,
                             checkpoint.CheckpointError):
        meta = checkpoint.check(folder)
        saved = tomllib.loads((folder / files.CASE).read_text(encoding="utf-8"))
        modulus = saved["bodies"][body]["shear_modulus"]
        if not isinstance(modulus, float | int) or isinstance(modulus, bool):
            return None
        candidate = case.calibrated(body, float(modulus))
        if checkpoint.case_fingerprint(candidate.resolved()) != meta.get("fingerprint"):
            return None
        return float(modulus), (files.read_json(folder / files.SUMMARY) or {}).get(
            "calibration")
    return None


def build_to_resume(case: Case, comm: MPI.Comm) -> BuiltCase:
    """Build a case to resume in its output folder (collective).

    With calibration, the killed run's calibrated modulus is used when the case with it
    is the checkpoint's (see the module docstring); the built case's ``extra`` then
    keeps the killed run's calibration summary. Otherwise, :meth:`Case.build`.
    """
    if not case.calibration.enabled:
        return case.build(comm)
    found = on_rank_zero(comm, lambda: _saved(case, case.output_directory))
    if found is None:
        return case.build(comm)
    modulus, calibration = found
    built = case.calibrated(case.calibration.body, modulus).build(comm)
    if isinstance(calibration, dict):
        built.extra["calibration"] = calibration
    return built
