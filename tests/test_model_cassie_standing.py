"""The Cassie MJCF stands: a PD hold about the stand keyframe with the static feedforward keeps
the robot up for one second, both blades on the floor."""

from __future__ import annotations

import mujoco
import numpy as np

from cassie_sheet import (
    CONTACT_RADIUS,
    JOINTS,
    MODEL,
    MOTORS,
    SIDES,
)


def static_feedforward(m, d):
    """Motor torques (joint side) that hold the current pose statically on four contact points.

    Solves qfrc_bias - qfrc_passive = S tau + Jc^T f by least squares with torques on all 14
    leg joints; the tarsus torque is then supplied by the achilles tendon, whose reaction acts on
    the knee with the same sign, so the knee motor carries tau_knee - tau_tarsus.
    """
    dofs = [m.jnt_dofadr[m.joint(n).id] for n in JOINTS]
    S = np.zeros((m.nv, len(JOINTS)))
    S[dofs, range(len(JOINTS))] = 1.0
    jacs = []
    for s in SIDES:
        for t in ("toe", "heel"):
            jp = np.zeros((3, m.nv))
            mujoco.mj_jacSite(m, d, jp, None, m.site(f"{s}-{t}").id)
            jacs.append(jp)
    A = np.hstack([S, np.vstack(jacs).T])
    x = np.linalg.lstsq(A, d.qfrc_bias - d.qfrc_passive, rcond=None)[0]
    tau = dict(zip(JOINTS, x[: len(JOINTS)]))
    out = []
    for name in MOTORS:
        t = tau[name]
        if name.endswith("knee"):
            t -= tau[name.replace("knee", "tarsus")]
        out.append(t)
    return np.array(out)


def test_stands_for_one_second_with_pd_hold():
    m = mujoco.MjModel.from_xml_path(str(MODEL))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("stand").id)
    mujoco.mj_forward(m, d)
    q0 = d.qpos.copy()
    ff = static_feedforward(m, d)
    qa = np.array([m.jnt_qposadr[m.actuator_trnid[i, 0]] for i in range(m.nu)])
    va = np.array([m.jnt_dofadr[m.actuator_trnid[i, 0]] for i in range(m.nu)])
    gear = m.actuator_gear[:, 0]
    kp, kd = 400.0, 20.0
    z = []
    for _ in range(int(round(1.0 / m.opt.timestep))):
        tau = kp * (q0[qa] - d.qpos[qa]) - kd * d.qvel[va] + ff
        d.ctrl[:] = np.clip(tau / gear, m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1])
        mujoco.mj_step(m, d)
        z.append(d.qpos[2])
    z = np.array(z) - q0[2]
    assert np.all(np.isfinite(d.qpos))
    assert np.abs(z).max() < 0.05
    assert np.linalg.norm(d.qpos[:2] - q0[:2]) < 0.10
    up = d.xmat[m.body("cassie-pelvis").id].reshape(3, 3)[:, 2]
    assert up[2] > np.cos(np.radians(10))
    # Both blades still on the floor, penetration below 1 mm.
    heights = [d.site(f"{s}-{t}").xpos[2] for s in SIDES for t in ("toe", "heel")]
    np.testing.assert_allclose(heights, CONTACT_RADIUS, atol=1e-3)
    assert d.ncon == 4
    assert min(d.contact.dist[: d.ncon]) > -1e-3
