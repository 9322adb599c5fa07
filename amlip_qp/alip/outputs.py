"""Reference outputs ``h_d(s)`` with their first and second time derivatives.

The output names and orders are those of ``docs/ARCHITECTURE.md``. The shapes
come from :func:`amlip_qp.alip.kernels.swing_reference` (Cassie's nine
outputs); Rabbit's four are the entries ``kernels.RABBIT_FROM_CASSIE`` of that
layout, so there is one copy of the shapes.

The swing targets ``com_x_over_swing`` / ``com_y_over_swing`` are expressed in
the current step's heading frame ``D_k`` (ARCHITECTURE.md): pass the desired
``p_sw->CoM`` at touchdown rotated into that frame
(:func:`amlip_qp.alip.heading.world_to_heading`).

Units: angles rad, lengths m, ``s`` dimensionless, ``T`` s; velocities are per
second and accelerations per second squared (``d/dt = (1/T) d/ds``).
"""

from __future__ import annotations

import numpy as np

from amlip_qp.alip import _checks as C
from amlip_qp.alip import kernels
from amlip_qp.exceptions import InputError

#: Cassie's nine outputs, in the order of ``h_0``, ``h_d`` and the SWING_REFERENCE layout.
CASSIE_OUTPUTS = (
    "torso_pitch",
    "torso_roll",
    "stance_hip_yaw",
    "swing_hip_yaw",
    "com_z_over_stance",
    "com_x_over_swing",
    "com_y_over_swing",
    "com_z_over_swing",
    "swing_toe_pitch",
)

#: Rabbit's four outputs, in order.
RABBIT_OUTPUTS = ("torso_pitch", "com_z_over_stance", "com_x_over_swing", "com_z_over_swing")

#: Output names of each supported robot.
ROBOT_OUTPUTS = {"cassie": CASSIE_OUTPUTS, "rabbit": RABBIT_OUTPUTS}

_RABBIT_IDX = np.asarray(kernels.RABBIT_FROM_CASSIE)

assert len(CASSIE_OUTPUTS) == kernels.N_CASSIE_OUTPUTS
assert tuple(CASSIE_OUTPUTS[i] for i in kernels.RABBIT_FROM_CASSIE) == RABBIT_OUTPUTS


def check_robot(robot: str) -> str:
    """Return ``robot`` if it is ``"cassie"`` or ``"rabbit"``, else raise InputError."""
    if robot not in ROBOT_OUTPUTS:
        raise InputError(f"unknown robot {robot!r}; the ALIP planner supports {sorted(ROBOT_OUTPUTS)}")
    return robot


def output_names(robot: str) -> tuple[str, ...]:
    """Output names of ``robot`` (``"cassie"`` or ``"rabbit"``), in order."""
    return ROBOT_OUTPUTS[check_robot(robot)]


def check_clearance(z_cl_m, H_m) -> None:
    """Raise InputError unless ``0 <= z_cl_m < H_m`` (m): the swing foot must stay below the CoM."""
    C.non_negative("z_cl_m (swing clearance)", z_cl_m, "m")
    C.positive("H_m (CoM height over the contact)", H_m, "m")
    if not z_cl_m < H_m:
        raise InputError(
            f"z_cl_m={z_cl_m!r} m must be smaller than H_m={H_m!r} m (the swing foot cannot rise to the CoM)"
        )


#: Largest ground pitch the references accept, rad (the terrain's slopes stay below 45 degrees).
MAX_GROUND_PITCH_RAD = 0.5 * np.pi - 1e-6


def check_ground(ground, H_m, z_cl_m) -> None:
    """Raise InputError unless the swing foot's path stays below the CoM and the pitches are sane.

    ``ground = (dz_sw0_m, dz_sw_m, slope_pitch0_rad, slope_pitch_rad)`` (m, m, rad,
    rad). The foot's apex over the stance contact is at most
    ``max(dz0, dz1) + z_cl + |dz1 - dz0| / 8`` (:func:`amlip_qp.alip.formulas.swing_height`)
    and must stay below the CoM at ``H + min(dz0, 0)``; pitches must be in
    ``(-pi/2, pi/2)``.
    """
    dz0, dz1, pitch0, pitch1 = ground
    for name, v in zip(("dz_sw0_m", "dz_sw_m", "slope_pitch0_rad", "slope_pitch_rad"), ground):
        C.finite(name, v)
    apex = max(dz0, dz1) + z_cl_m + 0.125 * abs(dz1 - dz0)
    if not apex < H_m + min(dz0, 0.0):
        raise InputError(
            f"swing foot path too high: dz_sw0_m={dz0!r}, dz_sw_m={dz1!r} m with clearance {z_cl_m!r} m reach "
            f"{apex:.3g} m over the stance contact, not below the CoM (H = {H_m!r} m); pass smaller height differences"
        )
    for name, v in (("slope_pitch0_rad", pitch0), ("slope_pitch_rad", pitch1)):
        if not abs(v) <= MAX_GROUND_PITCH_RAD:
            raise InputError(f"{name}={v!r} rad must be within (-pi/2, pi/2); pass the ground's pitch in radians")


def pack_swing_reference_input(
    robot: str,
    s,
    T_s,
    H_m,
    z_cl_m,
    h0_start,
    p_sw_des_heading_m,
    turn_rad,
    out: np.ndarray | None = None,
    ground: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0),
) -> np.ndarray:
    """Fill the dense SWING_REFERENCE input vector (15,) without validation.

    Args:
        robot: ``"cassie"`` or ``"rabbit"`` (already checked).
        s: phase in [0, 1]; T_s: step duration, s; H_m: CoM height, m; z_cl_m: clearance, m.
        h0_start: the robot's measured outputs at the step start, in its output order.
        p_sw_des_heading_m: (2,) target ``p_sw->CoM`` at touchdown in the heading frame
            ``D_k`` (x, y), m; for Rabbit only x is used.
        turn_rad: ``dD = D_{k+1} - D_k``, rad (0 for Rabbit).
        out: optional (15,) float array to fill in place (no allocation).
        ground: ``(dz_sw0_m, dz_sw_m, slope_pitch0_rad, slope_pitch_rad)``, the
            ground at lift-off and at the target relative to the stance contact
            (layout in :mod:`amlip_qp.alip.kernels`; zeros on flat ground).
            Rabbit has no toe: its pitches are not used.
    """
    u = np.empty(len(kernels.SWING_REFERENCE_INPUTS)) if out is None else out
    h0, p, (dz0, dz1, pitch0, pitch1) = h0_start, p_sw_des_heading_m, ground
    # One slice assignment per call (a control-rate hot path), in the layout of the kernels module doc.
    if robot == "cassie":
        u[:] = (s, T_s, H_m, z_cl_m, h0[2], h0[3], h0[5], h0[6], p[0], p[1], turn_rad, dz0, dz1, pitch0, pitch1)
    else:
        u[:] = (s, T_s, H_m, z_cl_m, 0.0, 0.0, h0[2], 0.0, p[0], 0.0, 0.0, dz0, dz1, 0.0, 0.0)
    return u


def reference_outputs(
    robot: str,
    s,
    T_s,
    H_m,
    z_cl_m,
    h0_start,
    p_sw_des_heading_m,
    turn_rad=0.0,
    reference_fn=None,
    *,
    dz_sw0_m=0.0,
    dz_sw_m=0.0,
    slope_pitch0_rad=0.0,
    slope_pitch_rad=0.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``h_d(s)``, ``dh_d/dt`` and ``d^2h_d/dt^2`` of ``robot`` in its output order.

    Args:
        robot: ``"cassie"`` (9 outputs) or ``"rabbit"`` (4 outputs).
        s: phase in [0, 1] (dimensionless; see :mod:`amlip_qp.alip.phase`).
        T_s: step duration, s (> 0).
        H_m: desired CoM height over the stance contact, m (> 0).
        z_cl_m: swing-foot clearance at mid-step, m (0 <= z_cl < H).
        h0_start: measured outputs at the step start, the robot's order and units.
        p_sw_des_heading_m: (2,) desired CoM minus swing contact at touchdown in the
            current step's heading frame, m (Rabbit: only x is used).
        turn_rad: turn of this step ``D_{k+1} - D_k``, rad (split +/- half to the hip yaws; Cassie only).
        reference_fn: the SWING_REFERENCE implementation (15 -> 27); default
            :func:`kernels.swing_reference`.
        dz_sw0_m: ground height where the swing foot lifted off (the previous
            stance contact) minus the stance contact, m.
        dz_sw_m: ground height at the swing target minus the stance contact, m.
        slope_pitch0_rad, slope_pitch_rad: ground pitch along the heading at
            lift-off and at the target, rad (rotation about the heading's y
            axis, positive = ground descending ahead; Cassie's toe only).
            All four ground values are 0 on flat ground; see
            :func:`check_ground` for their limits.

    Returns:
        Three float arrays of the robot's output count: values (rad or m), first
        time derivatives (per s) and second time derivatives (per s^2).
    """
    names = output_names(robot)
    C.finite("s", s)
    if not 0.0 <= s <= 1.0:
        raise InputError(f"phase s={s!r} must be in [0, 1]; clip it with amlip_qp.alip.phase.step_phase_clipped")
    C.positive("T_s (step duration)", T_s, "s")
    check_clearance(z_cl_m, H_m)
    h0 = C.vector("h0_start", h0_start, len(names))
    target = C.vector("p_sw_des_heading_m", p_sw_des_heading_m, 2)
    C.finite("turn_rad", turn_rad)
    ground = (dz_sw0_m, dz_sw_m, slope_pitch0_rad, slope_pitch_rad)
    check_ground(ground, H_m, z_cl_m)
    u = pack_swing_reference_input(robot, s, T_s, H_m, z_cl_m, h0, target, turn_rad, ground=ground)
    y = np.asarray((reference_fn or kernels.swing_reference)(u), dtype=float).reshape(-1)
    return split_reference(robot, y)


def late_descent(h_end, rate_mps, tau_s) -> tuple[float, float, float]:
    """``com_z_over_swing`` after a late touchdown: keep descending until contact.

    Past the end of the step (``tau_s`` s after ``T``, phase held at 1) the swing
    foot keeps going down at ``rate_mps`` (m/s, > 0 descends: the CoM-minus-foot
    height grows) while the CoM holds its height. Returns the value, the first
    and the second time derivative ``(h_end + rate tau, rate, 0)`` (m, m/s, m/s^2),
    ``h_end`` being the reference at s = 1. Pass the reference's own ``dh/dt`` at
    s = 1 as the rate for a velocity-continuous continuation (the planner's
    ``late_descent="landing"``).
    """
    return h_end + rate_mps * tau_s, rate_mps, 0.0


def split_reference(robot: str, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split a SWING_REFERENCE output (27,) into the robot's ``(h_d, dh_d, ddh_d)`` (new arrays)."""
    n = kernels.N_CASSIE_OUTPUTS
    if robot == "cassie":
        y = y.copy()  # one copy (the kernels may return a shared buffer), three views of it
        return y[:n], y[n : 2 * n], y[2 * n :]
    return y[_RABBIT_IDX], y[n + _RABBIT_IDX], y[2 * n + _RABBIT_IDX]
