"""The IMU's reading turned into that of an IMU fixed to the base with the base's axes.

The contact-aided EKF (:mod:`~amlip_qp.estimation.invariant_ekf`) tracks a
point fixed to the base body with the base's axes: the *base IMU*. The robot's
IMU may sit anywhere (:class:`~amlip_qp.profiles.ImuMount`): on the base with
its own axes, or on another body (a humanoid's torso, behind the waist
joints). :class:`ImuToBase` turns each reading into the base IMU's before the
EKF sees it, with the encoder kinematics at the measured joint positions and
velocities on its own copy of the controller's Pinocchio model; the filter and
its generated C are the same for every mounting.

Frames: ``W`` world, ``b`` base, ``i`` IMU. With the base held at the identity
pose and at rest (so that Pinocchio's world is the base frame) the encoders
give the IMU's axes ``R_bi`` and position ``p_bi`` in the base frame, its
velocity ``v_rel`` and angular velocity ``w_rel`` relative to the base, and
its acceleration relative to the base at zero joint accelerations,
``a_rel0 = Jdot qdot`` (all base axes). The base IMU sits at ``P``: the
mounting's position on the base itself; on another body the IMU's position at
the robot's stand pose (``p_bi`` at ``q_stand``), so that ``r = p_bi - P``
stays small while the joints between stay near their stand angles.

- orientation: ``R_Wb = R_Wi R_bi^T`` (exact);
- angular velocity: ``w_b = R_bi w_i - w_rel`` (exact);
- specific force at ``P``, base axes (the rigid-body transport from the IMU's point):
  ``f_P = R_bi f_i - w_b x (w_b x r) - 2 w_b x v_rel - a_rel0 - J qddot - alpha_b x r``.

:meth:`ImuToBase.reading` is exact when it is given the joint accelerations
``qddot`` and the base's angular acceleration ``alpha_b`` (tested against
MuJoCo to 1e-13). The encoders give neither, so the estimator
(:meth:`ImuToBase.estimator_reading`) takes ``qddot`` as the finite
difference of the measured joint velocities from the last tick, and
**neglects** ``alpha_b x r`` (the gyro differentiated would be mostly noise;
``r`` is the IMU's displacement from its stand position, centimetres). Both
terms vanish on the base (``r = 0``, ``J = 0``), where the reading is turned
exactly. The error this leaves in the specific force, measured on 2.5 s of a
G1 walk with the IMU on the torso (``tests/test_estimation_imu_to_base.py``,
``docs/EQUATIONS.md``): 0.23 m/s^2 RMS (5.5 at most, at touchdowns), against
1.20 m/s^2 RMS (12.4 at most) with ``J qddot`` neglected as well. The gyro
and accelerometer biases the EKF estimates are those of the base IMU: the
IMU's own biases turned by ``R_bi``, which moves with the joints between.

An IMU on the base with the base's own axes (:attr:`ImuToBase.identity`) is
the base IMU: its readings are passed on untouched, bit for bit.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.estimation.rotations import quat_wxyz_to_rot, quat_xyzw_to_rot, rot_to_quat_xyzw
from amlip_qp.exceptions import InputError
from amlip_qp.messages import ImuReading
from amlip_qp.profiles.profile import UNIT_QUATERNION_TOL

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.profiles import ImuMount
    from amlip_qp.robots.robot import Robot

#: Name of the frame :class:`ImuToBase` adds to its copy of the Pinocchio model at the IMU.
IMU_FRAME = "amlip-imu"


class ImuToBase:
    """The base IMU's reading from the robot's IMU (see the module doc).

    Args:
        robot: A floating-base robot (the controller's model).
        mount: Where the IMU sits (:class:`~amlip_qp.profiles.ImuMount`; ``body`` ``None``: the base body).

    Attributes:
        body: The IMU's body.
        on_base: True when that body is the base.
        identity: True on the base with the base's axes: :meth:`reading` returns its input.
        point_in_base_m: ``P``, where the base IMU sits in the base frame, m, shape (3,).

    Raises:
        InputError: A robot without a floating base, a body the model lacks, a position that is
            not 3 finite numbers, or a quaternion that is not 4 numbers of norm 1.
    """

    def __init__(self, robot: Robot, mount: ImuMount):
        import pinocchio as pin

        if not robot.is_floating:
            raise InputError(
                f"{robot.name}: the contact-aided EKF needs a free-floating base (a free joint); "
                "use --estimator truth for this robot"
            )
        pos = np.array(mount.pos_m, dtype=float)
        if pos.shape != (3,) or not np.isfinite(pos).all():
            raise InputError(f"the IMU's pos_m must be 3 finite numbers in m, got {mount.pos_m!r}")
        quat = np.array(mount.quat_wxyz, dtype=float)
        if quat.shape != (4,) or not np.isfinite(quat).all() or abs(np.linalg.norm(quat) - 1.0) > UNIT_QUATERNION_TOL:
            raise InputError(f"the IMU's quat_wxyz must be a unit quaternion w x y z, got {mount.quat_wxyz!r}")
        self.body = robot.base_body if mount.body is None else mount.body
        self.on_base = self.body == robot.base_body
        self.identity = self.on_base and tuple(quat.tolist()) == (1.0, 0.0, 0.0, 0.0)
        R_mount = quat_wxyz_to_rot(quat)
        self._R_bi = R_mount  # constant on the base
        self._pin = pin
        self._v_joints_prev: np.ndarray | None = None
        if self.on_base:
            self.point_in_base_m = pos
            return
        model = pin.Model(robot.pin_model)  # its own copy, with a frame at the IMU
        if not model.existFrame(self.body, pin.BODY):
            raise InputError(f"{robot.name}: the IMU's body {self.body!r} is not in the model")
        body_id = model.getFrameId(self.body, pin.BODY)
        body = model.frames[body_id]
        placement = body.placement * pin.SE3(R_mount, pos)
        self._fid = model.addFrame(pin.Frame(IMU_FRAME, body.parentJoint, body_id, placement, pin.OP_FRAME))
        self.model, self.data = model, model.createData()
        self._nq, self._nv = model.nq, model.nv
        self._q = pin.neutral(model)
        self._q[0:7] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)
        self._v = np.zeros(model.nv)
        self._a = np.zeros(model.nv)
        self.point_in_base_m = self.pose_in_base(robot.q_stand)[1].copy()

    def pose_in_base(self, q) -> tuple[np.ndarray, np.ndarray]:
        """``(R_bi, p_bi)``: the IMU's axes and position in the base frame at the joint angles of ``q``
        (Pinocchio configuration; only ``q[7:]`` is used), m."""
        if self.on_base:
            return self._R_bi, self.point_in_base_m
        pin = self._pin
        self._q[7:] = q[7 : self._nq]
        pin.forwardKinematics(self.model, self.data, self._q)
        M = pin.updateFramePlacement(self.model, self.data, self._fid)
        return M.rotation, M.translation

    def reset(self) -> None:
        """Forget the last joint velocities (a new run)."""
        self._v_joints_prev = None

    def estimator_reading(self, imu: ImuReading, q, v, dt_s: float) -> ImuReading:
        """:meth:`reading` as the EKF takes it: on another body than the base, the joint
        accelerations are the finite difference of the measured joint velocities over ``dt_s``
        (the previous call's to this one's; none on the first call after :meth:`reset` or with
        ``dt_s`` <= 0), and the base's angular acceleration is neglected."""
        if self.on_base:
            return self.reading(imu, q, v)
        v_joints = np.array(v[6 : self._nv], dtype=float)
        prev, self._v_joints_prev = self._v_joints_prev, v_joints
        joint_acc = None if prev is None or not dt_s > 0 else (v_joints - prev) / dt_s
        return self.reading(imu, q, v, joint_acc=joint_acc)

    def reading(self, imu: ImuReading, q, v, joint_acc=None, base_ang_acc_radps2=None) -> ImuReading:
        """The base IMU's reading (base axes, at :attr:`point_in_base_m`) from the IMU's ``imu``.

        Args:
            imu: The IMU's reading (its own axes).
            q: The measured Pinocchio configuration; only the joint angles ``q[7:]`` are used.
            v: The measured Pinocchio velocity; only the joint velocities ``v[6:]`` are used.
            joint_acc: The joint accelerations ``v[6:]``'s derivative, rad/s^2, or ``None`` (the
                estimator's case: the ``J qddot`` term is neglected).
            base_ang_acc_radps2: The base's angular acceleration, base axes, rad/s^2, or ``None``
                (the estimator's case: the ``alpha_b x r`` term is neglected).

        Returns:
            ``imu`` itself for :attr:`identity`; otherwise a new reading.
        """
        if self.identity:
            return imu
        R_Wi = quat_xyzw_to_rot(imu.quat_xyzw)
        gyro = np.asarray(imu.gyro_radps, dtype=float)
        accel = np.asarray(imu.accel_mps2, dtype=float)
        if self.on_base:
            R_bi = self._R_bi
            return ImuReading(
                quat_xyzw=rot_to_quat_xyzw(R_Wi @ R_bi.T), gyro_radps=R_bi @ gyro, accel_mps2=R_bi @ accel
            )
        pin, m, d, fid = self._pin, self.model, self.data, self._fid
        self._q[7:] = q[7 : self._nq]
        self._v[6:] = v[6 : self._nv]
        self._a[6:] = 0.0 if joint_acc is None else joint_acc
        pin.forwardKinematics(m, d, self._q, self._v, self._a)
        M = pin.updateFramePlacement(m, d, fid)
        R_bi, r = M.rotation, M.translation - self.point_in_base_m
        frame = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        rel = pin.getFrameVelocity(m, d, fid, frame)
        a_rel = pin.getFrameClassicalAcceleration(m, d, fid, frame).linear
        w_b = R_bi @ gyro - rel.angular
        transport = _cross(w_b, _cross(w_b, r)) + 2.0 * _cross(w_b, rel.linear)
        if base_ang_acc_radps2 is not None:
            transport += _cross(np.asarray(base_ang_acc_radps2, dtype=float), r)
        f = R_bi @ accel - transport - a_rel
        return ImuReading(quat_xyzw=rot_to_quat_xyzw(R_Wi @ R_bi.T), gyro_radps=w_b, accel_mps2=f)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x b`` of two 3-vectors (``np.cross`` costs about 15 µs a call, this about 1)."""
    (a0, a1, a2), (b0, b1, b2) = a.tolist(), b.tolist()
    return np.array((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0))
