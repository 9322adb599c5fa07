"""The equations of the iterative IK (:class:`~amlip_qp.control.pbc.ik.IterativeIK`).

Formulation (square system, ``nv`` equations in the ``nv`` velocity coordinates)
------------------------------------------------------------------------------
Unknown: the full configuration ``q`` (base and all joints). Equations:

1. **Outputs**: ``h_0(q) = h_d`` (the ``n_h`` outputs of
   :mod:`amlip_qp.robots.outputs`; Cassie 9, Rabbit 4).
2. **Stance contact pose held at its estimate**: the pose of the stance
   ``{st}-contact`` frame equals the estimated one: position (m) and
   orientation (rad, world-axes rotation vector ``log3(R R_est^T)``). For a
   planar robot only its in-plane rows (x, z, pitch) exist. For Rabbit the
   contact frame rides on the shin, so this fixes the stance shin's absolute
   angle (the unactuated coordinate) at its estimate; for Cassie it fixes the
   foot on the ground, including its roll about the blade.
3. **Unactuated stance ankle held at its estimate**: the joints of the
   stance leg that are passive in stance (the profile's
   ``feet.passive_in_stance``: Cassie's stance toe, passive in the paper;
   H1's ankle; G1's ankle pitch and roll), when the system would otherwise
   be under-determined by their number, each equal their estimate. A model
   without a profile holds the stance contact frame's parent joint when one
   equation is missing.
4. **Posture joints held at the stand pose**: each actuated joint outside
   both legs (a humanoid's waist, arms and head; :attr:`Robot.leg_joint_names
   <amlip_qp.robots.robot.Robot.leg_joint_names>`) equals its value in the
   robot's ``stand`` keyframe, with zero rate. Cassie and Rabbit have none.
5. **Springs held at their estimates**: each passive joint that is not in a
   coupling (Cassie's shins) equals its estimate, and each coupling length
   (Cassie's ``q_knee + q_tarsus``) equals its estimated length, so the
   tarsus moves with the knee as through a rigid achilles rod.

Consequently the free coordinates are: the actuated joints other than the
stance ankle (Cassie: stance hip roll/yaw/pitch and knee, swing hip
roll/yaw/pitch, knee and toe: 9 = ``n_h``; Rabbit: both hips and knees, 4 =
``n_h``) -- the base pose and the tarsi are then dependent (the base follows
from the stance leg standing on the fixed foot; each tarsus from its knee).
Fixed (at the estimate): the stance contact pose, the stance ankle (Cassie),
the shins and the coupling lengths. Cassie: 9 + 6 + 1 + 2 + 2 = 20 = nv;
Rabbit: 4 + 3 = 7 = nv.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.exceptions import MJCFError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.robots.kinematics import RobotKinematics
    from amlip_qp.robots.robot import Robot


class StanceRows:
    """Per-stance constant parts of the system (built once) and its per-tick buffers."""

    def __init__(
        self,
        nv: int,
        n_out: int,
        n_pose: int,
        lin_q: np.ndarray,
        lin_v: np.ndarray,
        lin_rate: np.ndarray,
        posture: slice = slice(0, 0),
        posture_target: np.ndarray | None = None,
    ):
        self.n_var = n_out + n_pose  # rows that change with q
        self.posture = posture  # the posture rows among the linear rows
        self.posture_target = np.zeros(0) if posture_target is None else posture_target  # their held values
        self.lin_q = lin_q  # (n_lin, nq): linear residual rows  L_q q - b
        self.lin_rate = lin_rate  # (n_lin, nv): held rates = lin_rate @ v_est
        self.A = np.zeros((nv, nv))
        self.A[self.n_var :] = lin_v
        self.A_eps = self.A.copy()
        self.drift = np.zeros(self.n_var)
        self.F = np.zeros(nv)


class IKEquations:
    """Which coordinates the IK holds, and the constant rows of its system per stance (module doc).

    Args:
        robot: The robot.
        n_out: Number of outputs ``n_h``.

    Attributes:
        robot: The robot.
        n_out: Number of outputs ``n_h``.
        pose_rows: Rows of the stance contact pose's 6-D twist that are equations
            (planar robots: x, z, pitch).
        held_springs: The springs the IK holds: the passive joints outside
            couplings, then the couplings (the order of ``held_springs`` of
            :meth:`IterativeIK.solve <amlip_qp.control.pbc.ik.IterativeIK.solve>`).
        held_v, held_q: Side -> Pinocchio ``v`` / ``q`` indices of the held stance
            ankle joints (empty when none is held).
        rows: Side -> the :class:`StanceRows` of that stance.

    Raises:
        MJCFError: The model does not give a square system (outputs + held
            coordinates != nv), or a stance ankle joint to hold is not actuated.
    """

    def __init__(self, robot: Robot, n_out: int):
        self.robot = robot
        m = robot.pin_model
        nv, nq = m.nv, m.nq
        # in-plane rows of the contact pose (planar robots: x, z, pitch)
        self.pose_rows = np.array([0, 2, 4]) if robot.is_planar else np.arange(6)
        self._pose = slice(0, 5, 2) if robot.is_planar else slice(0, 6)  # the same rows, read as a view
        self.n_out = n_out
        # Held springs: the passive joints outside couplings, then the coupling lengths.
        springs = robot.springs
        self.held_springs = tuple(r for r in springs if r.kind == "joint") + tuple(
            r for r in springs if r.kind == "coupling"
        )
        # Posture joints: actuated, in neither leg; held at the stand pose.
        legs = {name for side in robot.foot_sides for name in robot.leg_joint_names.get(side, ())}
        act = robot.actuated
        posture = [k for k, name in enumerate(act.joint_names) if name not in legs]
        self.posture_v = np.array([act.pin_v_idx[k] for k in posture], dtype=int)
        self.posture_q = np.array([act.pin_q_idx[k] for k in posture], dtype=int)
        n_fixed = len(self.pose_rows) + len(self.posture_v) + len(self.held_springs)
        n_held = nv - (n_out + n_fixed)
        # the stance ankle joints: the ones passive in stance, if actuated and needed
        self.held_v: dict[str, tuple[int, ...]] = {}
        self.held_q: dict[str, tuple[int, ...]] = {}
        act_v = [int(i) for i in robot.actuated.pin_v_idx]
        for side in robot.foot_sides:
            names = _stance_ankle(robot, side, n_held)
            if len(names) != n_held:
                raise MJCFError(
                    f"{robot.name}: IK needs {nv} equations, has {n_out} outputs + {n_fixed} held coordinates"
                    f" + {len(names)} stance joints passive in stance"
                )
            ids = [m.getJointId(name) for name in names]
            self.held_v[side] = tuple(m.joints[j].idx_v for j in ids)
            self.held_q[side] = tuple(m.joints[j].idx_q for j in ids)
            for name, iv in zip(names, self.held_v[side]):
                if iv not in act_v:
                    raise MJCFError(f"{robot.name}: the {side} stance joint {name!r} to hold is not actuated")
        # linear rows per stance: ankle (held, with its estimated rate), springs and couplings (rate 0)
        self.rows: dict[str, StanceRows] = {}
        for side in robot.foot_sides:
            lq: list[np.ndarray] = []
            lv: list[np.ndarray] = []
            lr: list[np.ndarray] = []
            for iq, iv in zip(self.held_q[side], self.held_v[side]):
                r_q, r_v = np.zeros(nq), np.zeros(nv)
                r_q[iq] = 1.0
                r_v[iv] = 1.0
                lq.append(r_q)
                lv.append(r_v)
                lr.append(r_v.copy())
            start = len(lq)
            for iq, iv in zip(self.posture_q, self.posture_v):
                r_q, r_v = np.zeros(nq), np.zeros(nv)
                r_q[iq] = 1.0
                r_v[iv] = 1.0
                lq.append(r_q)
                lv.append(r_v)
                lr.append(np.zeros(nv))  # held still
            for spring in self.held_springs:
                lq.append(spring.row_q(nq))
                lv.append(spring.row_v(nv))
                lr.append(np.zeros(nv))
            self.rows[side] = StanceRows(
                nv,
                n_out,
                len(self.pose_rows),
                np.array(lq).reshape(-1, nq),
                np.array(lv).reshape(-1, nv),
                np.array(lr).reshape(-1, nv),
                slice(start, start + len(self.posture_q)),
                np.asarray(robot.q_stand, dtype=float)[self.posture_q],
            )

    def held_quantities(self, kin: RobotKinematics, stance: str) -> dict:
        """What the IK holds for ``stance``, from the controller's updated kinematics ``kin``: the
        contact frame's position (m, ``contact_pos``) and rotation (``contact_rot``), the linear
        rows' values (``lin``: the held ankle, posture and springs) and the held coordinates' rates
        (``rates``: the contact pose's twist rows, then the linear rows').
        """
        rows = self.rows[stance]
        q, v = kin.state()
        cid = self.robot.contact_frame_ids[stance]
        twist = np.dot(kin.frame_jacobian6(cid), v)
        rates = np.empty(self.robot.nv - self.n_out)
        npose = len(self.pose_rows)
        rates[:npose] = twist[self._pose]
        rates[npose:] = np.dot(rows.lin_rate, v)
        lin = np.dot(rows.lin_q, q)
        lin[rows.posture] = rows.posture_target  # posture joints: at the stand pose (their rates are 0)
        return {
            "contact_pos": kin.frame_position(cid),
            "contact_rot": kin.frame_rotation(cid),
            "lin": lin,
            "rates": rates,
        }

    def controlled_actuated(self, stance: str) -> np.ndarray:
        """Indices into the actuator list of the joints the IK solves for (all but the held stance ankle)."""
        held = self.held_v[stance]
        return np.array([k for k, iv in enumerate(self.robot.actuated.pin_v_idx) if iv not in held], dtype=int)

    def spring_rest_values(self) -> np.ndarray:
        """Rest values (rad) of :attr:`held_springs`, in their order: the passive joints
        outside couplings (their spring reference), then each coupling's rest length."""
        return np.array([spring.rest for spring in self.held_springs], dtype=float)


def _stance_ankle(robot: Robot, side: str, n_held: int) -> tuple[str, ...]:
    """The joints of ``side``'s leg the IK holds in stance: none if ``n_held`` is 0; else its joints
    passive in stance (:meth:`Robot.passive_in_stance <amlip_qp.robots.robot.Robot.passive_in_stance>`)
    or, for a model without a profile and one missing equation, the contact frame's parent joint."""
    if n_held <= 0:
        return ()
    if robot.profile is None and n_held == 1:
        m = robot.pin_model
        return (m.names[m.frames[robot.contact_frame_ids[side]].parentJoint],)
    return robot.passive_in_stance(side)
