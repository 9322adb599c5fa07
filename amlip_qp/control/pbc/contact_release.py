"""The PBC's tick without its stance contact, for a tick whose contact force would pull the foot.

:class:`~amlip_qp.control.pbc.tracker.PBCTracker` solves (1)-(3) of its module doc each tick as one
square system ``K x = rhs`` in ``x = (vdot, tau_ctrl, lambda)``: the rows are the dynamics (``nv``),
the stance contact (``n_contact``), the rigid springs, the controlled joints' accelerations (``na``);
the columns ``vdot`` (``nv``), ``tau_ctrl`` (``na``), the contact's ``lambda`` (``n_contact``), the
springs' ``lambda``. The contact holds the foot as an equality, so nothing keeps its normal force
positive: in a tick where the solve asks the ground to pull the foot, the plant cannot give that force
and the torques that rely on it do not act as computed. With ``PBCGains.release_pulling_contact`` such a
tick is solved again by :func:`solve_released`, with the contact's rows and columns left out: the foot
free, the springs still held, the controlled joints' accelerations as before.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import dgesv as _dgesv


def solve_released(
    K: np.ndarray, rhs: np.ndarray, nv: int, na: int, n_contact: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(vdot, tau_ctrl, lambda)`` of ``K x = rhs`` (the PBC's system, module doc) without the stance
    contact's rows and columns; ``lambda`` keeps its shape, the contact's part zero. ``K`` and ``rhs``
    are only read.

    Raises:
        numpy.linalg.LinAlgError: Singular system.
    """
    n = K.shape[0]
    rows = np.r_[0:nv, nv + n_contact : n]
    cols = np.r_[0 : nv + na, nv + na + n_contact : n]
    _, _, x, info = _dgesv(K[np.ix_(rows, cols)], rhs[rows], overwrite_a=1, overwrite_b=0)
    if info != 0:
        raise np.linalg.LinAlgError(f"singular PBC system without the stance contact (dgesv info {info})")
    lam = np.zeros(n - nv - na)
    lam[n_contact:] = x[nv + na :]
    return x[:nv], x[nv : nv + na], lam
