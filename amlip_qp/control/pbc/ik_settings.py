"""What goes into and comes out of the iterative IK (:class:`~amlip_qp.control.pbc.ik.IterativeIK`):
its :class:`IKSettings` and one call's :class:`IKResult`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from amlip_qp.exceptions import InputError


@dataclass(frozen=True)
class IKSettings:
    """Settings of :class:`~amlip_qp.control.pbc.ik.IterativeIK`.

    Attributes:
        iterations: Most Newton iterations per call when warm-started (the
            first one reuses the previous tick's final evaluation).
        cold_iterations: Most Newton iterations when starting from the estimate
            (first call, after a stance switch or a failure).
        tolerance: Stop iterating once the max-norm residual is below this
            (m / rad); only for the default iteration counts, an explicit
            ``iterations`` argument of :meth:`~amlip_qp.control.pbc.ik.IterativeIK.solve` runs them all.
        damping: Levenberg damping ``mu`` of the fallback step
            ``(A^T A + mu I) dq = -A^T F``, used only when the LU step is not
            finite (dimensionless; the rows are in m and rad).
        max_step_rad: Largest joint change per Newton step, rad (m for slide joints).
        fd_step_s: Time step of the finite difference for ``Adot v``, s.
        knee_limit_swap: When the iterations end unconverged (max-norm
            residual above ``swap_threshold``, m / rad) with a knee clamped at
            its straight-leg range limit: if that knee's output is out of reach
            (``com_z_over_stance`` for the stance knee, ``com_x_over_swing`` for
            the swing knee, with ``|y| < |h_d|``) exchange it for "knee = limit"
            (a square system again) and iterate on -- that output gives way
            (CoM height; how far the swing foot reaches) and all the others
            stay exact; otherwise restart the iterations with the knee moved
            ``knee_back_off_rad`` off the limit (the straight leg is a
            near-singular iterate). Without this the clamp breaks the rows
            through the knee (Cassie's coupling), the next step undoes it, and
            the iterates wander (``docs/TUNING.md``).
        knee_hold_short_of_limit: With ``knee_limit_swap`` and the default
            iteration counts: when the iterations end unconverged with the stance
            CoM height out of reach but the stance knee off its limit (the
            height's highest reachable value inside the range, a fold the Newton
            iterates circle), run ``cold_iterations`` more; if they do not
            converge either, exchange that output for "knee = its estimate"
            (clipped to its range) and iterate on, as at the limit
            (:mod:`~amlip_qp.control.pbc.knee_limits`).
        swap_threshold: See ``knee_limit_swap``.
        knee_back_off_rad: See ``knee_limit_swap``, rad.
    """

    iterations: int = 2
    cold_iterations: int = 8
    tolerance: float = 1e-6
    damping: float = 1e-10
    max_step_rad: float = 0.3
    fd_step_s: float = 1e-6
    knee_limit_swap: bool = True
    knee_hold_short_of_limit: bool = True
    swap_threshold: float = 1e-3
    knee_back_off_rad: float = 0.2

    def __post_init__(self):
        if self.iterations < 1 or self.cold_iterations < 1:
            raise InputError("IK iteration counts must be >= 1")
        if not (self.damping >= 0 and self.max_step_rad > 0 and self.fd_step_s > 0 and self.tolerance >= 0):
            raise InputError("IK damping and tolerance must be >= 0, max_step_rad and fd_step_s > 0")


@dataclass
class IKResult:
    """References for all coordinates (Pinocchio convention) from one IK call.

    Attributes:
        q_r: Reference configuration, shape (nq,).
        v_r: Reference velocity, shape (nv,).
        a_r: Reference acceleration, shape (nv,).
        iterations: Newton iterations done.
        residual: Max-norm of the equation residual at ``q_r`` (m / rad).
        ok: False when the solve failed and the previous reference was kept.
        knee_at_limit: A knee was held, in place of an unreachable output, at
            its straight-leg limit (``com_z_over_stance`` for the stance knee,
            ``com_x_over_swing`` for the swing knee) or, short of the limit, at
            its estimate (the stance knee; ``IKSettings.knee_hold_short_of_limit``).
    """

    q_r: np.ndarray
    v_r: np.ndarray
    a_r: np.ndarray
    iterations: int
    residual: float
    ok: bool = True
    knee_at_limit: bool = False
