"""Load an MJCF file into MuJoCo and Pinocchio and describe the robot.

:func:`load_robot` accepts a bundled robot name (``"cassie"``, ``"rabbit"``)
or a path to an MJCF ``.xml`` file. Everything in the returned
:class:`~amlip_qp.robots.robot.Robot` is derived from the compiled models:
joint names, actuator gears and limits, fixed tendons, springs, sites.
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

import numpy as np

from amlip_qp.exceptions import MJCFError, ModelFileError, ProfileError, UnknownRobotError
from amlip_qp.profiles import (
    PROFILES,
    RobotProfile,
    bundled_names,
    get_profile,
    looks_like_profile_path,
)
from amlip_qp.robots.model_edits import prepared_model_path
from amlip_qp.robots.model_sites import check_sites_agree, foot_sites
from amlip_qp.robots.passive import spring_rows
from amlip_qp.robots.robot import ActuatorSet, Coupling, Robot
from amlip_qp.robots.state import build_state_map, q_to_qpos, qpos_to_q

#: Name of the keyframe used as the nominal standing configuration.
STAND_KEYFRAME = "stand"

_FREE, _BALL, _SLIDE, _HINGE = 0, 1, 2, 3


def _one_line(exc: BaseException) -> str:
    """The parser's message on a single line."""
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    return "; ".join(lines) if lines else type(exc).__name__


def resolve_robot(name_or_path: str | os.PathLike) -> tuple[str, Path, RobotProfile | None]:
    """Turn a robot name, a profile path or an MJCF path into ``(name, MJCF path, profile)``.

    A bundled name or a ``.toml`` path gives its profile and the model file it prepares
    (:func:`~amlip_qp.robots.model_edits.prepared_model_path`); an MJCF path gives the file,
    with the profile of the bundled robot whose unedited model it is, else ``None``.

    Raises:
        UnknownRobotError: Not a known name and does not look like a file path.
        ProfileError: The profile file is missing or invalid.
        ModelFileError: The MJCF file does not exist.
    """
    text = os.fspath(name_or_path)
    is_xml = text.lower().endswith(".xml") or (Path(text).suffix.lower() == ".xml")
    if isinstance(name_or_path, str) and text.strip().lower() in bundled_names():
        profile = get_profile(text.strip().lower())
    elif not is_xml and looks_like_profile_path(name_or_path):
        profile = get_profile(name_or_path)
    else:
        if not (is_xml or os.sep in text or Path(text).exists()):
            known = ", ".join(repr(k) for k in bundled_names())
            raise UnknownRobotError(
                f"unknown robot {text!r}: known robots are {known}; a path to a robot profile (.toml) "
                "or an MJCF .xml file also works"
            )
        path = Path(text).expanduser()
        if not path.is_file():
            raise ModelFileError(f"robot model file not found: {path}")
        path = path.resolve()
        same = [p for p in PROFILES.values() if p.model.path == path and not p.model.edits_needed]
        return (same[0].name, path, same[0]) if same else (path.stem, path, None)
    return profile.name, prepared_model_path(profile), profile


def _compile(path: Path):
    """Compile the MJCF file with MuJoCo and Pinocchio; MJCFError on failure."""
    import mujoco
    import pinocchio as pin

    try:
        mj_model = mujoco.MjModel.from_xml_path(str(path))
    except Exception as exc:  # MuJoCo raises ValueError for XML and compile errors
        raise MJCFError(f"{path}: MuJoCo cannot load the model: {_one_line(exc)}") from exc
    try:
        pin_model = pin.buildModelFromMJCF(str(path))
    except Exception as exc:
        raise MJCFError(f"{path}: Pinocchio cannot load the model: {_one_line(exc)}") from exc
    return mj_model, pin_model


def _name(mj_model, objtype, idx: int) -> str:
    import mujoco

    return mujoco.mj_id2name(mj_model, objtype, idx) or ""


def _root(mj_model, path: Path):
    """The root body and its joints; whether they form a free or planar root."""
    import mujoco

    if mj_model.njnt == 0:
        raise MJCFError(f"{path}: the model has no joints")
    root_body = int(mj_model.jnt_bodyid[0])
    if int(mj_model.body_parentid[root_body]) != 0:
        raise MJCFError(f"{path}: the first joint must sit on a body directly under <worldbody>")
    root_joints = [j for j in range(mj_model.njnt) if int(mj_model.jnt_bodyid[j]) == root_body]
    types = [int(mj_model.jnt_type[j]) for j in root_joints]
    is_floating = types == [_FREE]
    is_planar = False
    if sorted(types) == [_SLIDE, _SLIDE, _HINGE]:
        data = mujoco.MjData(mj_model)
        mujoco.mj_kinematics(mj_model, data)
        hinge_axes = [data.xaxis[j] for j in range(mj_model.njnt) if int(mj_model.jnt_type[j]) == _HINGE]
        slide_axes = [data.xaxis[j] for j in root_joints if int(mj_model.jnt_type[j]) == _SLIDE]
        normal = hinge_axes[0]
        is_planar = abs(abs(normal[1]) - 1.0) < 1e-9  # motion in the world x-z plane
        is_planar = (
            is_planar
            and all(abs(abs(a @ normal) - 1.0) < 1e-9 for a in hinge_axes)
            and all(abs(a @ normal) < 1e-9 for a in slide_axes)
        )
    if not (is_floating or is_planar):
        raise MJCFError(
            f"{path}: the root body {_name(mj_model, mujoco.mjtObj.mjOBJ_BODY, root_body)!r} "
            "must carry either one free joint or a planar slide/slide/hinge triple "
            "(all hinges about the world y axis, slides in the x-z plane)"
        )
    names = tuple(_name(mj_model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in root_joints)
    return root_body, root_joints, names, is_floating, is_planar


def _actuators(mj_model, smap, path: Path) -> ActuatorSet:
    import mujoco

    names, jnames, pv, pq, dof, qadr, gear, crange, tlim = [], [], [], [], [], [], [], [], []
    for a in range(mj_model.nu):
        aname = _name(mj_model, mujoco.mjtObj.mjOBJ_ACTUATOR, a)
        if int(mj_model.actuator_trntype[a]) != int(mujoco.mjtTrn.mjTRN_JOINT):
            raise MJCFError(f"{path}: actuator {aname!r} must drive a joint directly")
        j = int(mj_model.actuator_trnid[a, 0])
        if int(mj_model.jnt_type[j]) not in (_SLIDE, _HINGE):
            raise MJCFError(f"{path}: actuator {aname!r} must drive a hinge or slide joint")
        jname = _name(mj_model, mujoco.mjtObj.mjOBJ_JOINT, j)
        if int(mj_model.actuator_biastype[a]) != int(mujoco.mjtBias.mjBIAS_NONE) or int(
            mj_model.actuator_gaintype[a]
        ) != int(mujoco.mjtGain.mjGAIN_FIXED):
            raise MJCFError(
                f"{path}: actuator {aname!r} is a position or velocity servo "
                f"(gain {mj_model.actuator_gainprm[a, 0]:g}, bias type "
                f"{mujoco.mjtBias(int(mj_model.actuator_biastype[a])).name}): the controller sends joint torques; "
                'give the robot a profile with servos = "convert" in its [model] table, or torque motors'
            )
        if float(mj_model.actuator_gainprm[a, 0]) != 1.0:
            raise MJCFError(
                f"{path}: actuator {aname!r} has gain {mj_model.actuator_gainprm[a, 0]:g}: a torque motor has gain 1 "
                "(its transmission is the gear)"
            )
        g = float(mj_model.actuator_gear[a, 0])
        lo, hi = -np.inf, np.inf
        if mj_model.actuator_ctrllimited[a]:
            lo, hi = (float(x) for x in mj_model.actuator_ctrlrange[a])
        crange.append((lo, hi))
        if mj_model.actuator_forcelimited[a]:
            flo, fhi = (float(x) for x in mj_model.actuator_forcerange[a])
            lo, hi = max(lo, flo), min(hi, fhi)
        t_lo, t_hi = sorted((g * lo, g * hi))
        if mj_model.jnt_actfrclimited[j]:  # joint-level clamp on the summed actuator force
            t_lo = max(t_lo, float(mj_model.jnt_actfrcrange[j, 0]))
            t_hi = min(t_hi, float(mj_model.jnt_actfrcrange[j, 1]))
        names.append(aname)
        jnames.append(jname)
        pv.append(smap.joint_pin_v[jname])
        pq.append(smap.joint_pin_q[jname])
        dof.append(int(mj_model.jnt_dofadr[j]))
        qadr.append(int(mj_model.jnt_qposadr[j]))
        gear.append(g)
        tlim.append((t_lo, t_hi))
    idx = lambda x: np.asarray(x, dtype=np.intp)  # noqa: E731
    return ActuatorSet(
        names=tuple(names),
        joint_names=tuple(jnames),
        pin_v_idx=idx(pv),
        pin_q_idx=idx(pq),
        mj_dof_idx=idx(dof),
        mj_qpos_idx=idx(qadr),
        gear=np.asarray(gear, dtype=float).reshape(-1),
        ctrl_range=np.asarray(crange, dtype=float).reshape(-1, 2),
        torque_limit_Nm=np.asarray(tlim, dtype=float).reshape(-1, 2),
    )


def _couplings(mj_model, smap, path: Path) -> tuple[Coupling, ...]:
    import mujoco

    out = []
    for t in range(mj_model.ntendon):
        tname = _name(mj_model, mujoco.mjtObj.mjOBJ_TENDON, t)
        adr, num = int(mj_model.tendon_adr[t]), int(mj_model.tendon_num[t])
        if any(int(mj_model.wrap_type[w]) != int(mujoco.mjtWrap.mjWRAP_JOINT) for w in range(adr, adr + num)):
            raise MJCFError(f"{path}: tendon {tname!r}: only fixed (joint) tendons are supported")
        if np.any(mj_model.tendon_stiffnesspoly[t]) or np.any(mj_model.tendon_dampingpoly[t]):
            raise MJCFError(f"{path}: tendon {tname!r}: nonlinear spring/damper polynomials are not supported")
        joints = [int(mj_model.wrap_objid[w]) for w in range(adr, adr + num)]
        jn = tuple(_name(mj_model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in joints)
        out.append(
            Coupling(
                name=tname,
                joint_names=jn,
                coefficients=np.array([float(mj_model.wrap_prm[w]) for w in range(adr, adr + num)]),
                pin_q_idx=np.array([smap.joint_pin_q[n] for n in jn], dtype=np.intp),
                pin_v_idx=np.array([smap.joint_pin_v[n] for n in jn], dtype=np.intp),
                springlength=(float(mj_model.tendon_lengthspring[t, 0]), float(mj_model.tendon_lengthspring[t, 1])),
                stiffness=float(mj_model.tendon_stiffness[t]),
                damping=float(mj_model.tendon_damping[t]),
            )
        )
    return tuple(out)


def _passive_params(mj_model, smap, path: Path):
    """Joint stiffness / springref / damping / armature in Pinocchio v order.

    Damping and armature are per dof and MuJoCo uses the same value on every
    dof of a free or ball joint, so they are invariant under the free-flyer
    velocity map and can be copied dof by dof.
    """
    import mujoco

    if np.any(mj_model.jnt_stiffnesspoly) or np.any(mj_model.dof_dampingpoly):
        raise MJCFError(f"{path}: nonlinear joint spring/damper polynomials are not supported")
    if np.any(mj_model.body_gravcomp):
        raise MJCFError(f"{path}: body gravcomp is not supported (it hides gravity from the controller)")
    nv = mj_model.nv
    stiff, ref, damp, arm = np.zeros(nv), np.zeros(nv), np.zeros(nv), np.zeros(nv)
    ndof = {_FREE: 6, _BALL: 3, _SLIDE: 1, _HINGE: 1}
    for j in range(mj_model.njnt):
        jtype = int(mj_model.jnt_type[j])
        name = _name(mj_model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"
        pv, da, n = smap.joint_pin_v[name], int(mj_model.jnt_dofadr[j]), ndof[jtype]
        damp[pv : pv + n] = mj_model.dof_damping[da : da + n]
        arm[pv : pv + n] = mj_model.dof_armature[da : da + n]
        if jtype in (_SLIDE, _HINGE):
            stiff[pv] = float(mj_model.jnt_stiffness[j])
            ref[pv] = float(mj_model.qpos_spring[int(mj_model.jnt_qposadr[j])])
        elif mj_model.jnt_stiffness[j] != 0.0:
            raise MJCFError(f"{path}: stiffness on free or ball joints is not supported")
    return stiff, ref, damp, arm


def _leg_joints(mj_model, contact_site_ids: dict[str, int], root_joints) -> dict[str, tuple[str, ...]]:
    """Side -> the hinge and slide joints on the tree path from the root to the body of that side's
    contact site (MuJoCo order): the leg's joints, whatever their names."""
    import mujoco

    legs = {}
    for side, site in contact_site_ids.items():
        body, on_path = int(mj_model.site_bodyid[site]), set()
        while body > 0:
            on_path.add(body)
            body = int(mj_model.body_parentid[body])
        legs[side] = tuple(
            _name(mj_model, mujoco.mjtObj.mjOBJ_JOINT, j)
            for j in range(mj_model.njnt)
            if j not in root_joints
            and int(mj_model.jnt_type[j]) in (_SLIDE, _HINGE)
            and int(mj_model.jnt_bodyid[j]) in on_path
        )
    return legs


def load_robot(name_or_path: str | os.PathLike) -> Robot:
    """Load a robot into MuJoCo and Pinocchio from one MJCF file.

    Args:
        name_or_path: A bundled robot's name (:func:`amlip_qp.profiles.bundled_names`), the path
            of a robot profile (``.toml``), or the path of an MJCF ``.xml`` file following the
            model conventions of ``docs/ARCHITECTURE.md``.

    Returns:
        The :class:`~amlip_qp.robots.robot.Robot`.

    Raises:
        UnknownRobotError: An unknown name (the message lists the known names).
        ProfileError: The profile file is missing or invalid, or its ``[imu] body`` is not in the model.
        ModelFileError: The file does not exist.
        MJCFError: The file is malformed (XML syntax, MuJoCo compile error,
            Pinocchio failure), lacks the ``left-contact``/``right-contact``
            sites, or uses something this library does not support.
    """
    import mujoco

    name, path, profile = resolve_robot(name_or_path)
    mj_model, pin_model = _compile(path)
    smap = build_state_map(mj_model, pin_model, source=str(path))
    actuated = _actuators(mj_model, smap, path)  # first: a servo is refused before anything else
    contact, c_mj, c_pin, force, f_mj, f_pin, line, l_pin = foot_sites(mj_model, pin_model, path)
    root_body, root_joints, root_names, is_floating, is_planar = _root(mj_model, path)
    check_sites_agree(mj_model, pin_model, smap, path)

    jt = mj_model.jnt_type
    joint_names = tuple(
        _name(mj_model, mujoco.mjtObj.mjOBJ_JOINT, j)
        for j in range(mj_model.njnt)
        if j not in root_joints and int(jt[j]) in (_SLIDE, _HINGE)
    )
    act_set = set(actuated.joint_names)
    passive = tuple(n for n in joint_names if n not in act_set)

    key_id = mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_KEY, STAND_KEYFRAME)
    qpos_stand = (mj_model.key_qpos[key_id] if key_id >= 0 else mj_model.qpos0).copy()
    q_stand = qpos_to_q(smap, qpos_stand)
    qpos_stand = q_to_qpos(smap, q_stand)  # quaternion normalized

    import pinocchio as pin

    base_name = _name(mj_model, mujoco.mjtObj.mjOBJ_BODY, root_body)
    imu_body = profile.imu.body if profile is not None else None
    has_imu_body = imu_body is None or mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_BODY, imu_body) >= 0
    if profile is not None and not has_imu_body:
        raise ProfileError(f"{profile.source}: imu.body: the model {path.name} has no body {imu_body!r}")
    stiff, ref, damp, arm = _passive_params(mj_model, smap, path)
    robot = Robot(
        name=name,
        path=path,
        mj_model=mj_model,
        pin_model=pin_model,
        pin_data=pin_model.createData(),
        state_map=smap,
        contact_sites=contact,
        contact_site_ids=c_mj,
        contact_frame_ids=c_pin,
        force_sites=force,
        force_site_ids=f_mj,
        force_frame_ids=f_pin,
        sole_line_sites=line,
        sole_line_frame_ids=l_pin,
        base_body=base_name,
        base_frame_id=int(pin_model.getFrameId(base_name, pin.BODY)),
        root_joint_names=root_names,
        is_floating=is_floating,
        is_planar=is_planar,
        joint_names=joint_names,
        actuated=actuated,
        passive_joint_names=passive,
        passive_v_idx=np.array([smap.joint_pin_v[n] for n in passive], dtype=np.intp),
        passive_q_idx=np.array([smap.joint_pin_q[n] for n in passive], dtype=np.intp),
        mass_kg=float(np.sum(mj_model.body_mass)),
        q_stand=q_stand,
        qpos_stand=qpos_stand,
        couplings=_couplings(mj_model, smap, path),
        dof_stiffness=stiff,
        dof_springref=ref,
        dof_damping=damp,
        dof_armature=arm,
        profile=profile,
        leg_joint_names=_leg_joints(mj_model, c_mj, root_joints),
    )
    return replace(robot, springs=spring_rows(robot))
