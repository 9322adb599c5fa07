"""Generate ``amlip_qp/models/cassie.xml`` (package data) from Agility Robotics' Cassie parameter sheet.

Usage::

    python models/tools/build_cassie.py [--params PATH] [--out PATH]

The sheet (``cassie_parameters.json``) describes Agility's 35-qpos MuJoCo
model: per leg a ball-jointed achilles rod, a heel spring, a foot crank and a
plantar rod closing two kinematic loops.  This script writes the 20-DOF model
used by amlip_qp (floating base + 7 hinges per leg) and lumps the bodies that
are dropped into the bodies they ride on, with the parallel-axis theorem, at
the sheet's standing configuration.  The lumping math lives in
:func:`lumped_bodies`, so tests and documentation can recompute it.

The emitted MJCF uses only features that both MuJoCo and Pinocchio's
``buildModelFromMJCF`` read: explicit ``<inertial>`` (pos, quat, mass,
diaginertia), hinge joints with ``range``/``armature``/``actuatorfrcrange`` (``ref`` is
baked into the body frames, see :func:`baked_quat`), sites, a free
joint.  MuJoCo-only elements (floor, lights, camera, tendons, actuators,
keyframe) are ignored by Pinocchio.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from cassie_sheet import (
    CONTACT_RADIUS,
    CONTACT_SOLIMP,
    CONTACT_SOLREF,
    DEFAULT_PARAMS,
    FRICTION,
    MODELS_DIR,
    SIDES,
    actuator_lines,
    baked_quat,
    bodies_by_name,
    body_inertia_tensor,
    fmt,
    foot_contact_points,
    foot_site_lines,
    hinge_joint_line,
    hinge_ref,
    keyframe_lines,
    level_feet_and_ground,
    load_params,
    mat_to_quat,
    pelvis_open_lines,
    pose_in_ancestor,
    scene_lines,
    sheet_standing,
)

DEFAULT_OUT = MODELS_DIR / "cassie.xml"

#: The 7 hinges kept per leg, in tree (= qpos) order.
LEG_JOINTS = ("hip-roll", "hip-yaw", "hip-pitch", "knee", "shin", "tarsus", "foot")
#: Dropped body -> body it is lumped into (per side).  See amlip_qp/models/README.md.
LUMP_INTO = {
    "achilles-rod": "hip-pitch",
    "knee-spring": "knee",
    "heel-spring": "tarsus",
    "foot-crank": "tarsus",
    "plantar-rod": "tarsus",
}
#: Heel-spring stiffness used for the knee-tarsus coupling tendon (N m/rad).
HEEL_SPRING_STIFFNESS = 1250.0
#: Damping of the coupling tendon (N m s/rad).
COUPLING_DAMPING = 0.1


def combine(parts):
    """Combine [(mass, com, I_about_com)] (all in one frame) into one rigid body."""
    m = sum(p[0] for p in parts)
    c = sum(p[0] * p[1] for p in parts) / m
    I = np.zeros((3, 3))
    for mi, ci, Ii in parts:
        d = ci - c
        I += Ii + mi * (d @ d * np.eye(3) - np.outer(d, d))
    return m, c, I


def principal(I):
    """Principal moments (descending) and the quaternion (w, x, y, z) of the principal frame."""
    I = 0.5 * (I + I.T)
    vals, vecs = np.linalg.eigh(I)
    order = np.argsort(vals)[::-1]
    vals, vecs = vals[order], vecs[:, order]
    if np.linalg.det(vecs) < 0:
        vecs[:, 2] *= -1
    return vals, mat_to_quat(vecs)


def lumped_bodies(params):
    """Mass properties of the kept bodies after lumping.

    Returns ``{body_name: dict(mass, com, inertia (3x3 about com, body axes),
    principal, iquat, absorbed=[names])}`` for the pelvis and the 7 bodies of
    each leg.  Dropped bodies are transported into their host frame at the
    sheet's standing configuration (ball-joint quaternion and hinge angles).
    """
    bodies = bodies_by_name(params)
    standing = sheet_standing(params)
    out = {}
    for name in ["cassie-pelvis"] + [f"{s}-{j}" for s in SIDES for j in LEG_JOINTS]:
        m, c, I = body_inertia_tensor(bodies[name])
        out[name] = {"parts": [(m, c, I)], "absorbed": []}
    for side in SIDES:
        for short, host in LUMP_INTO.items():
            name, host = f"{side}-{short}", f"{side}-{host}"
            # Pose of the dropped body in its host at the standing configuration.
            p, R = pose_in_ancestor(bodies, name, host, standing)
            mi, ci, Ii = body_inertia_tensor(bodies[name])
            out[host]["parts"].append((mi, p + R @ ci, R @ Ii @ R.T))
            out[host]["absorbed"].append(name)
    for d in out.values():
        m, c, I = combine(d.pop("parts"))
        vals, q = principal(I)
        d.update(mass=m, com=c, inertia=I, principal=vals, iquat=q)
    return out


# ---------------------------------------------------------------- MJCF writer
def build_xml(params, keyframe_qpos=None):
    bodies = bodies_by_name(params)
    lumped = lumped_bodies(params)
    act = {a["joint"]: a for a in params["actuators"]}
    lines = []
    w = lines.append

    def inertial(name, ind):
        d = lumped[name]
        w(
            f'{ind}<inertial pos="{fmt(d["com"])}" quat="{fmt(d["iquat"])}" '
            f'mass="{d["mass"]:.9g}" diaginertia="{fmt(d["principal"])}"/>'
        )

    def visual_geoms(b, ind, rgba):
        for k, g in enumerate(b["collision_capsules_etc"]):
            if b["name"].endswith("-foot") or b["name"] == "cassie-pelvis":
                continue
            size = g["size"][:2] if g["type"] == "capsule" else g["size"][:1]
            w(
                f'{ind}<geom name="{b["name"]}-vis{k}" type="{g["type"]}" size="{fmt(size)}" '
                f'pos="{fmt(g["pos"])}" quat="{fmt(g["quat"])}" contype="0" conaffinity="0" '
                f'group="1" rgba="{rgba}" mass="0"/>'
            )

    pel = bodies["cassie-pelvis"]
    lines += scene_lines(
        "cassie",
        [
            "Generated by models/tools/build_cassie.py from Agility Robotics' Cassie parameters.",
            "Physical parameters from Agility Robotics' Cassie MuJoCo model (MIT licence), also in",
            "MuJoCo Menagerie's agility_cassie; this model file was written for amlip_qp from those",
            "parameters.  20 DOF: free pelvis + 7 hinges per leg.  See amlip_qp/models/README.md.",
        ],
    )
    inertial("cassie-pelvis", "      ")
    lines += pelvis_open_lines(pel, lines.pop())
    for side in SIDES:
        ind = "      "
        opened = 0
        for short in LEG_JOINTS:
            name = f"{side}-{short}"
            b = bodies[name]
            w(f'{ind}<body name="{name}" pos="{fmt(b["pos_in_parent"])}" quat="{fmt(baked_quat(b))}">')
            opened += 1
            ind += "  "
            w(hinge_joint_line(b["joints"][0], act, ind))
            inertial(name, ind)
            visual_geoms(b, ind, "0.35 0.4 0.5 1" if side == "left" else "0.5 0.4 0.35 1")
            if short == "foot":
                fp = foot_contact_points(params, side)
                cap = b["collision_capsules_etc"][0]
                w(
                    f'{ind}<geom name="{side}-foot-blade" type="capsule" size="{fmt(cap["size"][:2])}" '
                    f'pos="{fmt(cap["pos"])}" quat="{fmt(cap["quat"])}" contype="0" conaffinity="0" '
                    f'group="1" rgba="0.2 0.2 0.2 1" mass="0"/>'
                )
                for tag, p in zip(("toe", "heel"), fp):
                    w(
                        f'{ind}<geom name="{side}-{tag}-contact" type="sphere" size="{CONTACT_RADIUS}" '
                        f'pos="{fmt(p)}" contype="0" conaffinity="1" condim="3" friction="{fmt(FRICTION)}" '
                        f'solref="{fmt(CONTACT_SOLREF)}" solimp="{fmt(CONTACT_SOLIMP)}" '
                        f'rgba="0.9 0.5 0.1 1" mass="0"/>'
                    )
                lines += foot_site_lines(side, fp, ind)
        for _ in range(opened):
            ind = ind[:-2]
            w(f"{ind}</body>")
    w("    </body>")
    w("  </worldbody>")
    w("  <tendon>")
    L0 = sum(hinge_ref(bodies[f"left-{j}"]["joints"][0]) for j in ("knee", "tarsus"))
    for side in SIDES:
        w(
            f'    <fixed name="{side}-achilles" stiffness="{HEEL_SPRING_STIFFNESS:.9g}" '
            f'springlength="{L0:.9g}" damping="{COUPLING_DAMPING:.9g}">'
        )
        w(f'      <joint joint="{side}-knee" coef="1"/>')
        w(f'      <joint joint="{side}-tarsus" coef="1"/>')
        w("    </fixed>")
    w("  </tendon>")
    lines += actuator_lines(act)
    if keyframe_qpos is not None:
        lines += keyframe_lines(keyframe_qpos)
    w("</mujoco>")
    return "\n".join(lines) + "\n"


def standing_qpos21(params):
    """The sheet's standing qpos reduced to our 21 entries (base height not yet adjusted)."""
    st = sheet_standing(params)
    q = list(st["base"])
    for side in SIDES:
        q += [st[f"{side}-{j}"] for j in LEG_JOINTS]
    return np.array(q, float)


def keyframe(params, xml_without_key):
    """Standing keyframe: the sheet's joint angles, base height such that the blades rest on the floor.

    The foot joint angle is adjusted (by a 1-D Newton solve) so the blade is level, then the
    base height is set so the toe/heel sphere centres are one radius above z = 0.
    Returns (qpos21, info dict).
    """
    import mujoco

    m = mujoco.MjModel.from_xml_string(xml_without_key)
    q = standing_qpos21(params)
    info = {"sheet_base_z": float(q[2])}
    level_feet_and_ground(m, q, info)
    return q, info


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--params", type=Path, default=DEFAULT_PARAMS)
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args(argv)
    params = load_params(args.params)
    q, info = keyframe(params, build_xml(params))
    args.out.write_text(build_xml(params, q))
    lumped = lumped_bodies(params)
    print(f"wrote {args.out}")
    print(f"total mass {sum(d['mass'] for d in lumped.values()):.9f} kg")
    for name, d in lumped.items():
        extra = f"  (+ {', '.join(d['absorbed'])})" if d["absorbed"] else ""
        print(f"  {name:16s} {d['mass']:.6f} kg{extra}")
    for k, v in info.items():
        print(f"  {k} = {v:.9g}")


if __name__ == "__main__":
    main()
