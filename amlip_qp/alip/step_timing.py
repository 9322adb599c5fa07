"""The current step's duration for a moved foothold: the one-step law's target brought to it by timing.

A terrain-aware controller may move the one-step law's swing target along the
heading (off a stair's edge, onto one tread: the planner's ``foothold`` hook).
With the step time fixed, a foothold moved by ``d`` misses the desired momentum
at the end of the next step by about ``m H l sinh(lT) d`` (about 11 of the
14 kg m^2/s of a 0.4 m/s walk for ``d = 0.1`` m on Cassie). The law's target
moves with the time left ``tau`` of the current step (the CoM travels on and
its momentum grows), so a step that ends later (earlier) puts the target
further ahead (behind). :func:`time_left_for_step` finds the ``tau`` at which
the law's target is the moved foothold, within bounds (:class:`StepTiming`); the
planner then plans the step to end there (the step clock's planned duration),
and its lateral placement follows from the law at that ``tau``.

Along the heading ``u`` of the next step, with ``p`` the CoM over the stance
contact and ``L`` the momentum of the sagittal pair (``(p_u, L_v)``, ``v`` the
heading's left axis), ``xi = p + L / (m H l)``, ``eta = p - L / (m H l)`` and
``sigma = exp(l tau)``, the law's step (target minus stance contact) is

    d(tau) = p_hat - p_sw_des = A sigma + B / sigma + C,
    A = (a + b) xi / 2,  B = (a - b) eta / 2,  C = -L_des / K,
    K = m (H l sinh(lT) - v_z cosh(lT)),  a = 1 + m v_z cosh(lT) / K,
    b = m H l cosh(lT) (1 - dz / H) / K,

(:func:`amlip_qp.alip.formulas.foot_placement` after :func:`~amlip_qp.alip.formulas.flow`
over ``tau``), so ``d(tau) = d`` is a quadratic in ``sigma``. Its root in
the bounds nearest the nominal ``tau`` is taken; without one, the bound where
``|d(tau) - d|`` (the end-of-next-step momentum error over ``K``) is least.
Numpy only; docs/EQUATIONS.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from amlip_qp.alip import _checks as C
from amlip_qp.alip.clock import StepClock
from amlip_qp.exceptions import InputError

__all__ = ["NOMINAL_TOL_S", "StepTiming", "retime", "time_left_bounds", "time_left_for_step"]

#: A planned duration this close to the command's ``T`` (s) is ``T`` itself.
NOMINAL_TOL_S = 1e-9


@dataclass(frozen=True, kw_only=True)
class StepTiming:
    """The bounds of a step's duration planned for a moved foothold.

    Attributes:
        step_time_min: shortest step, in units of the command's ``T`` (> 0).
        step_time_max: longest step, in units of ``T`` (>= step_time_min).
        min_time_left_s: the least time left a re-plan may give the step, s (>= 0); once the
            planned end is this close it is kept.
    """

    step_time_min: float = 0.6
    step_time_max: float = 1.4
    min_time_left_s: float = 0.05

    def __post_init__(self):
        C.positive("StepTiming.step_time_min", self.step_time_min, "")
        C.non_negative("StepTiming.min_time_left_s", self.min_time_left_s, "s")
        if not self.step_time_max >= self.step_time_min:
            raise InputError(
                f"StepTiming.step_time_max ({self.step_time_max!r}) must be >= step_time_min ({self.step_time_min!r})"
            )


def time_left_bounds(timing: StepTiming, T_s: float, t_in_s: float, planned_T_s: float | None) -> tuple[float, float]:
    """``(tau_lo, tau_hi)``, s: the time left the step may be given at ``t_in_s`` into it (command
    step time ``T_s``; ``planned_T_s`` the duration planned so far, or None). Once the planned end is
    within ``min_time_left_s`` (or past), both are the planned time left: the end is kept."""
    if planned_T_s is not None and planned_T_s - t_in_s <= timing.min_time_left_s:
        kept = max(planned_T_s - t_in_s, 0.0)
        return kept, kept
    hi = max(timing.step_time_max * T_s - t_in_s, 0.0)
    lo = min(max(timing.step_time_min * T_s - t_in_s, timing.min_time_left_s), hi)
    return lo, hi


def time_left_for_step(
    p_m: float,
    L: float,
    step_m: float,
    L_des: float,
    T_s: float,
    mass_kg: float,
    H_m: float,
    v_z_mps: float,
    g_mps2: float,
    dz_m: float,
    tau_lo_s: float,
    tau_hi_s: float,
    tau_nom_s: float,
) -> float:
    """The time left ``tau`` (s) in ``[tau_lo_s, tau_hi_s]`` at which the one-step law steps ``step_m``
    (module doc).

    Args:
        p_m, L: the CoM over the stance contact along the next step's heading (m) and the momentum of
            that sagittal pair now (kg m^2/s).
        step_m: the foothold's offset from the stance contact along the heading, m.
        L_des: the desired momentum of the pair at the end of the next step, kg m^2/s.
        T_s, mass_kg, H_m, v_z_mps, g_mps2, dz_m: the law's next step time (s), mass, CoM height,
            CoM vertical velocity (clamped as the law's), gravity and the foothold's height over the
            stance contact (m).
        tau_lo_s, tau_hi_s: the bounds of the time left (:func:`time_left_bounds`), s.
        tau_nom_s: the nominal time left, s: of two roots, the nearer one is taken.
    """
    l = math.sqrt(g_mps2 / H_m)
    ch, sh = math.cosh(l * T_s), math.sinh(l * T_s)
    mHl = mass_kg * H_m * l
    K = mass_kg * (H_m * l * sh - v_z_mps * ch)
    a = 1.0 + mass_kg * v_z_mps * ch / K
    b = mHl * ch * (1.0 - dz_m / H_m) / K
    xi, eta = p_m + L / mHl, p_m - L / mHl
    A, B, c0 = 0.5 * (a + b) * xi, 0.5 * (a - b) * eta, -L_des / K - step_m
    s_lo, s_hi = math.exp(l * tau_lo_s), math.exp(l * tau_hi_s)

    def miss(sig: float) -> float:
        return abs(A * sig + B / sig + c0)

    roots: list[float] = []
    if A != 0.0:
        disc = c0 * c0 - 4.0 * A * B
        if disc >= 0.0:
            q = -0.5 * (c0 + math.copysign(math.sqrt(disc), c0))  # the numerically stable pair of roots
            roots = [q / A] + ([B / q] if q != 0.0 else [])
    elif c0 != 0.0:
        roots = [-B / c0]
    roots = [r for r in roots if s_lo <= r <= s_hi]
    if not roots:
        return min((tau_lo_s, tau_hi_s), key=lambda tau: abs(A * math.exp(l * tau) + B / math.exp(l * tau) + c0))
    s_nom = math.exp(l * tau_nom_s)
    best = min(roots, key=lambda sig: abs(math.log(sig / s_nom)))
    return min(max(math.log(best) / l, tau_lo_s), tau_hi_s)


def retime(
    timing: StepTiming,
    clock: StepClock,
    plan_fn: Callable[[np.ndarray], np.ndarray],
    u: np.ndarray,
    y: np.ndarray,
    step_x_m: float,
    step_y_m: float,
    T_s: float,
    t_in_s: float,
) -> float:
    """The current step's duration (s) at which the one-step law's target is ``(step_x_m, step_y_m)`` from
    the stance contact along the next heading (:func:`time_left_for_step`), planned on ``clock``.

    ``u`` and ``y`` are the ``ALIP_PLAN`` inputs and outputs of this tick (:mod:`amlip_qp.alip.kernels`,
    at the command's step time ``T_s``, ``t_in_s`` into the step); both are re-planned in place with
    ``plan_fn`` for the new time left. A duration within 1e-9 s of ``T_s`` is ``T_s``.
    """
    p0, p1, L0, L1, t_rem, v_z, _, _, hn, _, m, H, _, _, g, dz = u.tolist()
    c, sn = math.cos(hn), math.sin(hn)
    tau_lo, tau_hi = time_left_bounds(timing, T_s, t_in_s, clock.planned_step_time_s)
    tau = time_left_for_step(
        c * p0 + sn * p1, c * L1 - sn * L0, c * step_x_m + sn * step_y_m, c * float(y[5]) - sn * float(y[4]),
        T_s, m, H, v_z, g, dz, tau_lo, tau_hi, t_rem,
    )  # fmt: skip
    T_cur = t_in_s + tau
    if abs(T_cur - T_s) < NOMINAL_TOL_S:
        T_cur, tau = T_s, t_rem
    clock.plan_step_time(T_cur)
    if tau != t_rem:
        u[4] = tau
        y[:] = np.asarray(plan_fn(u), dtype=float).reshape(-1)
    return T_cur
