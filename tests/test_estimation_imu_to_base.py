"""The IMU anywhere: the simulated IMU reads in its own axes what MuJoCo's own sensors at its site
read; ImuToBase turns a reading into the base IMU's (exactly on the base, and on another body when
given the accelerations the encoders lack); the EKF with G1's IMU on the torso against it on the
pelvis."""

import numpy as np
import pytest

from amlip_qp.estimation import make_base_estimator
from amlip_qp.estimation.imu_to_base import ImuToBase
from amlip_qp.estimation.rotations import quat_wxyz_to_rot, quat_xyzw_to_rot, rot_to_quat_xyzw
from amlip_qp.exceptions import InputError
from amlip_qp.messages import ImuReading, Measurement
from amlip_qp.profiles import ImuMount
from amlip_qp.robots import load_robot
from amlip_qp.robots.state import qvel_to_v
from amlip_qp.sim.scenarios.factory import build_simulation
from amlip_qp.sim.scenarios.named import get_scenario
from imu_cases import (
    G1_PELVIS_IMU_M,
    G1_TORSO_IMU_M,
    amlip_reading,
    imu_site_edit,
    profile_copy,
    reading,
    walk_samples,
)

CASSIE_IMU_M = (0.03155, 0.0, -0.07996)
#: A mounting turned about every axis: 2 rad about (1, 2, 3).
_AXIS = np.array([1.0, 2.0, 3.0]) / np.linalg.norm([1.0, 2.0, 3.0])
TURNED_WXYZ = (float(np.cos(1.0)), *(float(c) for c in np.sin(1.0) * _AXIS))
DT = 0.0005


@pytest.fixture(scope="module")
def cassie():
    return load_robot("cassie")


def _rot_error(quat_a_xyzw, quat_b_xyzw) -> float:
    return float(np.abs(quat_xyzw_to_rot(quat_a_xyzw) - quat_xyzw_to_rot(quat_b_xyzw)).max())


def _ekf_run(robot, mount, samples, readings):
    """The EKF's base estimates ``(q[:7], v[:6])`` of each sample, and its errors against the truth:
    the base velocity's RMS, m/s, and the largest orientation error, rad."""
    est = make_base_estimator("ekf", robot, DT, mount)
    qs, vs, dv, dr = [], [], [], []
    for s, imu in zip(samples, readings):
        q, v = s.q.copy(), s.v.copy()
        q[0:7], v[0:6] = np.nan, np.nan  # the robot's sensors: no base state
        m = est.fill(Measurement(s.t_s, q, v, s.contact, imu, False))
        qs.append(m.q[0:7].copy())
        vs.append(m.v[0:6].copy())
        dv.append(np.linalg.norm(m.v[0:3] - s.v[0:3]))
        E = quat_xyzw_to_rot(m.q[3:7]).T @ quat_xyzw_to_rot(s.q[3:7])
        dr.append(np.arccos(np.clip((np.trace(E) - 1.0) / 2.0, -1.0, 1.0)))
    return np.array(qs), np.array(vs), float(np.sqrt(np.mean(np.square(dv)))), float(max(dr))


def test_a_turned_mounting_on_the_base_is_turned_back_exactly_and_the_base_imu_is_passed_on(cassie):
    rng = np.random.default_rng(3)
    R_bi = quat_wxyz_to_rot(TURNED_WXYZ)
    R_wb = quat_xyzw_to_rot(rng.normal(size=4))
    base = ImuReading(rot_to_quat_xyzw(R_wb), rng.normal(size=3), rng.normal(size=3) + [0.0, 0.0, 9.81])
    turned = ImuReading(rot_to_quat_xyzw(R_wb @ R_bi), R_bi.T @ base.gyro_radps, R_bi.T @ base.accel_mps2)
    to_base = ImuToBase(cassie, ImuMount(pos_m=CASSIE_IMU_M, quat_wxyz=TURNED_WXYZ))
    assert to_base.on_base and not to_base.identity
    np.testing.assert_array_equal(to_base.point_in_base_m, CASSIE_IMU_M)
    out = to_base.reading(turned, cassie.q_stand, np.zeros(cassie.nv))
    assert _rot_error(out.quat_xyzw, base.quat_xyzw) < 1e-15
    np.testing.assert_allclose(out.gyro_radps, base.gyro_radps, rtol=0, atol=1e-15)
    np.testing.assert_allclose(out.accel_mps2, base.accel_mps2, rtol=0, atol=1e-14)
    identity = ImuToBase(cassie, ImuMount(pos_m=CASSIE_IMU_M))
    assert identity.identity and identity.reading(base, cassie.q_stand, np.zeros(cassie.nv)) is base


def test_bad_mountings_are_one_line_input_errors(cassie):
    with pytest.raises(InputError, match="IMU's body 'cassie-torso' is not in the model"):
        ImuToBase(cassie, ImuMount(body="cassie-torso"))
    with pytest.raises(InputError, match="pos_m must be 3 finite numbers"):
        ImuToBase(cassie, ImuMount(pos_m=(0.0, 0.0)))  # type: ignore[arg-type]
    with pytest.raises(InputError, match="quat_wxyz must be a unit quaternion"):
        ImuToBase(cassie, ImuMount(quat_wxyz=(1.0, 0.0, 0.1, 0.0)))
    with pytest.raises(InputError, match="free-floating base"):
        ImuToBase(load_robot("rabbit"), ImuMount())


def test_a_turned_mounting_on_the_base_reads_in_its_axes_and_gives_the_identity_mountings_estimate(cassie, tmp_path):
    w, x, y, z = TURNED_WXYZ
    path = profile_copy(tmp_path, "cassie", f"pos_m = {list(CASSIE_IMU_M)}\nquat_wxyz = [{w!r}, {x!r}, {y!r}, {z!r}]")
    robot = load_robot(path)
    sc = get_scenario("cassie-1mps").with_(robot=str(path))
    edit = imu_site_edit("test-base", "cassie-pelvis", CASSIE_IMU_M)
    sim = build_simulation(sc, "qp", sensors="ideal", estimator="truth", plant_edits=[edit])
    names = [f"{s}-{k}" for s in ("amlip-imu", "test-base") for k in ("quat", "gyro", "accel")]
    samples = walk_samples(sim, 0.6, names)
    R_bi = quat_wxyz_to_rot(TURNED_WXYZ)
    turned, base = [amlip_reading(s) for s in samples], [reading(s, "test-base") for s in samples]
    for t, b in zip(turned, base):  # the plant's IMU reads in its own (turned) axes
        assert _rot_error(t.quat_xyzw, rot_to_quat_xyzw(quat_xyzw_to_rot(b.quat_xyzw) @ R_bi)) < 1e-12
        np.testing.assert_allclose(t.gyro_radps, R_bi.T @ b.gyro_radps, rtol=0, atol=1e-12)
        np.testing.assert_allclose(t.accel_mps2, R_bi.T @ b.accel_mps2, rtol=0, atol=1e-11)
    q_t, v_t, err_t, _ = _ekf_run(robot, robot.imu_mount, samples, turned)
    q_b, v_b, err_b, _ = _ekf_run(robot, ImuMount(pos_m=CASSIE_IMU_M), samples, base)
    # measured: 2e-16 (pose) and 1.3e-15 (twist) apart over 1202 ticks; the estimate itself is 0.009 m/s off
    assert np.abs(q_t - q_b).max() < 1e-12 and np.abs(v_t - v_b).max() < 1e-12
    assert abs(err_t - err_b) < 1e-12 and err_b < 0.05


@pytest.fixture(scope="module")
def g1_torso(tmp_path_factory):
    """G1 with the IMU on its torso (the file's ``imu_in_torso`` site), 2.5 s of the 1 m/s walk on the
    true base state, each tick with the plant's IMU, MuJoCo's own torso sensors, a test IMU at the
    base IMU's point and one at the file's ``imu_in_pelvis`` site."""
    path = profile_copy(tmp_path_factory.mktemp("g1"), "g1", f'body = "torso_link"\npos_m = {list(G1_TORSO_IMU_M)}')
    robot = load_robot(path)
    to_base = ImuToBase(robot, robot.imu_mount)
    point = to_base.point_in_base_m.tolist()
    edits = [imu_site_edit("test-base", "pelvis", point), imu_site_edit("test-pelvis", "pelvis", G1_PELVIS_IMU_M)]
    sc = get_scenario("g1-1mps").with_(robot=str(path))
    sim = build_simulation(sc, "qp", sensors="ideal", estimator="truth", plant_edits=edits)
    names = [f"{s}-{k}" for s in ("amlip-imu", "test-base", "test-pelvis") for k in ("quat", "gyro", "accel")]
    names += ["imu-torso-angular-velocity", "imu-torso-linear-acceleration"]  # the file's own sensors
    return robot, to_base, walk_samples(sim, 2.5, names)


def test_the_imu_on_the_torso_reads_what_mujocos_own_sensors_at_that_site_read(g1_torso):
    _, to_base, samples = g1_torso
    assert to_base.body == "torso_link" and not to_base.on_base
    own = [(s.sensors["imu-torso-angular-velocity"], s.sensors["imu-torso-linear-acceleration"]) for s in samples]
    gyro = max(np.abs(s.sensors["amlip-imu-gyro"] - g).max() for s, (g, _) in zip(samples, own))
    accel = max(np.abs(s.sensors["amlip-imu-accel"] - a).max() for s, (_, a) in zip(samples, own))
    assert gyro < 1e-12 and accel < 1e-10  # measured: 0 and 0
    assert max(np.abs(s.sensors["amlip-imu-accel"]).max() for s in samples) > 11.0  # a walk (12.9), not a stand


def test_the_torso_reading_turned_to_the_base_is_the_bases_truth(g1_torso):
    robot, to_base, samples = g1_torso
    gyro, rot, exact, fd, neglected = [], [], [], [], []
    prev = None
    for s in samples:
        imu, truth = amlip_reading(s), reading(s, "test-base")
        out = to_base.reading(imu, s.q, s.v)
        gyro.append(max(np.abs(out.gyro_radps - truth.gyro_radps).max(), np.abs(out.gyro_radps - s.v[3:6]).max()))
        rot.append(_rot_error(out.quat_xyzw, truth.quat_xyzw))
        neglected.append(np.linalg.norm(out.accel_mps2 - truth.accel_mps2))
        qdd = qvel_to_v(robot, s.q, s.qacc)[6:]
        full = to_base.reading(imu, s.q, s.v, joint_acc=qdd, base_ang_acc_radps2=s.qacc[3:6])
        exact.append(np.linalg.norm(full.accel_mps2 - truth.accel_mps2))
        if prev is not None:  # the estimator's: qddot from the joint velocities' last difference
            est = to_base.reading(imu, s.q, s.v, joint_acc=(s.v[6:] - prev.v[6:]) / DT)
            fd.append(np.linalg.norm(est.accel_mps2 - truth.accel_mps2))
        prev = s
    assert max(gyro) < 1e-9 and max(rot) < 1e-9  # measured: 1.2e-15, 1e-16
    assert max(exact) < 1e-9  # every term kept: measured 3e-14 m/s^2
    rms_fd, rms_neglected = np.sqrt(np.mean(np.square(fd))), np.sqrt(np.mean(np.square(neglected)))
    # measured on these 5001 ticks: 0.23 m/s^2 RMS (5.5 at most) with alpha x r neglected and qddot one tick
    # old; 1.20 m/s^2 RMS (12.4 at most) with qddot neglected as well
    assert rms_fd < 0.4 and rms_neglected > 3.0 * rms_fd, (rms_fd, rms_neglected)


def test_the_ekf_with_the_imu_on_the_torso_is_about_as_good_as_with_it_on_the_pelvis(g1_torso):
    robot, _, samples = g1_torso
    torso = [amlip_reading(s) for s in samples]
    pelvis = [reading(s, "test-pelvis") for s in samples]
    *_, v_torso, rot_torso = _ekf_run(robot, robot.imu_mount, samples, torso)
    *_, v_pelvis, rot_pelvis = _ekf_run(robot, ImuMount(pos_m=G1_PELVIS_IMU_M), samples, pelvis)
    # measured: base velocity RMS 0.0135 (torso) against 0.0132 m/s (pelvis); largest orientation error
    # 0.0025 against 0.0029 rad
    assert v_torso < v_pelvis + 0.002 and v_torso < 0.03, (v_torso, v_pelvis)
    assert rot_torso < rot_pelvis + 0.002 and rot_torso < 0.01, (rot_torso, rot_pelvis)


def test_the_torso_imu_scenario_puts_the_plants_imu_and_the_ekfs_on_the_torso():
    import mujoco

    sim = build_simulation(get_scenario("g1-1mps-ekf-torso-imu"), "qp")
    m = sim.plant.model
    site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "amlip-imu")
    assert mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, int(m.site_bodyid[site])) == "torso_link"
    np.testing.assert_allclose(m.site_pos[site], G1_TORSO_IMU_M, rtol=0, atol=1e-12)
    to_base = sim.controller.base_estimator.to_base
    assert to_base.body == "torso_link" and not to_base.on_base
    nominal = build_simulation(get_scenario("g1-1mps-ekf"), "qp")
    assert nominal.controller.base_estimator.to_base.identity  # G1's pelvis IMU: on the base, its axes
