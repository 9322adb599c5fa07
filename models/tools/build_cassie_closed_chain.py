"""Generate ``amlip_qp/models/cassie-closed-chain.xml``: Cassie with the sheet's full tree and loop closures.

Usage::

    python models/tools/build_cassie_closed_chain.py [--params PATH] [--out PATH]

The sheet (``cassie_parameters.json``, Agility Robotics' Cassie MuJoCo model
parameters, MIT licence) describes Agility's 35-qpos model.  This script keeps
all of it, per leg: the ball-jointed achilles rod, the welded knee spring, the
heel-spring hinge, the foot crank and the plantar rod, with the sheet's masses,
inertias and frames, and the sheet's four ``connect`` loop closures (achilles
rod -> heel spring, plantar rod -> foot).  It is a MuJoCo plant only: the
controller keeps Pinocchio's ``cassie.xml``.

Shared with ``build_cassie.py`` (:mod:`cassie_sheet`): the scene, options,
contact softness, actuators, foot sites, and the baking of the knee and tarsus
``ref`` into the body frames, so a joint value means the same in both files.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from cassie_sheet import (
    CONTACT_SOLIMP,
    CONTACT_SOLREF,
    DEFAULT_PARAMS,
    FRICTION,
    MODELS_DIR,
    SIDES,
    actuator_lines,
    baked_quat,
    bodies_by_name,
    fmt,
    foot_contact_points,
    foot_site_lines,
    hinge_joint_line,
    keyframe_lines,
    level_feet_and_ground,
    load_params,
    pelvis_open_lines,
    pose_in_ancestor,
    scene_lines,
    sheet_reference_config,
)

DEFAULT_OUT = MODELS_DIR / "cassie-closed-chain.xml"

#: solref (timeconst s, dampratio) and solimp of the loop-closure equalities: stiff rods, the
#: stiffest time constant MuJoCo allows (2 time steps), the contacts' impedance.
LOOP_SOLREF = (0.001, 1.0)
LOOP_SOLIMP = (0.95, 0.99, 0.001)
#: Radius of the rods' and crank's visual capsules (m); visual only, no mass.
ROD_VIS_RADIUS = 0.008
#: Passive joints moved to close the loops in the keyframe (per side).
LOOP_JOINTS = ("achilles-rod", "heel-spring", "foot-crank", "plantar-rod")
#: Tolerance (m) of the keyframe's loop-closure projection.
CLOSE_TOL_M = 1e-12


def loop_closures(params):
    """The sheet's ``connect`` closures with both anchors: ``[dict(name, body1, body2, anchor1, anchor2)]``.

    The sheet gives the anchor in body1.  MuJoCo computes the body2 anchor in the model's
    qpos0, which for the sheet's own model is every hinge at its ``ref`` and the ball joints at
    identity (:func:`cassie_sheet.sheet_reference_config`).  This file bakes ``ref`` into the
    frames (its qpos0 differs), so the body2 anchor is computed here, in that same configuration,
    and both anchors are written as sites.
    """
    bodies = bodies_by_name(params)
    config = sheet_reference_config(params)
    out = []
    for c in params["loop_closures"]:
        if c["type"] != "connect":
            raise ValueError(f"unsupported loop closure type {c['type']!r}")
        a1 = np.array(c["anchor_in_body1"], float)
        p1, R1 = pose_in_ancestor(bodies, c["body1"], "cassie-pelvis", config)
        p2, R2 = pose_in_ancestor(bodies, c["body2"], "cassie-pelvis", config)
        a2 = R2.T @ (p1 + R1 @ a1 - p2)
        side, short = c["body1"].split("-", 1)
        name = f"{side}-{short.removesuffix('-rod')}-loop"
        out.append({"name": name, "body1": c["body1"], "body2": c["body2"], "anchor1": a1, "anchor2": a2})
    return out


def loop_site(body):
    """Name of a loop-closure anchor site on ``body``."""
    return f"{body}-loop"


def build_xml(params, keyframe_qpos=None):
    bodies = bodies_by_name(params)
    act = {a["joint"]: a for a in params["actuators"]}
    children = {}
    for b in params["bodies"]:
        children.setdefault(b["parent"], []).append(b)
    closures = loop_closures(params)
    anchors = {}  # body -> [(site name, pos)]
    for c in closures:
        anchors.setdefault(c["body1"], []).append((loop_site(c["body1"]), c["anchor1"]))
        anchors.setdefault(c["body2"], []).append((loop_site(c["body2"]), c["anchor2"]))
    contact = (
        f'contype="0" conaffinity="1" condim="3" friction="{fmt(FRICTION)}" '
        f'solref="{fmt(CONTACT_SOLREF)}" solimp="{fmt(CONTACT_SOLIMP)}"'
    )
    lines = []
    w = lines.append

    def inertial(b, ind):
        return (
            f'{ind}<inertial pos="{fmt(b["com"])}" quat="{fmt(b["inertia_frame_quat_wxyz"])}" '
            f'mass="{b["mass"]:.9g}" diaginertia="{fmt(b["principal_inertia"])}"/>'
        )

    def rod_vis(name, tip, ind):
        w(
            f'{ind}<geom name="{name}-vis" type="capsule" size="{ROD_VIS_RADIUS}" fromto="0 0 0 {fmt(tip)}" '
            f'contype="0" conaffinity="0" group="1" rgba="0.7 0.7 0.72 1" mass="0"/>'
        )

    def body(b, ind):
        name = b["name"]
        side = name.split("-", 1)[0]
        w(f'{ind}<body name="{name}" pos="{fmt(b["pos_in_parent"])}" quat="{fmt(baked_quat(b))}">')
        inner = ind + "  "
        for j in b["joints"]:
            if j["type"] == "hinge":
                w(hinge_joint_line(j, act, inner))
            elif j["type"] == "ball":
                w(f'{inner}<joint name="{j["name"]}" type="ball" pos="0 0 0" damping="{j["damping"]:.9g}"/>')
            else:
                raise ValueError(f"unexpected {j['type']} joint on {name}")
        w(inertial(b, inner))
        rgba = "0.35 0.4 0.5 1" if side == "left" else "0.5 0.4 0.35 1"
        for k, g in enumerate(b["collision_capsules_etc"]):
            size = g["size"][:2] if g["type"] == "capsule" else g["size"][:1]
            w(
                f'{inner}<geom name="{name}-collision{k}" type="{g["type"]}" size="{fmt(size)}" '
                f'pos="{fmt(g["pos"])}" quat="{fmt(g["quat"])}" {contact} rgba="{rgba}" mass="0"/>'
            )
        for site, pos in anchors.get(name, ()):
            w(f'{inner}<site name="{site}" pos="{fmt(pos)}" size="0.006"/>')
            if not name.endswith("-foot"):
                rod_vis(name, pos, inner)
        if name.endswith("-foot-crank"):
            rod_vis(name, children[name][0]["pos_in_parent"], inner)
        if name.endswith("-foot"):
            lines.extend(foot_site_lines(side, foot_contact_points(params, side), inner))
        for c in children.get(name, ()):
            body(c, inner)
        w(f"{ind}</body>")

    pel = bodies["cassie-pelvis"]
    lines += scene_lines(
        "cassie-closed-chain",
        [
            "Generated by models/tools/build_cassie_closed_chain.py from Agility Robotics' Cassie parameters.",
            "Physical parameters from Agility Robotics' Cassie MuJoCo model (MIT licence), also in",
            "MuJoCo Menagerie's agility_cassie; this model file was written for amlip_qp from those",
            "parameters.  The sheet's full tree: achilles and plantar rods closed by connect equalities,",
            "knee and heel springs, foot crank.  A MuJoCo plant; the controller's model is cassie.xml.",
            "See amlip_qp/models/README.md, 'Cassie closed chain'.",
        ],
    )
    lines += pelvis_open_lines(pel, inertial(pel, "      "))
    for c in children["cassie-pelvis"]:
        body(c, "      ")
    w("    </body>")
    w("  </worldbody>")
    w("  <equality>")
    for c in closures:
        w(
            f'    <connect name="{c["name"]}" site1="{loop_site(c["body1"])}" site2="{loop_site(c["body2"])}" '
            f'solref="{fmt(LOOP_SOLREF)}" solimp="{fmt(LOOP_SOLIMP)}"/>'
        )
    w("  </equality>")
    lines += actuator_lines(act)
    if keyframe_qpos is not None:
        lines += keyframe_lines(keyframe_qpos)
    w("</mujoco>")
    return "\n".join(lines) + "\n"


def loop_residuals(m, d):
    """Per closure (in ``m``'s equality order): the world distance (m) between its two anchor sites.

    ``d`` must hold forwarded kinematics.
    """
    import mujoco

    out = []
    for e in range(m.neq):
        s1, s2 = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
        assert int(m.eq_objtype[e]) == int(mujoco.mjtObj.mjOBJ_SITE)
        out.append(float(np.linalg.norm(d.site_xpos[s1] - d.site_xpos[s2])))
    return np.array(out)


def close_loops(m, q, info):
    """Move the passive loop joints (:data:`LOOP_JOINTS`) so every closure's anchors coincide.

    Gauss-Newton with minimum-norm steps on those joints only (the shared joints keep their
    values); ``q`` is modified in place.  Records the residuals before and after in ``info``.
    """
    import mujoco

    d = mujoco.MjData(m)
    dofs = [
        int(m.jnt_dofadr[m.joint(f"{s}-{j}").id]) + k
        for s in SIDES
        for j in LOOP_JOINTS
        for k in range(3 if j == "achilles-rod" else 1)
    ]
    jp1, jp2 = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    for it in range(50):
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        r, J = [], []
        for e in range(m.neq):
            s1, s2 = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
            mujoco.mj_jacSite(m, d, jp1, None, s1)
            mujoco.mj_jacSite(m, d, jp2, None, s2)
            r.append(d.site_xpos[s1] - d.site_xpos[s2])
            J.append(jp1 - jp2)
        r, J = np.concatenate(r), np.vstack(J)
        if it == 0:
            info["levelled_loop_residual_max_m"] = float(np.abs(loop_residuals(m, d)).max())
        if np.abs(r).max() < CLOSE_TOL_M:
            break
        dv = np.zeros(m.nv)
        dv[dofs] = -np.linalg.lstsq(J[:, dofs], r, rcond=None)[0]
        mujoco.mj_integratePos(m, q, dv, 1.0)
    info["loop_residual_max_m"] = float(np.abs(loop_residuals(m, d)).max())


def keyframe(params, xml_without_key):
    """Standing keyframe (35 qpos): the sheet's standing qpos, feet levelled, loops closed, on the floor.

    The feet are levelled exactly as in ``cassie.xml`` (same joint values for the joints both
    files share), then the passive loop joints are projected onto the loop closures, then the
    base height is set so the toe/heel centres are one contact radius above z = 0.
    Returns (qpos35, info dict).
    """
    import mujoco

    m = mujoco.MjModel.from_xml_string(xml_without_key)
    q = np.array(params["standing_qpos"], float)
    d = mujoco.MjData(m)
    d.qpos[:] = q
    mujoco.mj_kinematics(m, d)
    info = {"sheet_base_z": float(q[2]), "sheet_loop_residual_max_m": float(loop_residuals(m, d).max())}
    level_feet_and_ground(m, q, info, close=lambda qq: close_loops(m, qq, info))
    return q, info


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--params", type=Path, default=DEFAULT_PARAMS)
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args(argv)
    params = load_params(args.params)
    q, info = keyframe(params, build_xml(params))
    args.out.write_text(build_xml(params, q))
    print(f"wrote {args.out}")
    print(f"total mass {sum(b['mass'] for b in params['bodies']):.9f} kg (sheet {params['total_mass']} kg)")
    for c in loop_closures(params):
        print(f"  {c['name']}: {c['body1']} {fmt(c['anchor1'])} -> {c['body2']} {fmt(c['anchor2'])}")
    for k, v in info.items():
        print(f"  {k} = {v:.9g}")


if __name__ == "__main__":
    main()
