"""The :class:`Robot` description shared by the plant (MuJoCo) and the controller (Pinocchio).

A :class:`Robot` is built by :func:`amlip_qp.robots.load_robot` from ONE MJCF
file. It holds both compiled models and everything the rest of the library
needs to know about the robot, all derived from the models themselves
(joint names, actuator gears and limits, tendons, sites), so the same code
serves Cassie, Rabbit and any model that follows the site conventions of
``docs/ARCHITECTURE.md``.

Index conventions: ``*_v_idx`` / ``*_q_idx`` index Pinocchio's ``v`` / ``q``;
``*_dof_idx`` / ``*_qpos_idx`` index MuJoCo's ``qvel`` / ``qpos``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from amlip_qp.robots.state import StateMap

if TYPE_CHECKING:  # pragma: no cover - typing only
    import mujoco
    import pinocchio as pin

    from amlip_qp.profiles import ImuMount, RobotProfile

#: The two foot sides, in the order used everywhere.
FOOT_SIDES: tuple[str, str] = ("left", "right")

#: Joint role -> the joint name a model without a profile uses for it (docs/ARCHITECTURE.md,
#: "Model conventions"); a profile's ``[roles]`` table names any other.
CONVENTION_ROLES: dict[str, str] = {
    "hip_yaw": "{side}-hip-yaw",
    "hip_roll": "{side}-hip-roll",
    "hip_pitch": "{side}-hip-pitch",
    "knee": "{side}-knee",
    "ankle_pitch": "{side}-foot",
    "ankle_roll": "{side}-ankle-roll",
}


@dataclass(frozen=True)
class ActuatorSet:
    """The actuated joints, one entry per MuJoCo actuator (MuJoCo actuator order).

    Attributes:
        names: Actuator names.
        joint_names: Name of the joint each actuator drives.
        pin_v_idx: Pinocchio velocity index of each joint, shape (nu,).
        pin_q_idx: Pinocchio configuration index of each joint, shape (nu,).
        mj_dof_idx: MuJoCo dof (qvel) index of each joint, shape (nu,).
        mj_qpos_idx: MuJoCo qpos index of each joint, shape (nu,).
        gear: Transmission gear: joint torque = gear * actuator force, shape (nu,).
        ctrl_range: MuJoCo control range (actuator side), shape (nu, 2);
            +/-inf where unlimited.
        torque_limit_Nm: Joint-side torque limits = gear * actuator force
            limits (the tighter of ctrlrange and forcerange), further clipped
            by the joint's ``actuatorfrcrange`` if set; low/high, shape
            (nu, 2), N m (N for slide joints).
    """

    names: tuple[str, ...]
    joint_names: tuple[str, ...]
    pin_v_idx: np.ndarray
    pin_q_idx: np.ndarray
    mj_dof_idx: np.ndarray
    mj_qpos_idx: np.ndarray
    gear: np.ndarray
    ctrl_range: np.ndarray
    torque_limit_Nm: np.ndarray

    def __len__(self) -> int:
        return len(self.names)


@dataclass(frozen=True)
class Coupling:
    """A fixed (joint) tendon: a linear coupling of joints with an optional spring.

    The tendon length is ``L = sum_i coefficients[i] * qpos[joint_i]`` (MuJoCo
    joint coordinates, which equal Pinocchio's for hinge and slide joints).
    MuJoCo's spring force on the tendon is ``-stiffness * (L - clip(L,
    springlength[0], springlength[1]))`` and its damping force
    ``-damping * dL/dt``; the joint torques are ``coefficients * force``.

    Attributes:
        name: Tendon name.
        joint_names: The coupled joints.
        coefficients: Coupling coefficients (rad per rad or m per m).
        pin_q_idx: Pinocchio configuration index of each joint.
        pin_v_idx: Pinocchio velocity index of each joint.
        springlength: Spring rest length interval ``(low, high)`` (rad for
            hinge joints); ``low == high`` for an ordinary spring.
        stiffness: Spring stiffness (N m/rad for hinge joints).
        damping: Damping (N m s/rad for hinge joints).
    """

    name: str
    joint_names: tuple[str, ...]
    coefficients: np.ndarray
    pin_q_idx: np.ndarray
    pin_v_idx: np.ndarray
    springlength: tuple[float, float]
    stiffness: float
    damping: float


@dataclass(frozen=True)
class Robot:
    """A robot loaded into MuJoCo and Pinocchio from the same MJCF file.

    Attributes:
        name: ``"cassie"``, ``"rabbit"`` or the file's stem.
        path: The MJCF file.
        mj_model: The compiled MuJoCo model (the plant).
        pin_model: The Pinocchio model (the controller's model).
        pin_data: A Pinocchio data for quick one-off use; long-lived users
            (trackers, :class:`RobotKinematics`) create their own with
            :meth:`new_pin_data`.
        state_map: The MuJoCo <-> Pinocchio index maps (see
            :mod:`amlip_qp.robots.state`).
        foot_sides: ``("left", "right")``.
        contact_sites: Side -> name of the ALIP contact site (``{side}-contact``).
        contact_site_ids: Side -> MuJoCo site id of the contact site.
        contact_frame_ids: Side -> Pinocchio frame id of the contact site.
        force_sites: Side -> names of the sites where contact forces act
            (toe and heel for Cassie; the contact site for Rabbit; the sole's four
            corners ``{side}-toe-left``, ``-toe-right``, ``-heel-left``, ``-heel-right``
            for a four-point foot).
        force_site_ids: Side -> MuJoCo site ids of the force sites.
        force_frame_ids: Side -> Pinocchio frame ids of the force sites.
        sole_line_sites: Side -> the ends of the foot's sole line, ``({side}-toe, {side}-heel)``:
            a two-point foot's force sites, a four-point foot's midpoints of its toe pair and of
            its heel pair; ``()`` for a point foot. The swing foot's pitch output, the PBC
            tracker's stance rows and the EKF's flat-foot test read this line.
        sole_line_frame_ids: Side -> Pinocchio frame ids of :attr:`sole_line_sites`.
        base_body: Name of the root body (the one carrying the root joints).
        base_frame_id: Pinocchio frame id of the root body.
        root_joint_names: MuJoCo names of the root joints (one free joint,
            or the planar slide-x / slide-z / hinge-pitch triple).
        is_floating: True when the root is a free joint (Pinocchio free-flyer).
        is_planar: True when the root is planar in the world x-z plane (two
            slides and a hinge; every hinge about the world y axis).
        joint_names: Names of all hinge and slide joints that are not root
            joints (MuJoCo order).
        actuated: The actuated joints.
        passive_joint_names: Non-root hinge/slide joints with no actuator.
        passive_v_idx: Pinocchio velocity indices of the passive joints.
        passive_q_idx: Pinocchio configuration indices of the passive joints.
        mass_kg: Total mass (kg).
        q_stand: The ``stand`` keyframe (or MuJoCo's qpos0 if the model has no
            such keyframe) in Pinocchio's configuration convention.
        qpos_stand: The same configuration in MuJoCo's convention.
        couplings: Fixed tendons (joint couplings).
        dof_stiffness: Joint spring stiffness per Pinocchio velocity index,
            shape (nv,) (0 on the root).
        dof_springref: Spring reference position per Pinocchio velocity index
            (rad or m), shape (nv,).
        dof_damping: Joint damping per Pinocchio velocity index, shape (nv,).
        dof_armature: Rotor armature per Pinocchio velocity index, shape (nv,).
        profile: The robot's :class:`~amlip_qp.profiles.RobotProfile` (loaded by
            name, from a profile file, or from a bundled robot's unedited model
            file), ``None`` for a bare MJCF file: every fact about the robot
            that is not in its model comes from it.
        leg_joint_names: Side -> the hinge and slide joints on the tree path
            from the root to that side's contact site (MuJoCo order).
        springs: The robot's springs (:func:`amlip_qp.robots.passive.spring_rows`, filled by the loader).
    """

    name: str
    path: Path
    mj_model: mujoco.MjModel
    pin_model: pin.Model
    pin_data: pin.Data
    state_map: StateMap
    contact_sites: dict[str, str]
    contact_site_ids: dict[str, int]
    contact_frame_ids: dict[str, int]
    force_sites: dict[str, tuple[str, ...]]
    force_site_ids: dict[str, tuple[int, ...]]
    force_frame_ids: dict[str, tuple[int, ...]]
    base_body: str
    base_frame_id: int
    root_joint_names: tuple[str, ...]
    is_floating: bool
    is_planar: bool
    joint_names: tuple[str, ...]
    actuated: ActuatorSet
    passive_joint_names: tuple[str, ...]
    passive_v_idx: np.ndarray
    passive_q_idx: np.ndarray
    mass_kg: float
    q_stand: np.ndarray
    qpos_stand: np.ndarray
    couplings: tuple[Coupling, ...]
    dof_stiffness: np.ndarray
    dof_springref: np.ndarray
    dof_damping: np.ndarray
    dof_armature: np.ndarray
    foot_sides: tuple[str, str] = field(default=FOOT_SIDES)
    profile: RobotProfile | None = None
    leg_joint_names: dict[str, tuple[str, ...]] = field(default_factory=dict)
    sole_line_sites: dict[str, tuple[str, ...]] = field(default_factory=dict)
    sole_line_frame_ids: dict[str, tuple[int, ...]] = field(default_factory=dict)
    springs: tuple = ()

    def role_joint(self, role: str, side: str) -> str | None:
        """The name of ``side``'s joint with ``role`` (:data:`amlip_qp.profiles.JOINT_ROLES`), or ``None``.

        The profile's ``[roles]`` name it; a robot without a profile, or a role its profile does not
        name, follows the model conventions (``{side}-hip-yaw``, ``{side}-knee``, ``{side}-foot`` ...,
        :data:`CONVENTION_ROLES`). ``None`` when the model has no such joint.
        """
        name = self.profile.joint_name(role, side) if self.profile is not None else None
        if name is None:
            template = CONVENTION_ROLES.get(role)
            name = None if template is None else template.format(side=side)
        return name if name is not None and name in self.state_map.joint_pin_v else None

    def passive_in_stance(self, side: str) -> tuple[str, ...]:
        """The joints of ``side``'s leg that carry no torque while it is in stance: the profile's
        ``feet.passive_in_stance`` roles (without a profile, ``ankle_pitch``), those the model has."""
        roles = self.profile.feet.passive_in_stance if self.profile is not None else ("ankle_pitch",)
        names = (self.role_joint(role, side) for role in roles)
        return tuple(n for n in names if n is not None)

    @property
    def imu_mount(self) -> ImuMount:
        """Where the IMU sits, its body named: the profile's ``[imu]`` (the base body when it names
        none); without a profile, the base body's origin with its axes."""
        from dataclasses import replace

        from amlip_qp.profiles import ImuMount

        mount = self.profile.imu if self.profile is not None else ImuMount()
        return mount if mount.body is not None else replace(mount, body=self.base_body)

    @property
    def nq(self) -> int:
        """Size of Pinocchio's configuration ``q``."""
        return int(self.pin_model.nq)

    @property
    def nv(self) -> int:
        """Size of Pinocchio's velocity ``v`` (= MuJoCo's nv)."""
        return int(self.pin_model.nv)

    @property
    def nu(self) -> int:
        """Number of actuators."""
        return len(self.actuated)

    def new_mj_data(self, keyframe: str | None = None) -> mujoco.MjData:
        """A fresh ``mujoco.MjData``; set to the named keyframe if given (then forwarded)."""
        import mujoco

        data = mujoco.MjData(self.mj_model)
        if keyframe is not None:
            key_id = mujoco.mj_name2id(self.mj_model, mujoco.mjtObj.mjOBJ_KEY, keyframe)
            if key_id < 0:
                from amlip_qp.exceptions import InputError

                raise InputError(
                    f"{self.name}: no keyframe named {keyframe!r}; the model has {self.mj_model.nkey} keyframe(s)"
                )
            mujoco.mj_resetDataKeyframe(self.mj_model, data, key_id)
            mujoco.mj_forward(self.mj_model, data)
        return data

    def new_pin_data(self) -> pin.Data:
        """A fresh ``pinocchio.Data`` for this robot's Pinocchio model."""
        return self.pin_model.createData()
