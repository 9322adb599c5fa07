"""The gait phase ``s = (t - t_step_start) / T`` (paper eq. phase_variable).

:func:`step_phase` is strict: ``s`` outside ``[0, 1]`` raises InputError. In
a real gait the swing foot often touches down a little *after* ``T`` (late
touchdown), so ``t - t_step_start > T`` happens and is not an error; a walking
controller uses :func:`step_phase_clipped` (or ``step_phase(..., clip=True)``),
which holds ``s = 1`` (the references stay at their end-of-step targets with
zero phase velocity) until the touchdown is detected, and
:func:`time_remaining`, which holds the predictor horizon at 0 s.
"""

from __future__ import annotations

from amlip_qp.alip import _checks as C
from amlip_qp.exceptions import InputError

#: Slack (dimensionless) for :func:`step_phase` so that round-off at s = 0 or 1 is not an error.
PHASE_TOLERANCE = 1e-9


def _checked(t_s, t_step_start_s, T_s) -> float:
    C.finite("t_s", t_s)
    C.finite("t_step_start_s", t_step_start_s)
    C.positive("T_s (step duration)", T_s, "s")
    return (float(t_s) - float(t_step_start_s)) / float(T_s)


def step_phase(t_s: float, t_step_start_s: float, T_s: float, clip: bool = False) -> float:
    """Phase ``s`` in ``[0, 1]`` (dimensionless) at time ``t_s`` (s) of a step started at
    ``t_step_start_s`` (s) with duration ``T_s`` (s).

    With ``clip=False`` it raises InputError when ``s`` is outside ``[0, 1]`` by
    more than :data:`PHASE_TOLERANCE` (values within it are clamped). With
    ``clip=True`` it behaves as :func:`step_phase_clipped`, for gaits where late
    touchdowns (``s > 1``) are expected.
    """
    s = _checked(t_s, t_step_start_s, T_s)
    if not clip and (s < -PHASE_TOLERANCE or s > 1.0 + PHASE_TOLERANCE):
        raise InputError(
            f"phase s = (t - t_step_start)/T = {s:.6g} is outside [0, 1] (t_s={t_s}, t_step_start_s={t_step_start_s}, "
            f"T_s={T_s}); call start_step at touchdown, or use step_phase_clipped() for late touchdowns"
        )
    return min(max(s, 0.0), 1.0)


def step_phase_clipped(t_s: float, t_step_start_s: float, T_s: float) -> float:
    """Phase ``s`` clipped to ``[0, 1]`` (dimensionless).

    A late touchdown (``t - t_step_start > T``) gives ``s = 1``; a time before the
    step start gives ``s = 0``. Arguments as in :func:`step_phase`; ``T_s <= 0`` and
    non-finite times still raise InputError.
    """
    s = _checked(t_s, t_step_start_s, T_s)
    return min(max(s, 0.0), 1.0)


def time_remaining(t_s: float, t_step_start_s: float, T_s: float) -> float:
    """Time left in the step, ``max(T - (t - t_step_start), 0)`` in s (0 after a late ``T``)."""
    C.finite("t_s", t_s)
    C.finite("t_step_start_s", t_step_start_s)
    C.positive("T_s (step duration)", T_s, "s")
    return max(float(T_s) - (float(t_s) - float(t_step_start_s)), 0.0)
