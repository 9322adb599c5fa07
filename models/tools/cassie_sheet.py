"""Shared code of the Cassie model generators: the parameter sheet, rotations, MJCF fragments.

Used by ``build_cassie.py`` (``cassie.xml``, 20 DOF, lumped) and
``build_cassie_closed_chain.py`` (``cassie-closed-chain.xml``, the sheet's full
tree with its loop closures).  The sheet (``cassie_parameters.json``) holds
Agility Robotics' Cassie MuJoCo model parameters (MIT licence).

Conventions kept by both generators:

- hinge ``ref`` is baked into the body frames (:func:`baked_quat`), so qpos
  keeps Agility's angle zeros and no ``ref`` attribute is written;
- the scene (floor, light, sky, camera), the contact softness and the foot
  sites (``{side}-toe``, ``{side}-heel``, ``{side}-contact``) are the same.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
MODELS_DIR = REPO / "amlip_qp" / "models"
#: The parameter sheet vendored in the repository (models/reference/, MIT licence, credits in NOTICE).
DEFAULT_PARAMS = REPO / "models" / "reference" / "cassie_parameters.json"

SIDES = ("left", "right")
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
#: Motors per leg, in actuator order.
MOTORS = ("hip-roll", "hip-yaw", "hip-pitch", "knee", "foot")
#: Radius of the toe and heel contact spheres (m); equal to the sheet's foot capsule radius.
CONTACT_RADIUS = 0.02
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


def hinge_ref(joint):
    """The sheet's ``ref`` (rad) of a joint; 0 when it has none."""
    return (joint.get("ref_rad") or [0.0])[0]


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


def sheet_reference_config(params):
    """The sheet model's own qpos0 as a joint dict: hinges at ``ref``, ball joints at identity.

    MuJoCo computes a ``connect``'s second anchor in this configuration, so the sheet's loop
    closures are exactly closed there.
    """
    out = {}
    for b in params["bodies"]:
        for j in b["joints"]:
            if j["type"] == "ball":
                out[j["name"]] = np.array([1.0, 0.0, 0.0, 0.0])
            elif j["type"] == "hinge":
                out[j["name"]] = hinge_ref(j)
    return out


def body_inertia_tensor(b):
    """(mass, com, 3x3 inertia about the CoM) of a sheet body, in its body frame."""
    R = quat_to_mat(b["inertia_frame_quat_wxyz"])
    I = R @ np.diag(b["principal_inertia"]) @ R.T
    return float(b["mass"]), np.array(b["com"], float), I


def child_pose_at_standing(b, standing):
    """Pose (p, R) of sheet body ``b`` in its parent's frame at the configuration ``standing``.

    ``standing`` maps joint names to values (a hinge angle in rad, a ball quaternion wxyz).
    """
    p = np.array(b["pos_in_parent"], float)
    R = quat_to_mat(b["quat_in_parent_wxyz"])
    if not b["joints"]:
        return p, R
    j = b["joints"][0]
    if j["type"] == "ball":
        Rj = quat_to_mat(standing[j["name"]])
    elif j["type"] == "hinge":
        Rj = axis_angle_mat(j["axis"], standing[j["name"]] - hinge_ref(j))
    else:
        raise ValueError(f"cannot lump a body with a {j['type']} joint: {b['name']}")
    # Joints sit at the body origin in the sheet, so the rotation is about it.
    return p, R @ Rj


def pose_in_ancestor(bodies, name, ancestor, config):
    """(p, R) of sheet body ``name`` in the frame of its ancestor body at joint config ``config``."""
    chain = []
    cur = bodies[name]
    while cur["name"] != ancestor:
        chain.append(cur)
        cur = bodies[cur["parent"]]
    p, R = np.zeros(3), np.eye(3)
    for link in reversed(chain):
        pl, Rl = child_pose_at_standing(link, config)
        p, R = p + R @ pl, R @ Rl
    return p, R


def standing_pose(params, name):
    """(p, R) of a sheet body in the pelvis frame at the sheet's standing configuration."""
    return pose_in_ancestor(bodies_by_name(params), name, "cassie-pelvis", sheet_standing(params))


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
    ref = hinge_ref(j) if j and j["type"] == "hinge" else 0.0
    if ref == 0.0:
        return q
    return mat_to_quat(quat_to_mat(q) @ axis_angle_mat(j["axis"], -ref))


def fmt(v, digits=9):
    return " ".join(f"{float(x):.{digits}g}" for x in np.atleast_1d(v))


# ---------------------------------------------------------------- MJCF fragments
def scene_lines(model_name, comment):
    """``<mujoco>`` opening, compiler, options, visual, assets, and the world's light and floor.

    ``comment`` is the header comment's lines (without the comment markers' indentation).
    """
    lines = [f'<mujoco model="{model_name}">']
    lines.append("  <!-- " + comment[0])
    lines += ["       " + c for c in comment[1:-1]]
    lines.append("       " + comment[-1] + " -->")
    lines += [
        '  <compiler angle="radian" autolimits="true" inertiafromgeom="false"/>',
        '  <option timestep="0.0005" gravity="0 0 -9.81" integrator="implicitfast"/>',
        "  <visual>",
        '    <headlight ambient="0.4 0.4 0.4" diffuse="0.6 0.6 0.6" specular="0.1 0.1 0.1"/>',
        '    <global offwidth="1280" offheight="720"/>',
        "  </visual>",
        "  <asset>",
        '    <texture name="sky" type="skybox" builtin="gradient" rgb1="0.45 0.6 0.8" rgb2="0.05 0.05 0.1" '
        'width="512" height="3072"/>',
        '    <texture name="grid" type="2d" builtin="checker" rgb1="0.25 0.3 0.35" rgb2="0.35 0.4 0.45" '
        'width="512" height="512"/>',
        '    <material name="grid" texture="grid" texrepeat="1 1" texuniform="true"/>',
        "  </asset>",
        "  <worldbody>",
        '    <light name="sun" pos="0 0 4" dir="0 0 -1" directional="true"/>',
        f'    <geom name="floor" type="plane" size="0 0 0.05" material="grid" contype="1" conaffinity="0" '
        f'condim="3" friction="{fmt(FRICTION)}" solref="{fmt(CONTACT_SOLREF)}" solimp="{fmt(CONTACT_SOLIMP)}"/>',
    ]
    return lines


def pelvis_open_lines(pel, inertial_line):
    """The pelvis body's opening: free joint, inertial, collision sphere, site and tracking camera."""
    g = pel["collision_capsules_etc"][0]
    return [
        f'    <body name="cassie-pelvis" pos="{fmt(pel["pos_in_parent"])}" quat="{fmt(pel["quat_in_parent_wxyz"])}">',
        '      <freejoint name="floating-base"/>',
        inertial_line,
        f'      <geom name="pelvis-collision" type="sphere" size="{g["size"][0]:.9g}" pos="{fmt(g["pos"])}" '
        f'contype="0" conaffinity="1" condim="3" rgba="0.6 0.6 0.65 0.5" mass="0"/>',
        '      <site name="pelvis" pos="0 0 0" size="0.01"/>',
        # Side view from 3.5 m, 0.5 m above the pelvis, pitched down 15 deg towards mid-leg height.
        '      <camera name="track" mode="trackcom" pos="0 -3.5 0.5" xyaxes="1 0 0 0 0.2588 0.9659" fovy="45"/>',
    ]


def hinge_joint_line(j, act, ind):
    """A hinge ``<joint>``: the sheet's range, stiffness (shin: :data:`SHIN_STIFFNESS`), damping,
    armature, and the motor's joint-side torque limit as ``actuatorfrcrange``.

    ``act`` maps joint names to the sheet's actuator entries.
    """
    short = j["name"].split("-", 1)[1]
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
    return f"{ind}<joint {' '.join(attrs)}/>"


def foot_site_lines(side, fp, ind):
    """The foot's toe and heel sites (sphere centres ``fp``) and its ``{side}-contact`` site."""
    lines = [f'{ind}<site name="{side}-{tag}" pos="{fmt(p)}" size="0.005"/>' for tag, p in zip(("toe", "heel"), fp)]
    lines.append(f'{ind}<site name="{side}-contact" pos="0 0 0" size="0.008"/>')
    return lines


def actuator_lines(act):
    """``<actuator>``: one motor per sheet actuator, left then right, in :data:`MOTORS` order."""
    lines = ["  <actuator>"]
    for side in SIDES:
        for short in MOTORS:
            a = act[f"{side}-{short}"]
            lines.append(
                f'    <motor name="{a["name"]}" joint="{a["joint"]}" gear="{a["gear"]:.9g}" '
                f'ctrllimited="true" ctrlrange="{fmt(a["motor_torque_limit"])}"/>'
            )
    lines.append("  </actuator>")
    return lines


def keyframe_lines(qpos):
    return ["  <keyframe>", f'    <key name="stand" qpos="{fmt(qpos, 12)}"/>', "  </keyframe>"]


# ---------------------------------------------------------------- keyframe
def level_feet_and_ground(m, q, info, close=None):
    """Level both blades (1-D Newton on each ``{side}-foot`` angle), then set the base height.

    ``m`` is a compiled MuJoCo model with the ``{side}-toe``/``{side}-heel`` sites; ``q`` its
    qpos (modified in place).  After levelling, ``close(q)`` (if given) may move other joints
    (it must not move the blades).  The base z is then set so the lowest toe/heel centre is
    :data:`CONTACT_RADIUS` above z = 0.  Records the sheet's and the levelled foot angles and
    the base height in ``info``.
    """
    import mujoco

    d = mujoco.MjData(m)

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
    if close is not None:
        close(q)
    d.qpos[:] = q
    mujoco.mj_kinematics(m, d)
    zmin = min(d.site(f"{s}-{t}").xpos[2] for s in SIDES for t in ("toe", "heel"))
    q[2] += CONTACT_RADIUS - zmin
    info["base_z"] = float(q[2])
    return q
