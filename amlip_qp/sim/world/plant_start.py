"""The start pose of a plant whose MJCF has no ``stand`` keyframe: the controller's stand, with its loops closed.

:func:`amlip_qp.sim.world.plant_loader.load_plant` adds the pose of :func:`stand_qpos` to
such a plant as its ``stand`` keyframe, before the other edits (so a terrain
lifts it as it lifts any keyframe, and the harness starts from it). The pose:

1. every joint of the controller's model, the base's free joint included,
   takes its value in the controller's stand (``Robot.qpos_stand``), mapped by
   name (:attr:`Plant.qpos_adr <amlip_qp.sim.world.plant.Plant.qpos_adr>`);
2. the plant's other joints start at their spring's rest (``springref``)
   when they have a spring, else at ``qpos0`` (the MJCF's own pose), moved to
   the middle of their range when that lies outside it; another body's free
   joint keeps the pose the MJCF gives the body;
3. the equality constraints (the loop closures of a closed-chain plant) are
   closed by moving only those other joints, with the base and the
   controller's joints held: Gauss-Newton steps of least norm on MuJoCo's
   equality residuals (the ``efc_pos`` of the equality rows, with their
   Jacobian ``efc_J``), until the largest is below :data:`SETTLED_TOL`;
4. the base is moved vertically so the controller's contact points (its
   ``{side}-contact`` sites, on the plant's foot bodies of the same names)
   are as high, on average, as in the controller's own stand; the loops are
   then closed again (a closure to the world would have moved).

A joint of the plant that is not in the controller's model, has no spring and
is moved by no equality constraint has no value to infer: the plant is
refused in one line (add a ``stand`` keyframe to its MJCF).
"""

from __future__ import annotations

import mujoco
import numpy as np

from amlip_qp.exceptions import InputError
from amlip_qp.sim.world.plant import Plant

#: The keyframe the harness starts from.
STAND_KEYFRAME = "stand"
#: Largest equality residual of a settled pose: m for positional rows (a ``connect``), rad for angular ones.
SETTLED_TOL = 1e-10
#: Gauss-Newton iterations before the loops count as not closable (the closed-chain Cassie takes 10).
MAX_ITERATIONS = 50
#: Largest joint motion of one Gauss-Newton step, rad or m (keeps the first steps on the nearby branch).
MAX_STEP = 0.5
#: A Jacobian entry above this (m/rad) means the equality moves the dof.
_MOVES = 1e-9

_FREE, _BALL = int(mujoco.mjtJoint.mjJNT_FREE), int(mujoco.mjtJoint.mjJNT_BALL)
_QPOS_SIZE = {_FREE: 7, _BALL: 4}
_DOF_SIZE = {_FREE: 6, _BALL: 3}


def _joint_name(model: mujoco.MjModel, j: int) -> str:
    return mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"


def _initial_guess(model: mujoco.MjModel, j: int) -> np.ndarray:
    """A joint's start before the loops are closed: its spring's rest, or qpos0 (inside its range)."""
    qa, jtype = int(model.jnt_qposadr[j]), int(model.jnt_type[j])
    n = _QPOS_SIZE.get(jtype, 1)
    value = (model.qpos_spring if model.jnt_stiffness[j] > 0 else model.qpos0)[qa : qa + n].copy()
    if n == 1 and model.jnt_limited[j]:
        lo, hi = model.jnt_range[j]
        if not lo <= value[0] <= hi:
            value[0] = 0.5 * (lo + hi)
    return value


def equality_residual(model: mujoco.MjModel, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
    """The equality rows' residuals (``efc_pos``) and their Jacobian (rows x nv, dense) at ``data.qpos``."""
    mujoco.mj_fwdPosition(model, data)
    rows = np.flatnonzero(data.efc_type == mujoco.mjtConstraint.mjCNSTR_EQUALITY)
    nefc, nv = int(data.nefc), int(model.nv)
    if mujoco.mj_isSparse(model):
        jac = np.zeros((nefc, nv))
        mujoco.mju_sparse2dense(jac, data.efc_J, data.efc_J_rownnz, data.efc_J_rowadr, data.efc_J_colind)
    else:
        jac = np.asarray(data.efc_J[: nefc * nv]).reshape(nefc, nv)
    return data.efc_pos[rows].copy(), jac[rows].copy()


def _close_loops(model: mujoco.MjModel, data: mujoco.MjData, free_dofs: np.ndarray, name: str) -> None:
    """Gauss-Newton on the equality residuals over ``free_dofs`` only, until below :data:`SETTLED_TOL`."""
    for _ in range(MAX_ITERATIONS):
        residual, jac = equality_residual(model, data)
        if residual.size == 0 or np.max(np.abs(residual)) <= SETTLED_TOL:
            return
        if free_dofs.size == 0:  # only held joints move the open closures
            break
        step = np.linalg.lstsq(jac[:, free_dofs], -residual, rcond=None)[0]
        step *= min(1.0, MAX_STEP / max(float(np.max(np.abs(step))), 1e-300))
        dq = np.zeros(model.nv)
        dq[free_dofs] = step
        mujoco.mj_integratePos(model, data.qpos, dq, 1.0)
    residual, _ = equality_residual(model, data)
    raise InputError(
        f"plant {name} has no '{STAND_KEYFRAME}' keyframe, and its loop closures stay open by "
        f"{np.max(np.abs(residual)):.3g} (m or rad) in the controller's stand pose with its other joints moved: "
        f"add a '{STAND_KEYFRAME}' keyframe to its MJCF"
    )


def _contact_heights_m(plant: Plant, data: mujoco.MjData) -> np.ndarray:
    """World z of the controller's contact sites on the plant's foot bodies at ``data``'s kinematics, m."""
    robot = plant.robot
    out = []
    for side in robot.foot_sides:
        local = robot.mj_model.site_pos[robot.contact_site_ids[side]]
        b = plant.foot_body_ids[side]
        out.append(float(data.xpos[b, 2] + data.xmat[b].reshape(3, 3)[2] @ local))
    return np.array(out)


def stand_qpos(plant: Plant) -> np.ndarray:
    """The plant's start pose (qpos) from the controller's stand, its loops closed (see the module).

    Raises:
        InputError: The base is not floated by a free joint (its pose cannot
            be copied), a plant joint's value cannot be inferred (named), or
            the loops cannot be closed by the plant's other joints.
    """
    model, robot, name = plant.model, plant.robot, plant.name
    if robot.is_floating and not plant.free_base:
        raise InputError(
            f"plant {name} has no '{STAND_KEYFRAME}' keyframe and no free joint on its base body "
            f"{robot.base_body!r} to start it from the controller's stand: add a '{STAND_KEYFRAME}' keyframe"
        )
    adr = plant.qpos_adr
    held_q = set(adr[adr >= 0].tolist())
    data = mujoco.MjData(model)
    data.qpos[:] = model.qpos0
    others: list[int] = []  # plant joints not in the controller's model (another body's free joint aside)
    for j in range(model.njnt):
        qa = int(model.jnt_qposadr[j])
        if qa in held_q or int(model.jnt_type[j]) == _FREE:
            continue
        guess = _initial_guess(model, j)
        data.qpos[qa : qa + guess.size] = guess
        others.append(j)
    mapped = adr >= 0
    data.qpos[adr[mapped]] = robot.qpos_stand[mapped]
    _, jac = equality_residual(model, data)
    dofs = {
        j: np.arange(model.jnt_dofadr[j], model.jnt_dofadr[j] + _DOF_SIZE.get(int(model.jnt_type[j]), 1))
        for j in others
    }
    in_loop = [j for j in others if jac.size and np.max(np.abs(jac[:, dofs[j]])) > _MOVES]
    unknown = [j for j in others if j not in in_loop and model.jnt_stiffness[j] <= 0]
    if unknown:
        names = ", ".join(repr(_joint_name(model, j)) for j in unknown)
        raise InputError(
            f"plant {name} has no '{STAND_KEYFRAME}' keyframe, and its joints {names} are not in the "
            f"{robot.name} controller's model, carry no spring and close no loop, so their start cannot be "
            f"inferred: add a '{STAND_KEYFRAME}' keyframe to its MJCF"
        )
    free_dofs = np.concatenate([dofs[j] for j in in_loop]) if in_loop else np.zeros(0, dtype=int)
    _close_loops(model, data, free_dofs, name)
    if plant.free_base:
        ctrl_data = mujoco.MjData(robot.mj_model)
        ctrl_data.qpos[:] = robot.qpos_stand
        mujoco.mj_kinematics(robot.mj_model, ctrl_data)
        want = np.array([ctrl_data.site_xpos[robot.contact_site_ids[s], 2] for s in robot.foot_sides])
        mujoco.mj_kinematics(model, data)
        base_z = int(model.jnt_qposadr[_free_joint_of(model, plant.base_body_id)]) + 2
        data.qpos[base_z] += float(np.mean(want - _contact_heights_m(plant, data)))
        _close_loops(model, data, free_dofs, name)
    return data.qpos.copy()


def _free_joint_of(model: mujoco.MjModel, body: int) -> int:
    return next(j for j in range(model.njnt) if model.jnt_bodyid[j] == body and model.jnt_type[j] == _FREE)
