"""The feet's MuJoCo contact sensors: the switches from them are the switches contact by contact, bit for bit."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.world import contact_sensors
from amlip_qp.sim.world.contact_sensors import CONTACT_SLOTS, contact_sensor_name, contact_spec_edit, sensor_switcher
from amlip_qp.sim.world.plant import Plant
from amlip_qp.sim.world.plant_loader import load_plant
from plant_cases import CASSIE_XML

THRESHOLDS = (-1.0, 0.0, 5.0, 20.0, 100.0)


@pytest.fixture(scope="module")
def cassie():
    return factory.load("cassie")


def _walk(plant, data, steps=600):
    """``data`` dropped from 5 cm (no contact, a landing), standing, then kicking: after each step."""
    data.qpos[2] += 0.05
    rng = np.random.default_rng(9)
    for k in range(steps):
        plant.write_ctrl(data, rng.uniform(-60.0, 60.0, plant.robot.nu) if k > 300 else np.zeros(plant.robot.nu))
        mujoco.mj_step(plant.model, data)
        yield data


def _definition(plant, data, threshold_N):
    """The switches by their definition: the full sums (contact by contact) above the threshold."""
    return lambda: {side: f > threshold_N for side, f in plant.foot_normal_forces_N(data).items()}


def _body_name(plant, side):
    return mujoco.mj_id2name(plant.model, mujoco.mjtObj.mjOBJ_BODY, plant.foot_body_ids[side])


@pytest.mark.parametrize("name", ["cassie", "cassie-closed-chain"])
def test_the_sensor_switches_are_the_switches_contact_by_contact(name):
    robot = factory.load("cassie")
    plant = load_plant(name, robot)
    data = plant.new_data("stand")
    fast = {
        t: sensor_switcher(plant.model, data, plant.foot_body_ids, t, _definition(plant, data, t)) for t in THRESHOLDS
    }
    assert all(f is not None for f in fast.values())
    kept = {t: plant.contact_switcher(data, t) for t in THRESHOLDS}  # the plant's: these
    seen = set()
    for _ in _walk(plant, data):  # bound once, they follow the data
        forces = plant.foot_normal_forces_N(data)
        for t in THRESHOLDS:
            got = fast[t]()
            assert got == kept[t]() == {side: f > t for side, f in forces.items()}
            assert list(got) == list(plant.foot_body_ids) and all(type(on) is bool for on in got.values())
            seen.add(tuple(got.values()))
        for t in forces.values():  # at the forces themselves: the sums are the same numbers
            f = sensor_switcher(plant.model, data, plant.foot_body_ids, t, _definition(plant, data, t))
            assert f is not None and f() == {side: x > t for side, x in forces.items()}
    assert {(False, False), (True, True)} <= seen and len(seen) >= 3


def test_more_contacts_than_slots_take_the_general_path(cassie, monkeypatch):
    """With one slot, a foot on two contacts: that tick is computed contact by contact."""
    monkeypatch.setattr(contact_sensors, "CONTACT_SLOTS", 1)
    plant = load_plant("cassie", cassie)
    data = plant.new_data("stand")
    calls = []
    general = _definition(plant, data, 20.0)

    def counted():
        calls.append(1)
        return general()

    fast = sensor_switcher(plant.model, data, plant.foot_body_ids, 20.0, counted)
    assert fast is not None
    for _ in _walk(plant, data, 400):
        assert fast() == general()
    assert calls  # some ticks had a foot on more than one contact
    assert len(calls) < 400  # and others not


def test_without_the_sensors_the_plant_switches_contact_by_contact(cassie, tmp_path):
    """A plant made from a model without them (or with another sensor of the name): the general path."""
    bare = Plant(cassie.mj_model, cassie, "bare")
    data = bare.new_data("stand")
    assert sensor_switcher(bare.model, data, bare.foot_body_ids, 20.0, dict) is None
    switches = bare.contact_switcher(data, 20.0)
    assert "sensor_switcher" not in switches.__qualname__
    for _ in _walk(bare, data, 350):
        assert switches() == _definition(bare, data, 20.0)()
    spec = mujoco.MjSpec.from_file(str(CASSIE_XML))
    sides = list(cassie.foot_sides)
    feet = {side: _body_name(bare, side) for side in sides}
    contact_spec_edit(spec, {sides[0]: feet[sides[1]], sides[1]: "world"})
    contact_spec_edit(spec, feet)  # no duplicates
    assert sum(s.name.startswith("amlip-contact-") for s in spec.sensors) == 2
    model = spec.compile()
    plant = Plant(model, cassie, "swapped feet")
    assert sensor_switcher(model, plant.new_data("stand"), plant.foot_body_ids, 20.0, dict) is None


def test_the_sensors_are_the_feet_against_the_world(cassie):
    plant = load_plant("cassie", cassie)
    m = plant.model
    for side, body in plant.foot_body_ids.items():
        sid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, contact_sensor_name(side))
        assert m.sensor_objid[sid] == body and m.sensor_refid[sid] == 0
        assert m.sensor_dim[sid] == 4 * CONTACT_SLOTS  # found, force (3) per slot


@pytest.mark.parametrize("setting", ["rk4", "sensors-disabled"])
def test_the_plant_switches_contact_by_contact_where_the_sensors_lag_or_sleep(cassie, setting):
    """RK4's later stages recompute the contacts but not the sensors, and disabled sensors read 0:
    the plant's switches then go contact by contact and stay the definition on every step."""
    plant = load_plant("cassie", cassie)
    if setting == "rk4":
        plant.model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    else:
        plant.model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_SENSOR
    data = plant.new_data("stand")
    assert sensor_switcher(plant.model, data, plant.foot_body_ids, 20.0, dict) is None
    switches = plant.contact_switcher(data, 20.0)
    seen = set()
    for _ in _walk(plant, data):
        got = switches()
        assert got == _definition(plant, data, 20.0)()
        seen.add(tuple(got.values()))
    assert (True, True) in seen and len(seen) >= 2
