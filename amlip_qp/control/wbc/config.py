"""Weights, gains and limits of the whole-body QP, and the tuned configurations.

Each robot's tuned configuration is a table of its profile file
(``[trackers.qp]``, :mod:`amlip_qp.profiles`), turned into a :class:`QPConfig`
by :func:`config_from_table`; :func:`default_config` looks it up. The
measurements behind the bundled robots' values are in docs/TUNING.md,
section "QP tracker".
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from amlip_qp.exceptions import InputError

if TYPE_CHECKING:
    from amlip_qp.robots.robot import Robot


#: The QP solvers of the whole-body QP (:attr:`QPConfig.qp_solver`).
QP_SOLVERS = ("proxqp", "daqp")


@dataclass(frozen=True)
class QPConfig:
    """Weights, gains and limits of the whole-body QP (SI units).

    Attributes:
        output_kp: Output PD proportional gains, 1/s^2, one per output of h_0.
        output_kd: Output PD derivative gains, 1/s, one per output.
        output_weight: Output tracking weights, (m/s^2)^-2 or (rad/s^2)^-2.
        posture_kp: Posture task (actuated joints toward ``robot.q_stand``) kp, 1/s^2.
        posture_kd: Posture task kd, 1/s.
        posture_weight: Posture task weight (keep small: a null-space regulariser).
        upper_posture_kp: Posture kp of the actuated joints outside both legs (a
            humanoid's waist and arms), 1/s^2; ``None``: ``posture_kp``. The
            legs' joints are held by the outputs, these only by the posture
            task: without a stiffer hold the QP swings them to help track
            the torso and CoM outputs.
        upper_posture_kd: Their posture kd, 1/s; ``None``: ``posture_kd``.
        upper_posture_weight: Their posture weight; ``None``: ``posture_weight``.
        spring_kd: Damping gain of the passive-spring task, 1/s.
        spring_weight: Weight of the passive-spring damping task (0 disables).
        friction_mu: Friction coefficient of the pyramid (below the plant's 1.0).
        min_normal_force_N: Least normal force on each stance force point, N.
        max_normal_force_N: Largest normal force on each force point, N.
        liftoff_phase: Phase over which the previous stance foot unloads.
        touchdown_blend: Gain (0 to 1, dimensionless) on the controller's
            pre-touchdown ramp ``target.swing_contact_weight`` (0 until phase
            0.9, then up to 1 at the step's end) in the swing foot's force
            box ``w = max(touchdown_blend * swing_contact_weight, liftoff
            ramp)``. 0 (default) keeps them at zero until the touchdown
            switches the stance, after which the liftoff ramp unloads the old
            stance foot; 1 blends the landing foot's forces in before the
            touchdown is detected. Forces planned on a foot still in the air
            do not happen, so the support they stand for is missing and the
            CoM drops before the touchdown (measured: docs/TUNING.md, "QP tracker").
        contact_kd: Velocity Baumgarte gain of the stance contact rows, 1/s.
        rigid_springs: Which legs' springs (tendon coupling, passive spring
            joints) the QP holds rigid with constraint forces: ``"swing"``,
            ``"all"`` or ``"none"``
            (:mod:`amlip_qp.control.wbc.spring_elimination`).
        coupling_kp: Swing leg: stiffness of the rigid-spring constraint toward
            zero deflection (what the unloaded spring does), 1/s^2.
        coupling_kd: Swing leg: damping of the rigid-spring constraint, 1/s.
        stance_coupling_kp: Stance leg (``"all"``): stiffness toward zero
            deflection, 1/s^2. Default 0: the loaded spring keeps its
            deflection (the constraint only damps its rate), so the constraint
            force stays small instead of fighting the spring's static load.
        stance_coupling_kd: Stance leg: damping of the deflection rate, 1/s.
        joint_limit_horizon_s: Horizon of the joint-limit acceleration bounds, s.
        joint_limit_max_recovery: Cap on the acceleration the bounds may force
            (to stay feasible with the torque limits), rad/s^2.
        reg_vdot: Regularisation weight on ``vdot``, (rad/s^2)^-2.
        reg_force: Regularisation weight on forces, N^-2.
        reg_torque: Regularisation weight on joint torques, (N m)^-2.
        reg_coupling: Regularisation weight on the rigid-spring forces
            ``lambda`` (tendon and shin; eliminated, penalised through
            ``Lam x + lam0``), (N m)^-2.
        stance_foot_torque_max_Nm: Bound on the **stance** foot ("toe") motor
            torque, N m (``inf``: only the motor limit). 0 leaves the stance toe
            passive as in the paper (section "Implementing ... on a Real
            Robot"): an ankle torque changes ``L`` about the contact directly
            (``Ldot = p x m g + tau_ankle``), which the ALIP prediction ignores,
            and it shifts the centre of pressure off the blade's middle,
            unloading the toe or the heel (the foot then slips in yaw).
            A bound of the torque-limit rows
            (:class:`~amlip_qp.control.wbc.constraints.TorqueLimits`). No
            effect on robots without a foot motor.
        stance_yaw_moment_weight: Cost weight on the yaw moment (about the
            vertical) of the stance foot's contact forces, (N m)^-2. The plant's
            line contact (two friction spheres) yields to a sustained yaw
            moment: the foot creeps in yaw and the robot turns. The moment is
            fixed by the accelerations, so the penalty makes the QP prefer
            motions that need less of it (the pelvis yields in stance hip yaw).
            0 disables. A cost of the build
            (:class:`~amlip_qp.control.wbc.costs.StanceYawMomentCost`). 3-D
            feet with two force points only.
        hip_yaw_feedback: Gain (dimensionless, 0 disables) of the pelvis-yaw
            feedback on the swing hip-yaw reference (beyond the paper, whose
            hip-yaw references are open-loop straight lines). Both hip-yaw
            outputs are joint angles, so yaw the stance foot creeps in the plant
            carries over to the pelvis and then to every later step. With the
            feedback the swing hip-yaw reference becomes
            ``h_d[swing_hip_yaw] - k e_psi``, with ``e_psi = wrap(psi_pelvis -
            (D_k - h_d[stance_hip_yaw]))`` the pelvis yaw error against its
            nominal value, and its rate reference
            ``dh_d[swing_hip_yaw] - k (psidot_pelvis + dh_d[stance_hip_yaw])``:
            the swing foot lands along ``D_{k+1}`` (world yaw) whatever the
            pelvis yaw error, and the next stance's hip-yaw line returns the
            pelvis to the heading. Applied to the output task's residual
            (:class:`~amlip_qp.control.pelvis_yaw.PelvisYawFeedback`); robots
            without hip-yaw outputs ignore it.
        qp_solver: The solver of the QP, one of :data:`QP_SOLVERS`: ``"proxqp"``
            (ProxSuite's warm-started ProxQP) or ``"daqp"`` (DAQP, a dual
            active-set method hot-started from the last working set). Both
            solve the same problem; the solutions differ by the solvers'
            tolerances (docs/BENCH_QP.md). ``QPTracker(qp_solver=...)``
            overrides it.
    """

    output_kp: tuple[float, ...]
    output_kd: tuple[float, ...]
    output_weight: tuple[float, ...]
    posture_kp: float = 20.0
    posture_kd: float = 8.0
    posture_weight: float = 1e-2
    upper_posture_kp: float | None = None
    upper_posture_kd: float | None = None
    upper_posture_weight: float | None = None
    spring_kd: float = 40.0
    spring_weight: float = 0.0
    friction_mu: float = 0.7
    min_normal_force_N: float = 5.0
    max_normal_force_N: float = 1500.0
    liftoff_phase: float = 0.08
    touchdown_blend: float = 0.0
    contact_kd: float = 10.0
    rigid_springs: str = "all"
    coupling_kp: float = 400.0
    coupling_kd: float = 40.0
    stance_coupling_kp: float = 0.0
    stance_coupling_kd: float = 40.0
    joint_limit_horizon_s: float = 0.05
    joint_limit_max_recovery: float = 200.0
    reg_vdot: float = 1e-6
    reg_force: float = 1e-6
    reg_torque: float = 1e-6
    reg_coupling: float = 1e-6
    stance_foot_torque_max_Nm: float = math.inf
    stance_yaw_moment_weight: float = 0.0
    hip_yaw_feedback: float = 0.0
    qp_solver: str = "proxqp"

    def __post_init__(self) -> None:
        if self.rigid_springs not in ("swing", "all", "none"):
            raise InputError(f"rigid_springs must be 'swing', 'all' or 'none', got {self.rigid_springs!r}")
        if self.qp_solver not in QP_SOLVERS:
            raise InputError(f"qp_solver must be one of {', '.join(QP_SOLVERS)}, got {self.qp_solver!r}")
        n = len(self.output_kp)
        if len(self.output_kd) != n or len(self.output_weight) != n:
            raise InputError("output_kp, output_kd and output_weight need one entry per output")
        scalars = {
            k: getattr(self, k)
            for k in self.__dataclass_fields__
            if k not in _STRINGS and getattr(self, k) is not None  # None: an upper_posture_* left unset
        }
        for name, val in scalars.items():
            arr = np.asarray(val, dtype=float)
            may_be_inf = name == "stance_foot_torque_max_Nm"
            if np.any(np.isnan(arr)) or np.any(arr < 0) or (not may_be_inf and not np.all(np.isfinite(arr))):
                raise InputError(f"QPConfig.{name} must be finite and >= 0, got {val!r}")
        if not 0 < self.friction_mu:
            raise InputError("friction_mu must be > 0")
        if self.min_normal_force_N > self.max_normal_force_N:
            raise InputError("min_normal_force_N must not exceed max_normal_force_N")
        if self.touchdown_blend > 1.0:
            raise InputError(f"touchdown_blend must be in [0, 1], got {self.touchdown_blend!r}")
        if self.joint_limit_horizon_s <= 0:
            raise InputError("joint_limit_horizon_s must be > 0 s")

    def with_(self, **changes: Any) -> QPConfig:
        """A copy with some fields changed."""
        return replace(self, **changes)


def config_from_table(table: Mapping[str, Any]) -> QPConfig:
    """A :class:`QPConfig` from a profile's ``[trackers.qp]`` table (field name -> value; lists
    for the per-output tuples, ``inf`` for no bound); every other field keeps its default.

    Raises:
        InputError: An unknown key (naming the known ones), a value of the wrong type, or a value
            :class:`QPConfig` refuses.
    """
    known = {f.name: f for f in fields(QPConfig)}
    kwargs: dict[str, Any] = {}
    for key, value in table.items():
        if key not in known:
            raise InputError(f"unknown key {key!r} (known: {', '.join(known)})")
        if key in _PER_OUTPUT:
            if not isinstance(value, list) or not all(_is_number(v) for v in value):
                raise InputError(f"{key} must be a list of numbers, one per output, got {value!r}")
            value = tuple(float(v) for v in value)
        elif key in _STRINGS:
            if not isinstance(value, str):
                raise InputError(f"{key} must be a string, got {value!r}")
        elif not _is_number(value):
            raise InputError(f"{key} must be a number, got {value!r}")
        else:
            value = float(value)
        kwargs[key] = value
    missing = [k for k in _PER_OUTPUT if k not in kwargs]
    if missing:
        raise InputError(f"{', '.join(missing)} required (one value per output)")
    return QPConfig(**kwargs)


_PER_OUTPUT = ("output_kp", "output_kd", "output_weight")
#: The fields that hold a name, not a number.
_STRINGS = ("rigid_springs", "qp_solver")


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def default_config(robot: Robot) -> QPConfig:
    """The tuned :class:`QPConfig` of ``robot``, from its profile's ``[trackers.qp]`` table.

    A robot loaded from an MJCF file without a profile gets the configuration
    of the bundled robot whose outputs it shares
    (:func:`~amlip_qp.robots.outputs.output_names`): the gains then fit its
    outputs one for one, but they were tuned for the bundled robot; give the
    robot a profile with its own table.

    Raises:
        MJCFError: The model fits no default outputs.
        InputError: The profile has no ``qp`` table, or an invalid one.
    """
    from amlip_qp.profiles import PROFILES
    from amlip_qp.robots.outputs import output_names

    profile = robot.profile
    if profile is not None:
        profile.check_supported("qp")
    if profile is None or "qp" not in profile.trackers:
        names = output_names(robot)
        profile = next(p for p in PROFILES.values() if p.outputs == names and "qp" in p.trackers)
    return profile.tracker_config("qp")
