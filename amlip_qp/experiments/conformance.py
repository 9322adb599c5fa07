"""Conformance checks of a robot profile: does the robot load, agree between its two models and walk?

``amlip-qp check-robot NAME|PATH`` runs them (:mod:`amlip_qp.experiments.conformance_cli`
prints them); ``docs/NEW_ROBOT.md`` says what to do when one fails. Each
check is one function returning a :class:`CheckResult` with one measured
number:

- :func:`check_mass`: MuJoCo and Pinocchio give the robot the same mass;
- :func:`check_joint_names`: every joint has a name (the plant is mapped by name);
- :func:`check_site_positions`, :func:`check_body_positions`: they place every
  site and every body alike at a few seeded random configurations;
- :func:`check_joint_roles`: the profile's ``[roles]`` name joints of the model;
- :func:`check_stand_on_floor`: the stand pose puts each foot on the floor;
- :func:`check_output_rank`: the output Jacobian has full rank at the stand pose;
- :func:`~amlip_qp.experiments.conformance_control.check_tick` (QP and PBC):
  one control tick at the stand pose solves, with finite torques inside the limits;
- :func:`~amlip_qp.experiments.conformance_control.check_walk`: a walk in place with
  the QP tracker does not fall.

:func:`~amlip_qp.experiments.conformance_cli.conformance_checks` runs them all.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from amlip_qp.robots import kinematics
from amlip_qp.robots.robot import Robot
from amlip_qp.robots.state import qpos_to_q

#: A check's status.
PASS, FAIL, SKIP = "PASS", "FAIL", "SKIP"

#: Largest difference of the total mass between MuJoCo and Pinocchio, kg.
MASS_TOL_KG = 1e-9
#: Largest distance between a site's (or body's) positions in MuJoCo and Pinocchio, m.
POSITION_TOL_M = 1e-9
#: Largest angle between a body's orientations in MuJoCo and Pinocchio, rad.
ROTATION_TOL_RAD = 1e-9
#: The seeded random configurations the positions are compared at.
RANDOM_CONFIGURATIONS = 3
#: A singular value of the output Jacobian at or below this counts as lost rank (the controller's own check).
RANK_TOL = kinematics.RANK_TOL
#: The range of the gap between each foot's collision geoms and the floor at the stand pose, m:
#: a gap above it drops the robot, below it the feet start inside the floor.
STAND_GAP_M = (-0.002, 0.01)

#: The checks' names, as printed.
MASS_NAME = "model loads in MuJoCo and Pinocchio"
NAMES_NAME = "every joint has a name"
SITES_NAME = "site positions agree"
BODIES_NAME = "body positions agree"
ROLES_NAME = "joint roles name joints of the model"
FLOOR_NAME = "stand pose puts the feet on the floor"
RANK_NAME = "output Jacobian has full rank at stand"


@dataclass(frozen=True)
class CheckResult:
    """One check's outcome.

    Attributes:
        name: What is checked, one line.
        status: :data:`PASS`, :data:`FAIL` or :data:`SKIP`.
        value: The measured number (``None`` when skipped or when the check raised).
        unit: Its unit (``""`` for a count or a ratio).
        detail: The measurement in words, one line.
    """

    name: str
    status: str
    value: float | None
    unit: str
    detail: str

    @property
    def passed(self) -> bool | None:
        """True for a pass, False for a failure, ``None`` for a skip."""
        return None if self.status == SKIP else self.status == PASS

    def line(self, width: int = 50) -> str:
        """The printed line: status, name, detail."""
        return f"{self.status:<5} {self.name:<{width}} {self.detail}"

    def to_json(self) -> dict[str, Any]:
        """The result as JSON values (a non-finite value becomes ``None``)."""
        value = self.value if self.value is not None and math.isfinite(self.value) else None
        return {
            "name": self.name,
            "status": self.status.lower(),
            "passed": self.passed,
            "value": value,
            "unit": self.unit,
            "detail": self.detail,
        }


def result(name: str, ok: bool, value: float | None, unit: str, detail: str) -> CheckResult:
    """A pass or a failure."""
    return CheckResult(name, PASS if ok else FAIL, value, unit, detail)


def one_line(exc: BaseException) -> str:
    """An exception as one line: its type when it has no message."""
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    return "; ".join(lines) if lines else type(exc).__name__


def check_mass(robot: Robot) -> CheckResult:
    """The total mass of MuJoCo's model (sum of the bodies') and of Pinocchio's (``computeTotalMass``)."""
    import pinocchio as pin

    m_mj = float(np.sum(robot.mj_model.body_mass))
    m_pin = float(pin.computeTotalMass(robot.pin_model))
    diff = abs(m_mj - m_pin)
    ok = diff <= MASS_TOL_KG
    detail = (
        f"mass {m_mj:.6g} kg in both (|diff| {diff:.2g} kg)"
        if ok
        else f"MuJoCo {m_mj:.9g} kg, Pinocchio {m_pin:.9g} kg"
    )
    return result(MASS_NAME, ok, diff, "kg", detail)


def check_joint_names(robot: Robot) -> CheckResult:
    """Every joint of the model has a name: the plant is mapped to the controller's model by joint name."""
    import mujoco

    m = robot.mj_model
    unnamed = [j for j in range(m.njnt) if not mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)]
    if not unnamed:
        return result(NAMES_NAME, True, 0.0, "", f"{m.njnt} joints, all named")
    free = [j for j in unnamed if int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE)]
    hint = "the free joint: set free_joint_name in [model]" if free else "name them in the MJCF"
    return result(
        NAMES_NAME, False, float(len(unnamed)), "", f"{len(unnamed)} of {m.njnt} joints have no name ({hint})"
    )


def random_configurations(robot: Robot, count: int = RANDOM_CONFIGURATIONS, seed: int = 0) -> list[np.ndarray]:
    """``count`` seeded random MuJoCo ``qpos``: each hinge and slide inside its range (±1 rad or
    ±0.5 m when unlimited), the free base anywhere within 0.5 m with a random orientation."""
    import mujoco

    m = robot.mj_model
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        qpos = m.qpos0.copy()
        for j in range(m.njnt):
            adr, kind = int(m.jnt_qposadr[j]), int(m.jnt_type[j])
            if kind == mujoco.mjtJoint.mjJNT_FREE:
                qpos[adr : adr + 3] = rng.uniform(-0.5, 0.5, 3) + np.array([0.0, 0.0, 1.0])
                quat = rng.normal(size=4)
                qpos[adr + 3 : adr + 7] = quat / np.linalg.norm(quat)
            elif kind == mujoco.mjtJoint.mjJNT_BALL:
                quat = rng.normal(size=4)
                qpos[adr : adr + 4] = quat / np.linalg.norm(quat)
            else:
                default = 1.0 if kind == mujoco.mjtJoint.mjJNT_HINGE else 0.5
                lo, hi = (float(x) for x in m.jnt_range[j]) if m.jnt_limited[j] else (-default, default)
                qpos[adr] = rng.uniform(lo, hi)
        out.append(qpos)
    return out


def _both_models(robot: Robot, qpos: np.ndarray):
    """MuJoCo's data and Pinocchio's (frames placed) at ``qpos``."""
    import mujoco
    import pinocchio as pin

    data = mujoco.MjData(robot.mj_model)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(robot.mj_model, data)
    pin_data = robot.pin_model.createData()
    pin.framesForwardKinematics(robot.pin_model, pin_data, qpos_to_q(robot.state_map, qpos))
    return data, pin_data


def _frames(robot: Robot, objtype, frame_type) -> list[tuple[int, int, str]]:
    """``(MuJoCo id, Pinocchio frame id, name)`` of every named site or body Pinocchio has a frame for."""
    import mujoco

    m, pm = robot.mj_model, robot.pin_model
    count = m.nsite if objtype == mujoco.mjtObj.mjOBJ_SITE else m.nbody
    out = []
    for i in range(count):
        name = mujoco.mj_id2name(m, objtype, i)
        if name and pm.existFrame(name, frame_type):
            out.append((i, pm.getFrameId(name, frame_type), name))
    return out


def check_site_positions(robot: Robot, seed: int = 0) -> CheckResult:
    """The largest distance between a site's MuJoCo and Pinocchio positions at the random configurations."""
    import mujoco
    import pinocchio as pin

    name = SITES_NAME
    sites = _frames(robot, mujoco.mjtObj.mjOBJ_SITE, pin.OP_FRAME)
    worst, where = 0.0, ""
    for qpos in random_configurations(robot, seed=seed):
        data, pin_data = _both_models(robot, qpos)
        for i, f, site in sites:
            err = float(np.linalg.norm(pin_data.oMf[f].translation - data.site_xpos[i]))
            if err > worst:
                worst, where = err, site
    ok = worst <= POSITION_TOL_M
    detail = f"max |diff| {worst:.2g} m over {len(sites)} sites at {RANDOM_CONFIGURATIONS} random configurations"
    return result(name, ok, worst, "m", detail if ok else f"{detail}, at site {where!r}")


def check_body_positions(robot: Robot, seed: int = 0) -> CheckResult:
    """The largest distance (and angle) between a body's MuJoCo and Pinocchio frames at the random configurations."""
    import mujoco
    import pinocchio as pin

    name = BODIES_NAME
    bodies = _frames(robot, mujoco.mjtObj.mjOBJ_BODY, pin.BODY)
    worst, worst_rad, where = 0.0, 0.0, ""
    for qpos in random_configurations(robot, seed=seed):
        data, pin_data = _both_models(robot, qpos)
        for i, f, body in bodies:
            err = float(np.linalg.norm(pin_data.oMf[f].translation - data.xpos[i]))
            ang = float(np.linalg.norm(pin.log3(pin_data.oMf[f].rotation.T @ data.xmat[i].reshape(3, 3))))
            if err > worst or ang > worst_rad:
                where = body
            worst, worst_rad = max(worst, err), max(worst_rad, ang)
    missing = robot.mj_model.nbody - 1 - len(bodies)  # the world body has no frame of its own
    ok = worst <= POSITION_TOL_M and worst_rad <= ROTATION_TOL_RAD and missing == 0
    detail = (
        f"max |diff| {worst:.2g} m, {worst_rad:.2g} rad over {len(bodies)} bodies "
        f"at {RANDOM_CONFIGURATIONS} random configurations"
    )
    if missing:
        detail += f"; {missing} bodies have no Pinocchio frame"
    elif not ok:
        detail += f", at body {where!r}"
    return result(name, ok, worst, "m", detail)


def check_joint_roles(robot: Robot) -> CheckResult:
    """Each joint the profile's ``[roles]`` and ``[feet] passive_in_stance`` name is a joint of the model."""
    name = ROLES_NAME
    profile = robot.profile
    roles = dict(profile.joint_roles) if profile is not None else {}
    wanted = {(role, side): template.format(side=side) for role, template in roles.items() for side in robot.foot_sides}
    passive = profile.feet.passive_in_stance if profile is not None else ()
    missing = [f"{role} {joint!r}" for (role, _), joint in wanted.items() if joint not in robot.state_map.joint_pin_v]
    unnamed = [
        f"passive_in_stance {role!r} ({side})"
        for role in passive
        for side in robot.foot_sides
        if robot.role_joint(role, side) is None
    ]
    found = len(wanted) - len(missing)
    ok = not missing and not unnamed
    detail = f"{found} of {len(wanted)} joints found ({len(roles)} role{'s' if len(roles) != 1 else ''} x 2 sides)"
    if missing:
        detail += f"; not in the model: {', '.join(missing)}"
    if unnamed:
        detail += f"; no joint for {', '.join(unnamed)}"
    return result(name, ok, float(found), "", detail)


def _foot_geoms(robot: Robot, side: str) -> list[int]:
    """The colliding geoms of the body carrying ``side``'s contact site and of the bodies below it."""
    m = robot.mj_model
    foot = int(m.site_bodyid[robot.contact_site_ids[side]])

    def below(body: int) -> bool:
        while body > 0:
            if body == foot:
                return True
            body = int(m.body_parentid[body])
        return False

    return [g for g in range(m.ngeom) if below(int(m.geom_bodyid[g])) and (m.geom_contype[g] or m.geom_conaffinity[g])]


def check_stand_on_floor(robot: Robot) -> CheckResult:
    """The gap between each foot's collision geoms and the floor (MuJoCo's plane geoms) at the stand pose."""
    import mujoco

    name = FLOOR_NAME
    m = robot.mj_model
    data = mujoco.MjData(m)
    data.qpos[:] = robot.qpos_stand
    mujoco.mj_kinematics(m, data)
    planes = [g for g in range(m.ngeom) if int(m.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_PLANE)]
    if not planes:
        return result(name, False, None, "m", "the model has no floor (a plane geom): set add_floor = true in [model]")
    fromto = np.zeros(6)
    gaps = {}
    for side in robot.foot_sides:
        geoms = _foot_geoms(robot, side)
        if not geoms:
            return result(name, False, None, "m", f"the {side} foot has no colliding geom")
        gaps[side] = min(mujoco.mj_geomDistance(m, data, g, p, 10.0, fromto) for g in geoms for p in planes)
    lo, hi = STAND_GAP_M
    worst = max(gaps.values(), key=lambda gap: max(gap - hi, lo - gap))
    ok = all(lo <= gap <= hi for gap in gaps.values())
    detail = ", ".join(f"{side} {round(gap * 1e3, 1) + 0.0:.1f} mm" for side, gap in gaps.items()) + " above the floor"
    if not ok:
        detail += f" (outside [{lo * 1e3:g}, {hi * 1e3:g}] mm: change base_pos_m's height in [model.stand])"
    return result(name, ok, worst, "m", detail)


def check_output_rank(robot: Robot) -> CheckResult:
    """The rank and the smallest singular value of the output Jacobian ``dh_0/dv`` at the stand pose, both stances."""
    name = RANK_NAME
    rank, n, smallest, side_min = kinematics.stand_output_rank(robot)
    ok = rank == n
    detail = f"rank {rank} of {n}, smallest singular value {smallest:.2g} ({side_min} stance)"
    if not ok:
        detail += f", at or below {RANK_TOL:g}: a singular pose (a straight knee?); bend the legs in [model.stand]"
    return result(name, ok, smallest, "", detail)


#: The kinematic checks, in the order they run.
MODEL_CHECKS: tuple[tuple[str, Callable[[Robot], CheckResult]], ...] = (
    (MASS_NAME, check_mass),
    (NAMES_NAME, check_joint_names),
    (SITES_NAME, check_site_positions),
    (BODIES_NAME, check_body_positions),
    (ROLES_NAME, check_joint_roles),
    (FLOOR_NAME, check_stand_on_floor),
    (RANK_NAME, check_output_rank),
)
