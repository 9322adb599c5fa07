"""The foot sites of a compiled model, and the check that MuJoCo and Pinocchio place every site alike.

:func:`foot_sites` finds each side's contact site, the points where its
contact forces act (a four-point foot's corners, a blade's toe and heel, else
the contact point) and its sole line (toe and heel), with their MuJoCo site
ids and Pinocchio frame ids (docs/ARCHITECTURE.md, "Model conventions").
:func:`check_sites_agree` compares where the two models put every site at a
fixed pseudo-random configuration. Both are the loader's
(:func:`~amlip_qp.robots.loader.load_robot`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from amlip_qp.exceptions import MJCFError
from amlip_qp.profiles import FORCE_SITE_SUFFIXES
from amlip_qp.robots.robot import FOOT_SIDES
from amlip_qp.robots.state import qpos_to_q

# Tolerance (m) of the load-time check that both models place every site alike.
_SITE_AGREEMENT_TOL_M = 1e-6

# MuJoCo's joint types (mjtJoint) that check_sites_agree moves.
_FREE, _SLIDE, _HINGE = 0, 2, 3


def site_ids(mj_model, pin_model, names, path) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """The MuJoCo site ids and the Pinocchio frame ids of the sites ``names``; MJCFError for a site
    Pinocchio has no frame for."""
    import mujoco
    import pinocchio as pin

    mj_ids, pin_ids = [], []
    for n in names:
        mj_ids.append(mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_SITE, n))
        if not pin_model.existFrame(n, pin.OP_FRAME):
            raise MJCFError(f"{path}: Pinocchio has no frame for site {n!r}")
        pin_ids.append(pin_model.getFrameId(n, pin.OP_FRAME))
    return tuple(mj_ids), tuple(pin_ids)


def foot_sites(mj_model, pin_model, path: Path):
    """Contact and force sites per side; MJCFError naming any missing site."""
    import mujoco

    has = lambda n: mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_SITE, n) >= 0  # noqa: E731
    missing = [f"{s}-contact" for s in FOOT_SIDES if not has(f"{s}-contact")]
    if missing:
        raise MJCFError(
            f"{path}: missing required contact site(s) {', '.join(missing)} "
            "(see docs/ARCHITECTURE.md, 'Model conventions')"
        )
    force: dict[str, tuple[str, ...]] = {}
    line: dict[str, tuple[str, ...]] = {}
    for s in FOOT_SIDES:
        toe, heel = has(f"{s}-toe"), has(f"{s}-heel")
        if toe != heel:
            raise MJCFError(
                f"{path}: site {s}-{'heel' if toe else 'toe'} is missing: a blade foot needs both toe and heel sites"
            )
        corners = tuple(f"{s}-{suffix}" for suffix in FORCE_SITE_SUFFIXES[4])
        present = [has(c) for c in corners]
        if any(present) and not (all(present) and toe):
            need = [c for c, p in zip((*corners, f"{s}-toe"), (*present, toe)) if not p]
            raise MJCFError(
                f"{path}: site(s) {', '.join(need)} missing: a four-point foot needs its corners "
                f"{', '.join(corners)} and its sole line's ends {s}-toe, {s}-heel"
            )
        line[s] = (f"{s}-toe", f"{s}-heel") if toe else ()
        force[s] = corners if all(present) else line[s] or (f"{s}-contact",)
    contact = {s: f"{s}-contact" for s in FOOT_SIDES}
    c_mj, c_pin, f_mj, f_pin, l_pin = {}, {}, {}, {}, {}
    for s in FOOT_SIDES:
        (c_mj[s],), (c_pin[s],) = site_ids(mj_model, pin_model, (contact[s],), path)
        f_mj[s], f_pin[s] = site_ids(mj_model, pin_model, force[s], path)
        l_pin[s] = site_ids(mj_model, pin_model, line[s], path)[1]
    return contact, c_mj, c_pin, force, f_mj, f_pin, line, l_pin


def check_sites_agree(mj_model, pin_model, smap, path: Path) -> None:
    """Both models must place every site at the same point (catches parser differences)."""
    import mujoco
    import pinocchio as pin

    rng = np.random.default_rng(12345)
    data = mujoco.MjData(mj_model)
    qpos = mj_model.qpos0.copy()
    for j in range(mj_model.njnt):
        qa, jt = int(mj_model.jnt_qposadr[j]), int(mj_model.jnt_type[j])
        if jt in (_SLIDE, _HINGE):
            qpos[qa] += rng.uniform(-0.3, 0.3)
        elif jt == _FREE:
            qpos[qa : qa + 3] += rng.uniform(-0.3, 0.3, 3)
            quat = rng.normal(size=4)
            qpos[qa + 3 : qa + 7] = quat / np.linalg.norm(quat)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(mj_model, data)
    pin_data = pin_model.createData()
    pin.framesForwardKinematics(pin_model, pin_data, qpos_to_q(smap, qpos))
    for s in range(mj_model.nsite):
        sname = mujoco.mj_id2name(mj_model, mujoco.mjtObj.mjOBJ_SITE, s) or ""
        if not sname or not pin_model.existFrame(sname, pin.OP_FRAME):
            continue
        err = np.linalg.norm(pin_data.oMf[pin_model.getFrameId(sname, pin.OP_FRAME)].translation - data.site_xpos[s])
        if err > _SITE_AGREEMENT_TOL_M:
            raise MJCFError(
                f"{path}: Pinocchio and MuJoCo place site {sname!r} {err:.3g} m apart; the MJCF uses "
                "something Pinocchio's parser reads differently (e.g. a joint-less body fixed to the world)"
            )
