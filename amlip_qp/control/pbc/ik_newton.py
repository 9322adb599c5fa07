"""The damped Newton step of the iterative IK (:mod:`amlip_qp.control.pbc.ik`) and its LU solves.

Each Newton step solves ``A dq = -F`` with ``A``'s LU factors (LAPACK getrf,
getrs); only if that step is not finite (a singular or ill-conditioned ``A``)
does it take the damped least-squares step ``(A^T A + mu I) dq = -A^T F``.
The step is then scaled down so that its joint part (the coordinates after
the base's) moves no joint more than ``max_step_rad``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg.lapack import dgetrf as _dgetrf
from scipy.linalg.lapack import dgetrs as _dgetrs

_add_reduce = np.add.reduce


def all_finite(*arrays) -> bool:
    """True if every entry is finite (a NaN or inf makes the sum non-finite; cheaper than
    ``np.all(np.isfinite(.))`` on these small arrays; the ufunc's reduce skips the Python
    layers of ``np.sum`` and ``ndarray.sum``)."""
    for a in arrays:
        if not math.isfinite(_add_reduce(a)):
            return False
    return True


def lu_solve(lu, b: np.ndarray) -> np.ndarray:
    """Solve with LU factors from :func:`lu_factor` (LAPACK getrs)."""
    x, info = _dgetrs(lu[0], lu[1], b)
    if info != 0:
        raise np.linalg.LinAlgError(f"getrs info {info}")
    return x


def lu_factor(A: np.ndarray):
    """LU factors of ``A`` (LAPACK getrf), or ``None`` if ``A`` is singular."""
    lu, piv, info = _dgetrf(A)
    return (lu, piv) if info == 0 else None


def newton_step(
    F: np.ndarray, A: np.ndarray, lu, damping: float, max_step_rad: float, n_base: int, eye: np.ndarray
) -> np.ndarray:
    """The step ``dq`` for the residual ``F`` and the matrix ``A`` (its LU factors ``lu``, or ``None``).

    ``damping`` is ``mu`` of the least-squares fallback (``eye`` the identity of ``A``'s size);
    the step is scaled down, whole, so that its largest joint coordinate (of ``dq[n_base:]``) is at
    most ``max_step_rad``, rad.
    """
    dq = -lu_solve(lu, F) if lu is not None else np.full(F.shape, np.nan)
    if not all_finite(dq):
        mu = damping
        dq = np.linalg.solve(A.T @ A + mu * eye, -A.T @ F)
    nb = n_base
    jmax = float(abs(dq[nb:]).max()) if dq.size > nb else 0.0
    if jmax > max_step_rad:
        dq *= max_step_rad / jmax
    return dq
