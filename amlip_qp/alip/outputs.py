"""Reference outputs ``h_d(s)`` with their first and second time derivatives.

The reference kernel (:func:`amlip_qp.alip.kernels.swing_reference`) gives
the references of every output a robot may declare
(:data:`REFERENCE_OUTPUTS`, :mod:`amlip_qp.profiles.outputs`); a robot takes
the entries of its own outputs (:class:`OutputSet`), in its order, so there
is one copy of the shapes and it does not depend on the robot.

The swing targets ``com_x_over_swing`` / ``com_y_over_swing`` are expressed in
the current step's heading frame ``D_k`` (ARCHITECTURE.md): pass the desired
``p_sw->CoM`` at touchdown rotated into that frame
(:func:`amlip_qp.alip.heading.world_to_heading`).

Units: angles rad, lengths m, ``s`` dimensionless, ``T`` s; velocities are per
second and accelerations per second squared (``d/dt = (1/T) d/ds``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from amlip_qp.alip import _checks as C
from amlip_qp.alip import kernels
from amlip_qp.exceptions import InputError
from amlip_qp.profiles.outputs import output_primitives

#: Every output the reference kernel gives, in its order (``SWING_REFERENCE``'s ``h_d`` block).
REFERENCE_OUTPUTS = (
    "torso_pitch",
    "torso_roll",
    "stance_hip_yaw",
    "swing_hip_yaw",
    "com_z_over_stance",
    "com_x_over_swing",
    "com_y_over_swing",
    "com_z_over_swing",
    "swing_toe_pitch",
    "swing_foot_roll",
)

assert len(REFERENCE_OUTPUTS) == kernels.N_REFERENCE_OUTPUTS


def _position(names: tuple[str, ...], name: str) -> int:
    """Index of ``name`` in ``names``, -1 if it is not there."""
    return names.index(name) if name in names else -1


class OutputSet:
    """A robot's outputs as the planner sees them: names, order and what the kernels need of them.

    A set without ``com_y_over_swing`` is planar (and then has no lateral
    output at all, :attr:`OutputPrimitive.lateral
    <amlip_qp.profiles.outputs.OutputPrimitive.lateral>`): its robot walks
    in the sagittal plane, heading 0.

    Args:
        names: The robot's output names, in its order (:mod:`amlip_qp.profiles.outputs`).

    Raises:
        InputError: An unknown or repeated name, or a set no walking robot can have.
    """

    def __init__(self, names: Sequence[str]):
        if isinstance(names, OutputSet):
            names = names.names
        if isinstance(names, str):
            raise InputError(f"outputs must be a sequence of output names, got the string {names!r}")
        names = tuple(names)
        planar = "com_y_over_swing" not in names
        output_primitives(names, planar)
        #: Output names, in order.
        self.names: tuple[str, ...] = names
        #: True for a set without lateral outputs (the sagittal plane only).
        self.planar = planar
        #: Each output's index in :data:`REFERENCE_OUTPUTS`.
        self.reference_index = np.array([REFERENCE_OUTPUTS.index(n) for n in names], dtype=int)
        n_ref = kernels.N_REFERENCE_OUTPUTS
        # h_d, dh_d and ddh_d's places in a SWING_REFERENCE output, one after the other (split_reference)
        self._split_index = np.concatenate([self.reference_index + k * n_ref for k in range(3)])
        # Where the kernel's step-start and command inputs come from (-1: not an output; its input is 0).
        self._i_stance_yaw = _position(names, "stance_hip_yaw")
        self._i_swing_yaw = _position(names, "swing_hip_yaw")
        self._i_x = _position(names, "com_x_over_swing")
        self._i_y = _position(names, "com_y_over_swing")
        self._turns = self._i_stance_yaw >= 0 or self._i_swing_yaw >= 0
        self._toe = "swing_toe_pitch" in names

    def __len__(self) -> int:
        return len(self.names)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, OutputSet) and other.names == self.names

    def __hash__(self) -> int:
        return hash(self.names)

    def __repr__(self) -> str:
        return f"OutputSet({list(self.names)!r})"

    def index(self, name: str) -> int:
        """Index of the output ``name``; :class:`InputError` if the set has none."""
        if name not in self.names:
            raise InputError(f"no output {name!r}; the outputs are {', '.join(self.names)}")
        return self.names.index(name)

    def pack_swing_reference_input(
        self,
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
            s: phase in [0, 1]; T_s: step duration, s; H_m: CoM height, m; z_cl_m: clearance, m.
            h0_start: the robot's measured outputs at the step start, in its output order.
            p_sw_des_heading_m: (2,) target ``p_sw->CoM`` at touchdown in the heading frame
                ``D_k`` (x, y), m; y only with a ``com_y_over_swing`` output.
            turn_rad: ``dD = D_{k+1} - D_k``, rad (only with hip-yaw outputs).
            out: optional (15,) float array to fill in place (no allocation).
            ground: ``(dz_sw0_m, dz_sw_m, slope_pitch0_rad, slope_pitch_rad)``, the
                ground at lift-off and at the target relative to the stance contact
                (layout in :mod:`amlip_qp.alip.kernels`; zeros on flat ground). The
                pitches only with a ``swing_toe_pitch`` output.

        An input that none of the set's outputs uses is 0.
        """
        u = np.empty(len(kernels.SWING_REFERENCE_INPUTS)) if out is None else out
        h0, p, (dz0, dz1, pitch0, pitch1) = h0_start, p_sw_des_heading_m, ground
        i_st, i_sw, i_x, i_y = self._i_stance_yaw, self._i_swing_yaw, self._i_x, self._i_y
        lateral, turns, toe = i_y >= 0, self._turns, self._toe
        # One slice assignment per call (a control-rate hot path), in the layout of the kernels module doc.
        u[:] = (
            s, T_s, H_m, z_cl_m,
            h0[i_st] if i_st >= 0 else 0.0, h0[i_sw] if i_sw >= 0 else 0.0,
            h0[i_x], h0[i_y] if lateral else 0.0,
            p[0], p[1] if lateral else 0.0, turn_rad if turns else 0.0,
            dz0, dz1, pitch0 if toe else 0.0, pitch1 if toe else 0.0,
        )  # fmt: skip
        return u

    def split_reference(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Split a SWING_REFERENCE output into this set's ``(h_d, dh_d, ddh_d)`` (new memory: three
        consecutive parts of one new array, gathered at once)."""
        parts = y[self._split_index]
        k = len(self.names)
        return parts[:k], parts[k : 2 * k], parts[2 * k :]


def output_set(outputs: Sequence[str] | OutputSet) -> OutputSet:
    """``outputs`` as an :class:`OutputSet` (itself if it is one)."""
    return outputs if isinstance(outputs, OutputSet) else OutputSet(outputs)


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


def reference_outputs(
    outputs: Sequence[str] | OutputSet,
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
    """``h_d(s)``, ``dh_d/dt`` and ``d^2h_d/dt^2`` of ``outputs``, in their order.

    Args:
        outputs: The robot's output names (or their :class:`OutputSet`).
        s: phase in [0, 1] (dimensionless; see :mod:`amlip_qp.alip.phase`).
        T_s: step duration, s (> 0).
        H_m: desired CoM height over the stance contact, m (> 0).
        z_cl_m: swing-foot clearance at mid-step, m (0 <= z_cl < H).
        h0_start: measured outputs at the step start, the robot's order and units.
        p_sw_des_heading_m: (2,) desired CoM minus swing contact at touchdown in the
            current step's heading frame, m (only x without a ``com_y_over_swing`` output).
        turn_rad: turn of this step ``D_{k+1} - D_k``, rad (split +/- half to the hip yaws).
        reference_fn: the SWING_REFERENCE implementation (15 -> 30); default
            :func:`kernels.swing_reference`.
        dz_sw0_m: ground height where the swing foot lifted off (the previous
            stance contact) minus the stance contact, m.
        dz_sw_m: ground height at the swing target minus the stance contact, m.
        slope_pitch0_rad, slope_pitch_rad: ground pitch along the heading at
            lift-off and at the target, rad (rotation about the heading's y
            axis, positive = ground descending ahead; ``swing_toe_pitch`` only).
            All four ground values are 0 on flat ground; see
            :func:`check_ground` for their limits.

    Returns:
        Three float arrays of the robot's output count: values (rad or m), first
        time derivatives (per s) and second time derivatives (per s^2).
    """
    outputs = output_set(outputs)
    names = outputs.names
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
    u = outputs.pack_swing_reference_input(s, T_s, H_m, z_cl_m, h0, target, turn_rad, ground=ground)
    y = np.asarray((reference_fn or kernels.swing_reference)(u), dtype=float).reshape(-1)
    return outputs.split_reference(y)


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
