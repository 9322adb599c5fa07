"""Typed exceptions of amlip_qp.

Every error the library raises on purpose derives from :class:`AmlipError`,
so a caller can catch the whole family at once. Errors caused by a bad
argument or state value also derive from :class:`ValueError`, and a missing
file from :class:`FileNotFoundError`, so generic handlers keep working.

Each message says what was wrong *and* what to do about it.
"""

from __future__ import annotations

from typing import Any


class AmlipError(Exception):
    """Base class of every error amlip_qp raises on purpose."""


class InputError(AmlipError, ValueError):
    """An argument or a state value is invalid (NaN, out of range, wrong shape...)."""


class UnknownRobotError(AmlipError, ValueError):
    """A robot name is neither a bundled robot nor a path to an MJCF file."""


class ProfileError(InputError):
    """A robot profile file is missing, is not TOML, or has a key that is unknown, of the wrong
    type or out of range (the message names the file and the key)."""


class ModelFileError(AmlipError, FileNotFoundError):
    """A robot model file does not exist."""


class MJCFError(AmlipError, ValueError):
    """A model file exists but cannot be parsed, or lacks what amlip_qp needs."""


class PlantMismatchError(InputError):
    """A plant model lacks joints, actuators or bodies the controller needs (the message names them)."""


class CodegenError(AmlipError):
    """Generating, compiling or loading the CasADi-generated C code failed."""


class CompilerUnavailableError(CodegenError):
    """No usable C compiler for generated code that has a Python equivalent
    (the message says why; set ``$AMLIP_QP_CC`` to a compiler)."""


class QPError(AmlipError):
    """A tracker QP could not be solved.

    Attributes:
        problem: The problem object that failed (for inspection or re-solving
            with another backend), or ``None``.
        status: The solver's status string, if any.
    """

    def __init__(self, message: str, problem: Any = None, status: str | None = None):
        super().__init__(message)
        self.problem = problem
        self.status = status


class InvalidQPError(QPError):
    """A QP is malformed before any solve: a field of the wrong shape, a NaN or infinite matrix
    or vector entry, a NaN bound, or a lower bound above its upper bound
    (:meth:`QPProblem.validate <amlip_qp.qp.problem.QPProblem.validate>`). Fix what built it: the
    state estimate, the references or the gains."""


class UnverifiedCommandWarning(UserWarning):
    """A command inside the robot's physical bounds but outside what its acceptance verifies
    (its profile's ``[verified]``): it runs, unverified. The CLI prints it as one line on stderr."""
