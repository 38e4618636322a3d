"""Exceptions that breakwater raises for its users."""

from __future__ import annotations


class BreakwaterError(Exception):
    """Base class: a problem the user can act on (bad input, failed solve)."""


class CaseError(BreakwaterError):
    """A case file (or an override) is invalid: one line, naming the field."""


class MeshError(BreakwaterError):
    """A mesh is unreadable or inconsistent with what the case asks of it."""


class OutputError(BreakwaterError):
    """An output file or folder cannot be written: ``cannot write <path>: <reason>``.

    Permissions, a full disk, a name too long: one line, exit status 1 (a check before
    the run refuses the output folder with exit status 2 instead:
    :func:`breakwater.common.files.check_writable`).
    """


def cannot_write(path: object, error: OSError) -> OutputError:
    """The :class:`OutputError` of an ``OSError`` met while writing ``path``."""
    return OutputError(f"cannot write {path}: {error.strerror or error}")


class ConvergenceError(BreakwaterError):
    """A nonlinear solve did not converge.

    Attributes:
        reason: PETSc SNES converged reason (negative on divergence).
        iterations: Newton iterations done.

    """

    def __init__(self, message: str, reason: int, iterations: int) -> None:
        super().__init__(message)
        self.reason = reason
        self.iterations = iterations


class Interrupted(BreakwaterError):
    """The run stopped on a signal (SIGTERM, SIGINT) where it was looked at (collectively).

    Between steps (the time loop) or between contact searches (a 3-D general pair: the
    static state may take many of them): ``summary.json`` says ``interrupted``.
    """


class PenetrationError(ConvergenceError):
    """A step leaves a general pair's slave node beyond what its contact search sees.

    See :mod:`breakwater.contact.penetration`: the step is rejected and cut back like a step
    that did not converge.
    """
