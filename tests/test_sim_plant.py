"""The plant: a model other than the controller's, mapped to it by name.

The variants of cassie.xml are built with ``mujoco.MjSpec`` (an extra passive
joint, a base floated by slide and ball joints, a missing actuator, a renamed
joint) and written to files, as a user's plant would be.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from amlip_qp.exceptions import InputError, ModelFileError, PlantMismatchError
from amlip_qp.paths import MODELS_DIR
from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.world.imu_site import IMU_SITE
from amlip_qp.sim.world.plant import Plant
from amlip_qp.sim.world.plant_loader import load_plant
from plant_cases import CASSIE_XML, extra_joint_spec, slide_ball_spec, write_plant


@pytest.fixture(scope="module")
def cassie():
    return factory.load("cassie")


def test_the_default_plant_is_the_robots_own_model_with_an_imu(cassie):
    plant = load_plant("cassie", cassie)
    assert plant.free_base and plant.name == "cassie"
    m0 = cassie.mj_model
    assert (plant.model.nq, plant.model.nv, plant.model.nu) == (m0.nq, m0.nv, m0.nu)
    assert plant.model.nsite == m0.nsite + 1 and plant.model.nsensor == 3 + 2  # the IMU's, the feet's contacts
    site = mujoco.mj_name2id(plant.model, mujoco.mjtObj.mjOBJ_SITE, IMU_SITE)
    assert plant.model.site_bodyid[site] == plant.base_body_id
    assert np.allclose(plant.model.site_pos[site], (0.03155, 0.0, -0.07996))
    assert np.array_equal(plant.gear, cassie.actuated.gear)
    assert np.array_equal(plant.ctrl_range, cassie.actuated.ctrl_range)


def test_the_imu_changes_no_trajectory(cassie):
    """The IMU site and sensors and the contact sensors only read the state: 200 steps with random controls
    are bit-identical."""
    plant = load_plant("cassie", cassie)
    rng = np.random.default_rng(3)
    ctrls = rng.uniform(-1.0, 1.0, (200, cassie.nu))
    d0, d1 = cassie.new_mj_data("stand"), plant.new_data("stand")
    for u in ctrls:
        d0.ctrl[:] = u
        plant.apply_ctrl(d1, u)
        mujoco.mj_step(cassie.mj_model, d0)
        mujoco.mj_step(plant.model, d1)
    assert np.array_equal(d0.qpos, d1.qpos) and np.array_equal(d0.qvel, d1.qvel)


def test_read_state_of_the_default_plant_is_the_state_conversion(cassie):
    from amlip_qp.robots import state as S

    plant = load_plant("cassie", cassie)
    d = plant.new_data("stand")
    d.qvel[:] = np.linspace(-0.5, 0.5, d.qvel.size)
    q, v = plant.read_state(d)
    q0, v0 = S.mj_to_pin(cassie.state_map, d.qpos, d.qvel)
    assert np.array_equal(q, q0) and np.array_equal(v, v0)


def test_a_slide_and_ball_base_gives_the_same_state_as_the_free_joint(cassie, tmp_path):
    """The same motion on both plants (same controls): the same (q, v), to integration rounding."""
    free = load_plant("cassie", cassie)
    slide = load_plant(write_plant(slide_ball_spec(), tmp_path / "slide_ball.xml"), cassie)
    assert not slide.free_base and slide.model.nv == free.model.nv
    df, ds = free.new_data("stand"), slide.new_data("stand")
    qf, vf = free.read_state(df)
    qs, vs = slide.read_state(ds)
    assert np.allclose(qf, qs, atol=1e-12) and np.allclose(vf, vs, atol=1e-12)
    rng = np.random.default_rng(0)
    worst_q = worst_v = 0.0
    for _ in range(300):  # 0.15 s of tumbling with random motor torques
        u = rng.uniform(-2.0, 2.0, cassie.nu)
        free.apply_ctrl(df, u)
        slide.apply_ctrl(ds, u)
        mujoco.mj_step(free.model, df)
        mujoco.mj_step(slide.model, ds)
        qf, vf = free.read_state(df)
        qs, vs = slide.read_state(ds)
        worst_q = max(worst_q, float(np.max(np.abs(qf - qs))))
        worst_v = max(worst_v, float(np.max(np.abs(vf - vs))))
    assert np.linalg.norm(vf[:6]) > 0.05  # the base did move
    # Same physics, different coordinates: only the integrators' rounding separates them.
    assert worst_q < 2e-5 and worst_v < 1e-3


def test_an_extra_passive_joint_is_mapped_by_name(cassie, tmp_path):
    # (MjSpec.to_xml leaves out the new body's inertial: put it back in the file)
    inertial = ('<joint name="left-toe-flex"', '<inertial pos="0 0 0" mass="0.01" diaginertia="1e-6 1e-6 1e-6"/>')
    plant = load_plant(write_plant(extra_joint_spec(), tmp_path / "extra.xml", inertial), cassie)
    assert plant.model.nq == cassie.mj_model.nq + 1 and plant.free_base
    d = plant.new_data("stand")
    extra = mujoco.mj_name2id(plant.model, mujoco.mjtObj.mjOBJ_JOINT, "left-toe-flex")
    d.qpos[plant.model.jnt_qposadr[extra]] = 0.3  # not a controller joint: invisible to it
    d.qvel[:] = 0.1
    q, v = plant.read_state(d)
    assert np.array_equal(q, cassie.q_stand) or np.allclose(q, cassie.q_stand, atol=1e-12)
    # the right leg sits after the new joint in the plant, before it nowhere in the controller
    right_knee = cassie.state_map.joint_pin_v["right-knee"]
    assert v[right_knee] == pytest.approx(0.1)
    # actuators: the controller's order, whatever the plant's ids
    tau = np.arange(1.0, cassie.nu + 1.0)
    plant.write_ctrl(d, tau)
    assert np.allclose(d.ctrl[plant.actuator_ids] * plant.gear, np.clip(tau, *cassie.actuated.torque_limit_Nm.T))


def test_actuators_are_written_by_name_in_any_plant_order(cassie, tmp_path):
    spec = mujoco.MjSpec.from_file(str(CASSIE_XML))
    names = [a.name for a in spec.actuators]
    for a in list(spec.actuators):
        spec.delete(a)
    for n in reversed(names):  # the plant lists them backwards
        spec.add_actuator(name=n, target=n, trntype=mujoco.mjtTrn.mjTRN_JOINT, gear=[10, 0, 0, 0, 0, 0])
    plant = load_plant(write_plant(spec, tmp_path / "reversed.xml"), cassie)
    assert list(plant.actuator_ids) == list(range(cassie.nu - 1, -1, -1))
    d = plant.new_data("stand")
    plant.write_ctrl(d, np.arange(cassie.nu, dtype=float))
    assert np.allclose(d.ctrl, np.arange(cassie.nu)[::-1] / 10.0)  # unlimited controls: not clipped


def test_a_missing_actuator_and_a_renamed_joint_are_named_in_one_line(cassie, tmp_path):
    spec = mujoco.MjSpec.from_file(str(CASSIE_XML))
    spec.delete(spec.actuator("left-knee"))
    spec.joint("right-shin").name = "right-knee-spring"
    with pytest.raises(PlantMismatchError) as err:
        load_plant(write_plant(spec, tmp_path / "broken.xml"), cassie)
    msg = str(err.value)
    assert "\n" not in msg and "actuator 'left-knee'" in msg and "joint 'right-shin'" in msg
    assert isinstance(err.value, InputError)


def test_a_missing_base_body_and_another_robot(cassie):
    with pytest.raises(PlantMismatchError, match="body 'cassie-pelvis'.*actuator 'left-hip-roll'"):
        load_plant(str(MODELS_DIR / "rabbit.xml"), cassie)


def test_a_welded_base_is_a_mismatch(cassie, tmp_path):
    spec = mujoco.MjSpec.from_file(str(CASSIE_XML))
    spec.delete(spec.joint("floating-base"))
    spec.delete(spec.key("stand"))
    with pytest.raises(PlantMismatchError, match="joints floating body 'cassie-pelvis'"):
        load_plant(write_plant(spec, tmp_path / "welded.xml"), cassie)


def test_names_paths_and_edits(cassie, tmp_path):
    with pytest.raises(InputError, match="unknown plant 'moon' for cassie: known plants are cassie, cassie-closed"):
        load_plant("moon", cassie)
    with pytest.raises(ModelFileError):
        load_plant(str(tmp_path / "none.xml"), cassie)
    seen = []

    def heavier(spec):
        seen.append(spec)
        spec.body("cassie-pelvis").mass = 20.0

    plant = load_plant("cassie", cassie, edits=[heavier])
    assert len(seen) == 1 and plant.model.body_mass[plant.base_body_id] == 20.0
    with pytest.raises(InputError, match="no keyframe named 'crouch'"):
        plant.new_data("crouch")


def test_rabbit_plant_maps_its_planar_root_by_name():
    rabbit = factory.load("rabbit")
    plant = load_plant("rabbit", rabbit)
    d = plant.new_data("stand")
    q, v = plant.read_state(d)
    assert np.array_equal(q, rabbit.q_stand) or np.allclose(q, rabbit.q_stand, atol=1e-12)
    assert plant.foot_normal_forces_N(d).keys() == {"left", "right"}


def test_contact_forces_are_mujocos_summed_per_foot_and_controls_are_clipped(cassie):
    plant = load_plant("cassie", cassie)
    data = plant.new_data("stand")
    for _ in range(200):  # settle on the floor: both feet in contact
        mujoco.mj_step(plant.model, data)
    assert data.ncon >= 2
    expected = dict.fromkeys(plant.foot_body_ids, 0.0)
    force6 = np.zeros(6)
    for i in range(data.ncon):  # the definition, contact by contact
        con = data.contact[i]
        bodies = {int(plant.model.geom_bodyid[con.geom1]), int(plant.model.geom_bodyid[con.geom2])}
        for side, body in plant.foot_body_ids.items():
            if bodies == {body, 0}:
                mujoco.mj_contactForce(plant.model, data, i, force6)
                expected[side] += abs(force6[0])
    got = plant.foot_normal_forces_N(data)
    assert got == expected and min(got.values()) > 10.0  # both feet on the floor
    tau = np.array([1e4, -1e4, np.nan, 0.5, -0.5, 3.0, -3.0, 1e-3, 0.0, 2.0])
    assert np.array_equal(plant.ctrl_from_tau(tau), np.clip(tau / plant.gear, *plant.ctrl_range.T), equal_nan=True)


def test_the_array_reader_is_read_state_with_the_root_row(cassie, tmp_path):
    """Bound once, it follows the data (a free-joint plant and a slide-and-ball one); new arrays each call."""
    for plant in (
        load_plant("cassie", cassie),
        load_plant(write_plant(slide_ball_spec(), tmp_path / "sb.xml"), cassie),
    ):
        d = plant.new_data("stand")
        read = plant.array_reader(d)
        rng = np.random.default_rng(5)
        for _ in range(20):
            plant.write_ctrl(d, rng.uniform(-50.0, 50.0, cassie.nu))
            mujoco.mj_step(plant.model, d)
            q_ref, v_ref = plant.read_state(d)
            qpos_list = d.qpos.tolist()
            for q, v, root in (read(qpos_list), read(qpos_list, sum(qpos_list))):
                assert q.tobytes() == q_ref.tobytes() and v.tobytes() == v_ref.tobytes()
                assert root == q_ref[:7].tolist() + v_ref[:6].tolist()
                assert not np.shares_memory(q, d.qpos) and not np.shares_memory(v, d.qvel)


def test_the_ctrl_writer_writes_what_write_ctrl_does(cassie, tmp_path):
    """Bit for bit, clipped (NaN kept), in the plant's order or not."""
    spec = mujoco.MjSpec.from_file(str(CASSIE_XML))
    names = [a.name for a in spec.actuators]
    for a in list(spec.actuators):
        spec.delete(a)
    for n in reversed(names):
        spec.add_actuator(name=n, target=n, trntype=mujoco.mjtTrn.mjTRN_JOINT, gear=[10, 0, 0, 0, 0, 0])
    reversed_plant = load_plant(write_plant(spec, tmp_path / "reversed.xml"), cassie)
    rng = np.random.default_rng(2)
    for plant in (load_plant("cassie", cassie), reversed_plant):
        d0, d1 = plant.new_data("stand"), plant.new_data("stand")
        write = plant.ctrl_writer(d1)
        for scale in (1.0, 100.0, 1e4):
            tau = rng.normal(0.0, scale, cassie.nu)
            tau[3] = np.nan
            plant.write_ctrl(d0, tau)
            write(tau)
            assert d0.ctrl.tobytes() == d1.ctrl.tobytes()
        assert np.isnan(d1.ctrl[plant.actuator_ids[3]])
        if np.all(np.isfinite(plant.ctrl_range)):  # the bundled model's limits: big torques sit on them
            ctrl, (lo, hi) = d1.ctrl[plant.actuator_ids], plant.ctrl_range.T
            assert np.any(ctrl == lo) and np.any(ctrl == hi) and not np.any((ctrl < lo) | (ctrl > hi))


def test_contact_switches_are_the_summed_forces_above_the_threshold(cassie):
    """Landing, standing and kicking: every switch is the full sum's, at thresholds around the forces."""
    plant = load_plant("cassie", cassie)
    data = plant.new_data("stand")
    data.qpos[2] += 0.05  # dropped from 5 cm: no contact, then a landing
    kept = {threshold: plant.contact_switcher(data, threshold) for threshold in (-1.0, 0.0, 5.0, 20.0, 100.0)}
    rng = np.random.default_rng(9)
    seen = set()
    for k in range(600):
        plant.write_ctrl(data, rng.uniform(-60.0, 60.0, cassie.nu) if k > 300 else np.zeros(cassie.nu))
        mujoco.mj_step(plant.model, data)
        forces = plant.foot_normal_forces_N(data)
        for threshold, switches in kept.items():  # bound before the first step: they follow the data
            got = switches()
            assert got == {side: f > threshold for side, f in forces.items()}
            assert all(type(on) is bool for on in got.values())
            seen.add(tuple(got.values()))
        for threshold in forces.values():  # at the forces themselves
            assert plant.contact_switcher(data, threshold)() == {side: f > threshold for side, f in forces.items()}
    assert {(False, False), (True, True)} <= seen and len(seen) >= 3


def test_a_position_servo_is_not_a_torque_motor(cassie):
    spec = mujoco.MjSpec.from_file(str(CASSIE_XML))
    knee = spec.actuator("left-knee")
    knee.set_to_position(kp=100.0)  # gain 100, bias -100 q: ctrl would be a joint angle, not tau / gear
    with pytest.raises(PlantMismatchError) as err:
        Plant(spec.compile(), cassie, "servo")
    assert str(err.value).startswith("plant servo: actuator 'left-knee' (of 1) is not a torque motor")
    spec = mujoco.MjSpec.from_file(str(CASSIE_XML))
    spec.actuator("right-knee").gainprm[0] = 2.0  # a motor of gain 2 would apply twice the torque
    with pytest.raises(PlantMismatchError, match="actuator 'right-knee' .* ctrl = tau / gear"):
        Plant(spec.compile(), cassie, "gain")


def test_plant_steps_per_control_tick_are_a_whole_number(cassie):
    plant = load_plant("cassie", cassie)  # 0.5 ms steps
    assert plant.substeps(0.0005) == 1 and plant.substeps(0.002) == 4
    for period in (0.00075, 0.0002):
        with pytest.raises(InputError, match=rf"control period \({period} s\) must be a whole multiple"):
            plant.substeps(period)
