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
import json
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
DEFAULT_PARAMS = Path(__file__).resolve().parents[3] / "shared" / "reference" / "cassie_parameters.json"
DEFAULT_OUT = REPO / "amlip_qp" / "models" / "cassie.xml"

SIDES = ("left", "right")
#: The 7 hinges kept per leg, in tree (= qpos) order.
LEG_JOINTS = ("hip-roll", "hip-yaw", "hip-pitch", "knee", "shin", "tarsus", "foot")
#: Per-leg joints of the sheet's 35-element standing qpos, in its order, with qpos widths.
SHEET_LEG_QPOS = (
    ("hip-roll", 1),
    ("hip-yaw", 1),
    ("hip-pitch", 1),
    ("achilles-rod", 4),
    ("knee", 1),
    ("shin", 1),
    ("tarsus", 1),
    ("heel-spring", 1),
    ("foot-crank", 1),
    ("plantar-rod", 1),
    ("foot", 1),
)
#: Dropped body -> body it is lumped into (per side).  See amlip_qp/models/README.md.
LUMP_INTO = {
    "achilles-rod": "hip-pitch",
    "knee-spring": "knee",
    "heel-spring": "tarsus",
    "foot-crank": "tarsus",
    "plantar-rod": "tarsus",
}
#: Radius of the toe and heel contact spheres (m); equal to the sheet's foot capsule radius.
CONTACT_RADIUS = 0.02
#: Heel-spring stiffness used for the knee-tarsus coupling tendon (N m/rad).
HEEL_SPRING_STIFFNESS = 1250.0
#: Damping of the coupling tendon (N m s/rad).
COUPLING_DAMPING = 0.1
#: Knee-spring (shin joint) stiffness (N m/rad), springref 0.
SHIN_STIFFNESS = 1500.0
#: Floor/foot contact: solref (timeconst, dampratio) and solimp.
CONTACT_SOLREF = (0.004, 1.0)
CONTACT_SOLIMP = (0.95, 0.99, 0.001, 0.5, 2.0)
FRICTION = (1.0, 0.005, 0.0001)


# ---------------------------------------------------------------- rotations
def quat_to_mat(q):
    """Rotation matrix of a unit quaternion (w, x, y, z)."""
    w, x, y, z = np.asarray(q, float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def mat_to_quat(R):
    """Unit quaternion (w, x, y, z), w >= 0, of a rotation matrix."""
    R = np.asarray(R, float)
    t = np.trace(R)
    if t > 0:
        s = 2.0 * np.sqrt(t + 1.0)
        q = [0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    else:
        i = int(np.argmax(np.diag(R)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(1.0 + R[i, i] - R[j, j] - R[k, k])
        q = [0.0] * 4
        q[0] = (R[k, j] - R[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (R[j, i] + R[i, j]) / s
        q[1 + k] = (R[k, i] + R[i, k]) / s
    q = np.array(q)
    q /= np.linalg.norm(q)
    return q if q[0] >= 0 else -q


def axis_angle_mat(axis, angle):
    """Rotation matrix about a unit axis."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


# ---------------------------------------------------------------- sheet access
def load_params(path=DEFAULT_PARAMS):
    with open(path) as f:
        return json.load(f)


def bodies_by_name(params):
    return {b["name"]: b for b in params["bodies"]}


def sheet_standing(params):
    """The sheet's standing qpos split into a dict: base (7,) and per joint name -> value(s)."""
    qs = list(params["standing_qpos"])
    out = {"base": np.array(qs[:7], float)}
    i = 7
    for side in SIDES:
        for name, width in SHEET_LEG_QPOS:
            vals = np.array(qs[i : i + width], float)
            out[f"{side}-{name}"] = vals if width > 1 else float(vals[0])
            i += width
    assert i == len(qs) == 35
    return out


def body_inertia_tensor(b):
    """(mass, com, 3x3 inertia about the CoM) of a sheet body, in its body frame."""
    R = quat_to_mat(b["inertia_frame_quat_wxyz"])
    I = R @ np.diag(b["principal_inertia"]) @ R.T
    return float(b["mass"]), np.array(b["com"], float), I


def child_pose_at_standing(b, standing):
    """Pose (p, R) of sheet body ``b`` in its parent's frame at the standing configuration."""
    p = np.array(b["pos_in_parent"], float)
    R = quat_to_mat(b["quat_in_parent_wxyz"])
    if not b["joints"]:
        return p, R
    j = b["joints"][0]
    if j["type"] == "ball":
        Rj = quat_to_mat(standing[j["name"]])
    elif j["type"] == "hinge":
        ref = (j.get("ref_rad") or [0.0])[0]
        Rj = axis_angle_mat(j["axis"], standing[j["name"]] - ref)
    else:
        raise ValueError(f"cannot lump a body with a {j['type']} joint: {b['name']}")
    # Joints sit at the body origin in the sheet, so the rotation is about it.
    return p, R @ Rj


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
            b = bodies[name]
            # Chain of poses from the host down to the dropped body.
            p, R = np.zeros(3), np.eye(3)
            chain = []
            cur = b
            while cur["name"] != host:
                chain.append(cur)
                cur = bodies[cur["parent"]]
            for link in reversed(chain):
                pl, Rl = child_pose_at_standing(link, standing)
                p, R = p + R @ pl, R @ Rl
            mi, ci, Ii = body_inertia_tensor(b)
            out[host]["parts"].append((mi, p + R @ ci, R @ Ii @ R.T))
            out[host]["absorbed"].append(name)
    for d in out.values():
        m, c, I = combine(d.pop("parts"))
        vals, q = principal(I)
        d.update(mass=m, com=c, inertia=I, principal=vals, iquat=q)
    return out


# ---------------------------------------------------------------- keyframe
def foot_contact_points(params, side):
    """Toe and heel sphere centres in the foot frame: the ends of the sheet's foot capsule."""
    g = bodies_by_name(params)[f"{side}-foot"]["collision_capsules_etc"][0]
    assert g["type"] == "capsule"
    c = np.array(g["pos"], float)
    axis = quat_to_mat(g["quat"])[:, 2]
    half = g["size"][1]
    a, b = c + half * axis, c - half * axis
    # The toe is the end that points forward (world +x) at the sheet's standing pose.
    R = standing_pose(params, f"{side}-foot")[1]
    return (a, b) if (R @ (a - b))[0] > 0 else (b, a)


def standing_pose(params, name):
    """(p, R) of a sheet body in the pelvis frame at the sheet's standing configuration."""
    bodies = bodies_by_name(params)
    standing = sheet_standing(params)
    chain = []
    cur = bodies[name]
    while cur["name"] != "cassie-pelvis":
        chain.append(cur)
        cur = bodies[cur["parent"]]
    p, R = np.zeros(3), np.eye(3)
    for link in reversed(chain):
        pl, Rl = child_pose_at_standing(link, standing)
        p, R = p + R @ pl, R @ Rl
    return p, R


def baked_quat(b):
    """Body quaternion with the hinge's ``ref`` baked in.

    The sheet places a body at ``quat_in_parent`` when its hinge is at ``ref``.  Writing
    ``quat_in_parent * rot(axis, -ref)`` and no ``ref`` attribute gives the same pose at every
    joint value (the joint sits at the body origin and rotations about the axis commute), so
    qpos keeps Agility's angle zeros.  Baking is needed because Pinocchio 4.1's MJCF parser
    honours ``ref`` in the kinematics but reports position limits shifted by ``-ref``.
    """
    q = np.array(b["quat_in_parent_wxyz"], float)
    j = b["joints"][0] if b["joints"] else None
    ref = (j.get("ref_rad") or [0.0])[0] if j and j["type"] == "hinge" else 0.0
    if ref == 0.0:
        return q
    return mat_to_quat(quat_to_mat(q) @ axis_angle_mat(j["axis"], -ref))


def fmt(v, digits=9):
    return " ".join(f"{float(x):.{digits}g}" for x in np.atleast_1d(v))


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

    def joint(b, ind):
        j = b["joints"][0]
        short = b["name"].split("-", 1)[1]
        attrs = [f'name="{j["name"]}"', 'type="hinge"', f'axis="{fmt(j["axis"])}"', 'pos="0 0 0"']
        if j["limited"]:
            attrs += ['limited="true"', f'range="{fmt(j["range_rad"])}"']
        stiff = SHIN_STIFFNESS if short == "shin" else j["stiffness"]
        if stiff:
            attrs += [f'stiffness="{stiff:.9g}"', 'springref="0"']
        if j["name"] in act:
            # Joint-side torque limit = gear * motor limit; MuJoCo clamps to it and
            # Pinocchio reads it into model.effortLimit.
            attrs.append(f'actuatorfrcrange="{fmt(act[j["name"]]["joint_torque_limit"])}"')
        attrs.append(f'damping="{j["damping"]:.9g}"')
        attrs.append(f'armature="{j["armature"]:.9g}"')
        w(f"{ind}<joint {' '.join(attrs)}/>")

    pel = bodies["cassie-pelvis"]
    w('<mujoco model="cassie">')
    w("  <!-- Generated by models/tools/build_cassie.py from Agility Robotics' Cassie parameters.")
    w("       Physical parameters from Agility Robotics' Cassie MuJoCo model (MIT licence), also in")
    w("       MuJoCo Menagerie's agility_cassie; this model file was written for amlip_qp from those")
    w("       parameters.  20 DOF: free pelvis + 7 hinges per leg.  See amlip_qp/models/README.md. -->")
    w('  <compiler angle="radian" autolimits="true" inertiafromgeom="false"/>')
    w('  <option timestep="0.0005" gravity="0 0 -9.81" integrator="implicitfast"/>')
    w("  <visual>")
    w('    <headlight ambient="0.4 0.4 0.4" diffuse="0.6 0.6 0.6" specular="0.1 0.1 0.1"/>')
    w('    <global offwidth="1280" offheight="720"/>')
    w("  </visual>")
    w("  <asset>")
    w(
        '    <texture name="sky" type="skybox" builtin="gradient" rgb1="0.45 0.6 0.8" rgb2="0.05 0.05 0.1" '
        'width="512" height="3072"/>'
    )
    w(
        '    <texture name="grid" type="2d" builtin="checker" rgb1="0.25 0.3 0.35" rgb2="0.35 0.4 0.45" '
        'width="512" height="512"/>'
    )
    w('    <material name="grid" texture="grid" texrepeat="1 1" texuniform="true"/>')
    w("  </asset>")
    w("  <worldbody>")
    w('    <light name="sun" pos="0 0 4" dir="0 0 -1" directional="true"/>')
    w(
        f'    <geom name="floor" type="plane" size="0 0 0.05" material="grid" contype="1" conaffinity="0" '
        f'condim="3" friction="{fmt(FRICTION)}" solref="{fmt(CONTACT_SOLREF)}" solimp="{fmt(CONTACT_SOLIMP)}"/>'
    )
    w(f'    <body name="cassie-pelvis" pos="{fmt(pel["pos_in_parent"])}" quat="{fmt(pel["quat_in_parent_wxyz"])}">')
    w('      <freejoint name="floating-base"/>')
    inertial("cassie-pelvis", "      ")
    g = pel["collision_capsules_etc"][0]
    w(
        f'      <geom name="pelvis-collision" type="sphere" size="{g["size"][0]:.9g}" pos="{fmt(g["pos"])}" '
        f'contype="0" conaffinity="1" condim="3" rgba="0.6 0.6 0.65 0.5" mass="0"/>'
    )
    w('      <site name="pelvis" pos="0 0 0" size="0.01"/>')
    # Side view from 3.5 m, 0.5 m above the pelvis, pitched down 15 deg towards mid-leg height.
    w('      <camera name="track" mode="trackcom" pos="0 -3.5 0.5" xyaxes="1 0 0 0 0.2588 0.9659" fovy="45"/>')
    for side in SIDES:
        ind = "      "
        opened = 0
        for short in LEG_JOINTS:
            name = f"{side}-{short}"
            b = bodies[name]
            w(f'{ind}<body name="{name}" pos="{fmt(b["pos_in_parent"])}" quat="{fmt(baked_quat(b))}">')
            opened += 1
            ind += "  "
            joint(b, ind)
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
                for tag, p in zip(("toe", "heel"), fp):
                    w(f'{ind}<site name="{side}-{tag}" pos="{fmt(p)}" size="0.005"/>')
                w(f'{ind}<site name="{side}-contact" pos="0 0 0" size="0.008"/>')
        for _ in range(opened):
            ind = ind[:-2]
            w(f"{ind}</body>")
    w("    </body>")
    w("  </worldbody>")
    w("  <tendon>")
    L0 = sum((bodies[f"left-{j}"]["joints"][0]["ref_rad"] or [0.0])[0] for j in ("knee", "tarsus"))
    for side in SIDES:
        w(
            f'    <fixed name="{side}-achilles" stiffness="{HEEL_SPRING_STIFFNESS:.9g}" '
            f'springlength="{L0:.9g}" damping="{COUPLING_DAMPING:.9g}">'
        )
        w(f'      <joint joint="{side}-knee" coef="1"/>')
        w(f'      <joint joint="{side}-tarsus" coef="1"/>')
        w("    </fixed>")
    w("  </tendon>")
    w("  <actuator>")
    for side in SIDES:
        for short in ("hip-roll", "hip-yaw", "hip-pitch", "knee", "foot"):
            a = act[f"{side}-{short}"]
            w(
                f'    <motor name="{a["name"]}" joint="{a["joint"]}" gear="{a["gear"]:.9g}" '
                f'ctrllimited="true" ctrlrange="{fmt(a["motor_torque_limit"])}"/>'
            )
    w("  </actuator>")
    if keyframe_qpos is not None:
        w("  <keyframe>")
        w(f'    <key name="stand" qpos="{fmt(keyframe_qpos, 12)}"/>')
        w("  </keyframe>")
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
    d = mujoco.MjData(m)
    q = standing_qpos21(params)
    info = {"sheet_base_z": float(q[2])}

    def blade(side):
        mujoco.mj_kinematics(m, d)
        toe = d.site(f"{side}-toe").xpos.copy()
        heel = d.site(f"{side}-heel").xpos.copy()
        return toe, heel

    for side in SIDES:
        adr = m.jnt_qposadr[m.joint(f"{side}-foot").id]
        d.qpos[:] = q
        toe, heel = blade(side)
        info[f"{side}_sheet_blade_dz"] = float(toe[2] - heel[2])
        info[f"{side}_sheet_foot"] = float(q[adr])
        for _ in range(20):
            d.qpos[:] = q
            toe, heel = blade(side)
            f0 = toe[2] - heel[2]
            if abs(f0) < 1e-13:
                break
            h = 1e-7
            d.qpos[:] = q
            d.qpos[adr] += h
            toe1, heel1 = blade(side)
            q[adr] -= f0 / ((toe1[2] - heel1[2] - f0) / h)
        info[f"{side}_foot"] = float(q[adr])
    d.qpos[:] = q
    mujoco.mj_kinematics(m, d)
    zmin = min(d.site(f"{s}-{t}").xpos[2] for s in SIDES for t in ("toe", "heel"))
    q[2] += CONTACT_RADIUS - zmin
    info["base_z"] = float(q[2])
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
