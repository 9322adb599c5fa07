"""The output map ``h_0(q)`` of docs/ARCHITECTURE.md, with its Jacobian and drift.

The outputs are the robot's declared primitives (:func:`output_names`: its
profile's ``outputs`` key, or a default a model without a profile fits; the
names and what each is in :mod:`amlip_qp.profiles.outputs`), in their order:
base angles, joint angles, CoM components over a contact, and the swing
foot's pitch and roll. The generated forms (the compiled output map, the QP
tracker's in-place assembly) are built from the same declaration
(:func:`amlip_qp.codegen.output_map.output_map_function`) and tested against
this one.

Angles in rad, distances in m. ``heading_rad`` is the step's heading ``D``;
``x_D = (cos D, sin D, 0)``, ``y_D = (-sin D, cos D, 0)``.

Each output is built from primitive quantities (rotation-matrix entries,
points, joint angles) whose value, Jacobian row and drift are known, and the
chain rule: ``J_y = grad f . J_x`` and
``Jdot_v_y = grad f . Jdot_v_x + xdot^T Hess f xdot``.

This runs every control tick, so the scalar chain rule works on plain Python
floats packed in tuples (a "chain scalar", below) and each Jacobian row is
written with one or two numpy calls into preallocated scratch space; no
per-scalar objects are created. The floating-point operations are those of
the plain per-row formulas (no reordering, no fused BLAS products), so the
results are the same to the last bit.
"""

from __future__ import annotations

import math

import numpy as np

from amlip_qp.alip import other_side
from amlip_qp.alip.formulas import world_to_heading_xy
from amlip_qp.exceptions import InputError, MJCFError
from amlip_qp.profiles.outputs import OutputPrimitive, output_primitives
from amlip_qp.robots.model_kinematics import ModelKinematics
from amlip_qp.robots.output_chain import atan2_chain, hypot_chain, neg_chain, rotation_column, rotation_entry_z
from amlip_qp.robots.robot import Robot

# The codes of OutputMap's evaluation plan (OutputMap._plan).
_PITCH, _ROLL, _PITCH_PLANAR, _JOINT, _COM, _TOE_PITCH, _FOOT_ROLL = range(7)

#: The outputs of a 3-D model without a profile that has hip-yaw joints and toe/heel force points.
DEFAULT_OUTPUTS_3D: tuple[str, ...] = (
    "torso_pitch", "torso_roll", "stance_hip_yaw", "swing_hip_yaw", "com_z_over_stance",
    "com_x_over_swing", "com_y_over_swing", "com_z_over_swing", "swing_toe_pitch",
)  # fmt: skip
#: The outputs of a planar model (a root moving in the x-z plane) without a profile.
DEFAULT_OUTPUTS_PLANAR: tuple[str, ...] = ("torso_pitch", "com_z_over_stance", "com_x_over_swing", "com_z_over_swing")


def _missing_for(robot: Robot, primitive: OutputPrimitive) -> str | None:
    """What the model lacks for ``primitive`` (one phrase), or ``None``."""
    if primitive.kind == "joint":
        if any(robot.role_joint(primitive.role, s) is None for s in robot.foot_sides):
            return f"a {primitive.role} joint on each leg (the profile's [roles] table names it)"
    elif primitive.kind == "foot_angle" and primitive.axis == "pitch":
        if any(len(robot.sole_line_sites.get(s, ())) != 2 for s in robot.foot_sides):
            return "a sole line on each foot: two or four force points ([feet] force_points_m or sole_rectangle_m)"
    if primitive.lateral and robot.is_planar:
        return "a 3-D root (the model's root is planar)"
    if primitive.kind == "base_angle" and not (robot.is_floating or robot.is_planar):
        return "a free or planar root"
    return None


def output_names(robot: Robot) -> tuple[str, ...]:
    """The outputs ``robot``'s trackers follow, in order (:mod:`amlip_qp.profiles.outputs`).

    A profile declares them (its ``outputs`` key); a model without one gets
    :data:`DEFAULT_OUTPUTS_3D` if it has a free root, hip-yaw joints and two
    force points per foot, or :data:`DEFAULT_OUTPUTS_PLANAR` for a planar root.

    Raises:
        MJCFError: The model lacks what an output reads, or (without a profile) fits neither default.
    """
    profile = robot.profile
    if profile is not None:
        names = tuple(profile.outputs)
        where = f"the {profile.name!r} profile's output"
    elif robot.is_planar:
        names, where = DEFAULT_OUTPUTS_PLANAR, "output"
    else:
        names, where = DEFAULT_OUTPUTS_3D, "output"
    try:
        primitives = output_primitives(names, robot.is_planar)
    except InputError as exc:
        raise MJCFError(f"{robot.path}: {exc}") from None
    hint = "" if profile is not None else " (a model without a profile gets the default outputs: write one)"
    for primitive in primitives:
        missing = _missing_for(robot, primitive)
        if missing is not None:
            raise MJCFError(f"{robot.path}: {where} {primitive.name!r} needs {missing}{hint}")
    n_leg, passive = leg_output_count(robot)
    if len(names) != n_leg - len(passive):
        outputs = "the profile declares" if profile is not None else "the default has"
        raise MJCFError(
            f"{robot.path}: {outputs} {len(names)} outputs; the legs need {n_leg - len(passive)}: one per free leg "
            f"joint ({n_leg} actuated leg joints minus {len(passive)} passive in stance"
            f"{': ' + ', '.join(passive) if passive else ''}){hint}"
        )
    return names


def leg_output_count(robot: Robot) -> tuple[int, tuple[str, ...]]:
    """The actuated joints of both legs (:attr:`Robot.leg_joint_names`) and the stance leg's joints
    passive in stance (:meth:`Robot.passive_in_stance`): the outputs a robot declares are the first
    minus the second (docs/NEW_ROBOT.md)."""
    actuated = set(robot.actuated.joint_names)
    legs = [n for side in robot.foot_sides for n in robot.leg_joint_names.get(side, ()) if n in actuated]
    return len(legs), robot.passive_in_stance(robot.foot_sides[0])


def computes_standard_outputs(output_map) -> bool:
    """Whether ``output_map`` evaluates the robot's standard ``h_0``: its own class (not a base
    class) sets ``standard_outputs = True``, so a subclass that changes ``evaluate`` is not taken
    for the standard map unless it says so."""
    return vars(type(output_map)).get("standard_outputs") is True


class OutputMap:
    """``h_0(q)`` for one robot; evaluate on an updated :class:`~amlip_qp.robots.kinematics.RobotKinematics`.

    One instance keeps scratch buffers for :meth:`evaluate`: do not share it
    between threads.

    Attributes:
        names: Output names, in order (:func:`output_names`).
        primitives: Their :class:`~amlip_qp.profiles.outputs.OutputPrimitive`, in order.
        planar: The model's root is planar (the pitch is about the world y axis).
        joint_rows: Index of each joint output among the outputs, in order.
    """

    #: This map evaluates the robot's standard ``h_0`` (docs/ARCHITECTURE.md), which generated code
    #: may then compute in its place (the QP tracker's in-place assembly). Read with
    #: :func:`computes_standard_outputs`: a subclass counts only if it sets the flag itself.
    standard_outputs = True

    def __init__(self, robot: Robot):
        """Read the robot's outputs (:func:`output_names`).

        Raises:
            MJCFError: The model lacks what an output reads.
        """
        self.robot = robot
        smap = robot.state_map
        self.names = output_names(robot)
        self.primitives = output_primitives(self.names, robot.is_planar)
        self.planar = bool(robot.is_planar)
        self.joint_rows = tuple(i for i, p in enumerate(self.primitives) if p.kind == "joint")
        self._swing_of = {s: other_side(s) for s in robot.foot_sides}
        self._joints: dict[str, tuple[tuple[int, ...], tuple[int, ...]]] = {}
        for stance, swing in self._swing_of.items():
            legs = {"stance": stance, "swing": swing}
            joints = [robot.role_joint(self.primitives[i].role, legs[self.primitives[i].side]) for i in self.joint_rows]
            self._joints[stance] = (
                tuple(smap.joint_pin_q[j] for j in joints),  # type: ignore[index]
                tuple(smap.joint_pin_v[j] for j in joints),  # type: ignore[index]
            )
        nv = robot.nv
        # Per stance: the evaluation plan, one ``(code, row, a, b)`` per output (see _plan).
        self._plans = {stance: self._plan(stance) for stance in self._swing_of}
        # Scratch (overwritten by every evaluate), per contact ("stance", "swing"): J_c - J_contact (3 x nv)
        # and its first two rows times the heading rotation [[cD, sD], [-sD, cD]] (2 x 2 x nv); J_toe - J_heel.
        self._J_rel = {side: np.empty((3, nv)) for side in ("stance", "swing")}
        self._rot_products = {side: np.empty((2, 2, nv)) for side in ("stance", "swing")}
        self._J_blade = np.empty((3, nv))
        self._rot = np.empty((2, 2, 1))
        # Per stance: the Jacobian filled in place (its joint rows preset: a 1 at the joint's v index;
        # every other row overwritten whole by each evaluate, which returns a copy) and its row views.
        self._J = {stance: np.zeros((self.size, nv)) for stance in self._swing_of}
        for stance, plan in self._plans.items():
            for code, i, _, b in plan:
                if code == _JOINT:
                    self._J[stance][i, b] = 1.0
        self._J_rows = {stance: tuple(J) for stance, J in self._J.items()}

    def _plan(self, stance: str) -> tuple[tuple, ...]:
        """The outputs of ``stance``, in order, as ``(code, row, a, b)``: a base angle ``(_PITCH |
        _ROLL | _PITCH_PLANAR, i, None, None)``; a joint ``(_JOINT, i, its q index, its v index)``; a
        CoM component ``(_COM, i, (contact "stance"/"swing", its frame id), axis 0 x, 1 y or 2 z)``;
        the swing foot's angle ``(_TOE_PITCH | _FOOT_ROLL, i, None, None)``."""
        legs = {"stance": stance, "swing": self._swing_of[stance]}
        q_idx, v_idx = self._joints[stance]
        plan: list[tuple] = []
        for i, prim in enumerate(self.primitives):
            if prim.kind == "base_angle":
                code = _ROLL if prim.axis != "pitch" else (_PITCH_PLANAR if self.planar else _PITCH)
                plan.append((code, i, None, None))
            elif prim.kind == "joint":
                k = self.joint_rows.index(i)
                plan.append((_JOINT, i, q_idx[k], v_idx[k]))
            elif prim.kind == "com_over_contact":
                axis = {"x": 0, "y": 1, "z": 2}[prim.axis]
                plan.append((_COM, i, (prim.side, self.robot.contact_frame_ids[legs[prim.side]]), axis))
            else:
                plan.append((_TOE_PITCH if prim.axis == "pitch" else _FOOT_ROLL, i, None, None))
        return tuple(plan)

    @property
    def size(self) -> int:
        """Number of outputs."""
        return len(self.names)

    def joint_indices(self, stance: str) -> tuple[tuple[int, ...], tuple[int, ...]]:
        """Pinocchio ``q`` and ``v`` indices of the joint outputs' joints (:attr:`joint_rows`) for ``stance``."""
        return self._joints[stance]

    def points(self, stance: str) -> tuple[int, ...]:
        """Pinocchio frame ids of the points the outputs read for ``stance``, in the order of
        :class:`~amlip_qp.codegen.output_map.OutputInputs` (``points``): the stance contact, the
        swing contact[, the ends of the swing foot's sole line, toe then heel
        (:attr:`~amlip_qp.robots.robot.Robot.sole_line_frame_ids`)]."""
        swing = self._swing_of[stance]
        robot = self.robot
        ids = [robot.contact_frame_ids[stance], robot.contact_frame_ids[swing]]
        if any(p.kind == "foot_angle" and p.axis == "pitch" for p in self.primitives):
            ids += list(robot.sole_line_frame_ids[swing])
        return tuple(ids)

    def rotating_frames(self, stance: str) -> tuple[int, ...]:
        """Pinocchio frame ids of the rotating frames the outputs read for ``stance`` (the swing
        contact frame for a ``swing_foot_roll`` output), in the order of ``OutputInputs.rotations``."""
        if any(p.kind == "foot_angle" and p.axis == "roll" for p in self.primitives):
            return (self.robot.contact_frame_ids[self._swing_of[stance]],)
        return ()

    def checked_swing(self, stance: str, heading_rad: float) -> str:
        """The swing side of ``stance``; :class:`InputError` for a bad side or a non-finite heading."""
        swing = self._swing_of.get(stance) if isinstance(stance, str) else None
        if swing is None:
            raise InputError(f"stance must be 'left' or 'right', got {stance!r}")
        if not math.isfinite(heading_rad):
            raise InputError(f"heading_rad must be finite, got {heading_rad!r}")
        return swing

    def evaluate(self, kin: ModelKinematics, stance: str, heading_rad: float = 0.0):
        """Outputs, Jacobian and drift at the last ``kin.update``.

        Args:
            kin: An updated :class:`~amlip_qp.robots.kinematics.RobotKinematics`.
            stance: Stance side, ``"left"`` or ``"right"``.
            heading_rad: Step heading ``D`` (rad).

        Returns:
            ``(y, J, Jdot_v)`` with shapes (n,), (n, nv), (n,): outputs (rad or m), their Jacobian on
            Pinocchio's ``v`` and their drift ``Jdot v`` (rad/s^2 or m/s^2). New arrays on every call.

        Raises:
            InputError: Bad side or a non-finite heading.
        """
        swing = self.checked_swing(stance, heading_rad)
        q, v = kin.state()
        jac, acc = kin.frame_jacobian6, kin.frame_jdot_v6  # world-aligned (linear, angular), cached per update
        n = len(self.names)
        y, jdv = np.zeros(n), np.zeros(n)
        J = self._J_rows[stance]  # row views of this stance's Jacobian buffer

        # Base orientation: R, world angular velocity w = Jw v (rad/s), drift alpha (rad/s^2).
        base = self.robot.base_frame_id
        Jw = jac(base)[3:]
        w = np.dot(Jw, v).tolist()
        alpha = acc(base).tolist()[3:]
        R = kin.frame_rotation_view(base).tolist()
        c = kin.com_view.tolist()
        dc = kin.com_jdot_v().tolist()
        Jc = np.ascontiguousarray(kin.com_jacobian())  # Pinocchio's is column-major; rows are used here
        cD, sD = math.cos(heading_rad), math.sin(heading_rad)
        rel: dict[str, list] = {}  # contact -> [CoM minus it, its drift, its Jacobian, heading-frame values]
        for code, i, a, b in self._plans[stance]:
            if code == _JOINT:  # a joint coordinate (its Jacobian row is preset)
                y[i] = q[a]
            elif code == _COM:
                side, fid = a
                entry = rel.get(side)
                if entry is None:
                    r, ar = kin.frame_translation_view(fid).tolist(), acc(fid).tolist()
                    J_rel = np.subtract(Jc, jac(fid)[:3], out=self._J_rel[side])
                    p_rel = (c[0] - r[0], c[1] - r[1], c[2] - r[2])
                    entry = rel[side] = [p_rel, (dc[0] - ar[0], dc[1] - ar[1], dc[2] - ar[2]), J_rel, None]
                if b == 2:
                    y[i], jdv[i] = entry[0][2], entry[1][2]
                    J[i][...] = entry[2][2]
                    continue
                # the step's heading frame: x_D = (cos D, sin D), y_D = (-sin D, cos D)
                heading = entry[3]
                if heading is None:  # once per contact: its x and y rows share the products
                    p_rel, d_rel, J_rel, _ = entry
                    rot, prod = self._rot, self._rot_products[side]
                    rot[0, 0, 0], rot[0, 1, 0], rot[1, 0, 0], rot[1, 1, 0] = cD, sD, -sD, cD
                    np.multiply(rot, J_rel[:2], out=prod)  # prod[i, j] = rot[i, j] * J_rel[j]
                    heading = entry[3] = (
                        world_to_heading_xy(p_rel[0], p_rel[1], cD, sD),
                        world_to_heading_xy(d_rel[0], d_rel[1], cD, sD),
                        prod,
                    )
                y[i], jdv[i] = heading[0][b], heading[1][b]
                np.add(heading[2][b, 0], heading[2][b, 1], out=J[i])
            elif code == _TOE_PITCH:
                chain = self._toe_pitch(kin, swing, v)
                np.dot(chain[2:5], self._J_blade, out=J[i])
                y[i], jdv[i] = chain[0], chain[5]
            elif code == _FOOT_ROLL:  # the swing foot's roll, from its contact frame's rotation (z-y-x Euler angles)
                fid = self.robot.contact_frame_ids[swing]
                Jf = jac(fid)[3:]
                wf = np.dot(Jf, v).tolist()
                af = acc(fid).tolist()[3:]
                Rf = kin.frame_rotation_view(fid).tolist()
                chain = atan2_chain(rotation_entry_z(Rf, 1, wf, af), rotation_entry_z(Rf, 2, wf, af))
                np.dot(chain[2:5], Jf, out=J[i])
                y[i], jdv[i] = chain[0], chain[5]
            else:  # a base angle
                if code == _PITCH:  # z-y-x Euler angles of the base
                    R00, R10, R20 = rotation_column(R, 0, w, alpha)
                    chain = atan2_chain(neg_chain(R20), hypot_chain(R00, R10))
                elif code == _ROLL:
                    chain = atan2_chain(rotation_entry_z(R, 1, w, alpha), rotation_entry_z(R, 2, w, alpha))
                else:  # the pitch of a planar root
                    R02, _, R22 = rotation_column(R, 2, w, alpha)
                    chain = atan2_chain(R02, R22)
                np.dot(chain[2:5], Jw, out=J[i])
                y[i], jdv[i] = chain[0], chain[5]
        return y, self._J[stance].copy(), jdv

    def _toe_pitch(self, kin: ModelKinematics, swing: str, v: np.ndarray) -> tuple:
        """The swing foot's pitch from its blade vector ``d = toe - heel`` (m, the ends of its sole
        line: a two-point foot's points, a four-point foot's toe-pair and heel-pair midpoints) as a
        chain scalar on ``J_toe - J_heel`` (left in :attr:`_J_blade`); ``v`` the state's velocity."""
        toe_id, heel_id = self.robot.sole_line_frame_ids[swing]
        jac, acc = kin.frame_jacobian6, kin.frame_jdot_v6
        t0, t1, t2 = kin.frame_translation_view(toe_id).tolist()
        h0, h1, h2 = kin.frame_translation_view(heel_id).tolist()
        Jd = np.subtract(jac(toe_id)[:3], jac(heel_id)[:3], out=self._J_blade)
        at, ah = acc(toe_id).tolist(), acc(heel_id).tolist()
        rd0, rd1, rd2 = np.dot(Jd, v).tolist()
        # The components of d as chain scalars on the blade Jacobian (coefficients: unit vectors).
        dx = (t0 - h0, rd0, 1.0, 0.0, 0.0, at[0] - ah[0])
        dy = (t1 - h1, rd1, 0.0, 1.0, 0.0, at[1] - ah[1])
        dz = (t2 - h2, rd2, 0.0, 0.0, 1.0, at[2] - ah[2])
        return atan2_chain(neg_chain(dz), hypot_chain(dx, dy))


def check_output_map(robot: Robot, output_map) -> None:
    """Check that ``output_map`` can stand in for ``OutputMap(robot)`` (as
    :attr:`RobotKinematics.output_map <amlip_qp.robots.kinematics.RobotKinematics.output_map>`):
    the same ``names``, a callable ``evaluate(kin, stance, heading_rad)`` and,
    if it has a ``robot``, the same ``nv``.

    Raises:
        InputError: It does not, naming the outputs it must evaluate.
    """
    names = OutputMap(robot).names
    other = getattr(output_map, "robot", robot)
    if (
        tuple(getattr(output_map, "names", ())) != tuple(names)
        or not callable(getattr(output_map, "evaluate", None))
        or other.nv != robot.nv
    ):
        raise InputError(f"output_map must evaluate the outputs {names} of {robot.name} (nv = {robot.nv})")
