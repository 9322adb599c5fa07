"""Tests of sim/world/plant_modifiers.py: each modifier's physics on compiled plants."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from amlip_qp.exceptions import InputError, MJCFError
from amlip_qp.paths import MODELS_DIR
from amlip_qp.sim.world.plant_modifiers import (
    PAYLOAD_BODY,
    FrictionEdit,
    MassScaleEdit,
    PlantModifiers,
    SpringScaleEdit,
    parse_payload,
)

#: (model file, base body) of the bundled plants.
PLANTS = {"cassie": ("cassie.xml", "cassie-pelvis"), "rabbit": ("rabbit.xml", "torso")}

#: Compiled-model arrays a modifier may change.
ARRAYS = (
    "body_mass",
    "body_inertia",
    "body_ipos",
    "body_iquat",
    "body_subtreemass",
    "jnt_stiffness",
    "tendon_stiffness",
    "geom_friction",
    "geom_contype",
    "geom_conaffinity",
    "pair_friction",
    "opt.o_friction",
)


def spec_of(robot: str) -> mujoco.MjSpec:
    return mujoco.MjSpec.from_file(str(MODELS_DIR / PLANTS[robot][0]))


def compiled(robot: str, edits=()) -> mujoco.MjModel:
    spec = spec_of(robot)
    for edit in edits:
        edit(spec)
    return spec.compile()


def modified(robot: str, mods: PlantModifiers) -> mujoco.MjModel:
    return compiled(robot, mods.spec_edits(PLANTS[robot][1]))


def array(model: mujoco.MjModel, name: str) -> np.ndarray:
    obj = model
    for part in name.split("."):
        obj = getattr(obj, part)
    return np.asarray(obj)


def stand(model: mujoco.MjModel) -> mujoco.MjData:
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, "stand"))
    mujoco.mj_forward(model, data)
    return data


# --- defaults -------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("robot", PLANTS)
def test_defaults_give_no_edit_and_the_same_model(robot):
    mods = PlantModifiers()
    assert mods.spec_edits(PLANTS[robot][1]) == []
    assert mods.describe() == {}
    reference = mujoco.MjModel.from_xml_path(str(MODELS_DIR / PLANTS[robot][0]))
    model = modified(robot, mods)
    assert (model.nbody, model.nq, model.nv, model.ngeom) == (
        reference.nbody,
        reference.nq,
        reference.nv,
        reference.ngeom,
    )
    for name in ARRAYS:
        np.testing.assert_array_equal(array(model, name), array(reference, name), err_msg=name)


@pytest.mark.parametrize("robot", PLANTS)
def test_unit_scale_edits_leave_the_model_unchanged(robot):
    """The edit machinery itself (reading and writing back every mass, inertia, stiffness) changes no number."""
    reference = compiled(robot)
    model = compiled(robot, [MassScaleEdit(1.0), SpringScaleEdit(1.0)])
    for name in ARRAYS:
        np.testing.assert_array_equal(array(model, name), array(reference, name), err_msg=name)


# --- mass scale -----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("robot", PLANTS)
@pytest.mark.parametrize("s", [0.8, 1.2])
def test_mass_scale_scales_every_mass_and_inertia(robot, s):
    ref, model = compiled(robot), modified(robot, PlantModifiers(mass_scale=s))
    assert model.body_mass.sum() == pytest.approx(s * ref.body_mass.sum(), rel=1e-12)
    np.testing.assert_allclose(model.body_mass, s * ref.body_mass, rtol=1e-12)
    np.testing.assert_allclose(model.body_inertia, s * ref.body_inertia, rtol=1e-9)
    np.testing.assert_allclose(model.body_ipos, ref.body_ipos, atol=1e-12)  # the CoMs stay
    np.testing.assert_allclose(model.dof_armature, ref.dof_armature)  # the rotors are the motors'
    # composite (subtree) inertias at the standing pose: 10-vectors (inertia, m*c, m) of every subtree
    d_ref, d = stand(ref), stand(model)
    assert np.abs(d_ref.crb).max() > 0
    np.testing.assert_allclose(d.crb, s * d_ref.crb, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(d.subtree_com, d_ref.subtree_com, atol=1e-12)


GEOM_MASS_XML = """
<mujoco>
  <compiler inertiafromgeom="auto"/>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="a" pos="0 0 1">
      <freejoint/>
      <geom type="box" size="0.1 0.2 0.3" density="500"/>
      <geom type="sphere" size="0.1" pos="0.2 0 0" mass="2"/>
      <body name="b" pos="0 0 -0.5">
        <joint type="hinge" axis="0 1 0"/>
        <inertial pos="0 0 -0.1" mass="1.5" fullinertia="0.02 0.03 0.04 0.001 0 0"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_mass_scale_of_geom_derived_and_full_inertias():
    def build(edits):
        spec = mujoco.MjSpec.from_string(GEOM_MASS_XML)
        for edit in edits:
            edit(spec)
        return spec.compile()

    ref, model = build([]), build([MassScaleEdit(1.3)])
    assert ref.body_mass[1] == pytest.approx(500 * 0.2 * 0.4 * 0.6 + 2.0)
    np.testing.assert_allclose(model.body_mass, 1.3 * ref.body_mass, rtol=1e-12)
    np.testing.assert_allclose(model.body_inertia, 1.3 * ref.body_inertia, rtol=1e-9)
    np.testing.assert_allclose(model.body_ipos, ref.body_ipos, atol=1e-12)
    np.testing.assert_allclose(model.body_iquat, ref.body_iquat, atol=1e-9)


# --- payload --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("robot", PLANTS)
def test_payload_adds_its_mass_and_moves_the_com_as_computed_by_hand(robot):
    kg, pos = 5.0, np.array([-0.1, 0.02, 0.05])
    ref, model = compiled(robot), modified(robot, PlantModifiers(payload_kg=kg, payload_pos_m=tuple(pos)))
    assert model.body_mass.sum() == pytest.approx(ref.body_mass.sum() + kg, abs=1e-12)
    assert (model.nq, model.nv, model.nu) == (ref.nq, ref.nv, ref.nu)  # welded: no new joint
    base = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, PLANTS[robot][1])
    payload = model.body(PAYLOAD_BODY)
    assert payload.parentid[0] == base and payload.mass[0] == kg
    # a 0.2 x 0.15 x 0.1 m uniform box
    np.testing.assert_allclose(
        payload.inertia, kg / 12 * np.array([0.15**2 + 0.1**2, 0.2**2 + 0.1**2, 0.2**2 + 0.15**2])
    )
    geom = model.geom(PAYLOAD_BODY)
    assert geom.contype[0] == 0 and geom.conaffinity[0] == 0
    # a tilted, turned base so the base-frame position matters
    qpos = stand(ref).qpos.copy()
    if robot == "cassie":
        qpos[3:7] = [np.cos(0.2), 0.3 * np.sin(0.2), 0.4 * np.sin(0.2), np.sqrt(0.75) * np.sin(0.2)]
    else:
        qpos[2] = 0.4  # root-pitch
    com = {}
    for name, m in (("ref", ref), ("mod", model)):
        d = mujoco.MjData(m)
        d.qpos[:] = qpos
        mujoco.mj_forward(m, d)
        com[name] = d.subtree_com[0].copy()
        if name == "ref":
            p_world = d.xpos[base] + d.xmat[base].reshape(3, 3) @ pos
            mass = m.body_mass.sum()
    expected = (mass * com["ref"] + kg * p_world) / (mass + kg)
    np.testing.assert_allclose(com["mod"], expected, atol=1e-12)
    assert np.linalg.norm(com["mod"] - com["ref"]) > 1e-3


def test_payload_comes_after_the_mass_scale():
    ref = compiled("cassie")
    model = modified("cassie", PlantModifiers(mass_scale=1.2, payload_kg=5.0))
    assert model.body_mass.sum() == pytest.approx(1.2 * ref.body_mass.sum() + 5.0, rel=1e-12)


def test_payload_needs_the_base_body():
    with pytest.raises(MJCFError, match="no body 'pelvis'"):
        compiled("cassie", PlantModifiers(payload_kg=1.0).spec_edits("pelvis"))


# --- springs --------------------------------------------------------------------------------------------------


def deflected_passive_force(model: mujoco.MjModel) -> np.ndarray:
    """qfrc_passive at rest (v = 0) with both shin springs and achilles tendons deflected."""
    data = stand(model)
    for side in ("left", "right"):
        data.qpos[model.joint(f"{side}-shin").qposadr[0]] += 0.05
        data.qpos[model.joint(f"{side}-tarsus").qposadr[0]] += 0.03
    data.qvel[:] = 0.0
    mujoco.mj_forward(model, data)
    return data.qfrc_passive.copy()


@pytest.mark.parametrize("s", [0.0, 0.5, 1.5])
def test_spring_scale_scales_the_passive_spring_torque(s):
    ref, model = compiled("cassie"), modified("cassie", PlantModifiers(spring_scale=s))
    f_ref, f = deflected_passive_force(ref), deflected_passive_force(model)
    shin, tarsus, knee = (ref.joint(f"left-{j}").dofadr[0] for j in ("shin", "tarsus", "knee"))
    assert abs(f_ref[shin]) > 50.0  # 1500 N m/rad x 0.05 rad on the shin spring
    assert abs(f_ref[tarsus]) > 10.0 and abs(f_ref[knee]) > 10.0  # the achilles tendon spring on both its joints
    np.testing.assert_allclose(f, s * f_ref, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(model.tendon_stiffness, s * ref.tendon_stiffness)


def test_spring_scale_refuses_springdamper_joints():
    spec = spec_of("cassie")
    spec.joint("left-shin").springdamper = [0.05, 1.0]
    with pytest.raises(MJCFError, match="left-shin.*springdamper"):
        SpringScaleEdit(0.5)(spec)


# --- friction -------------------------------------------------------------------------------------------------


def floor_contact_frictions(model: mujoco.MjModel, n_steps: int = 20) -> np.ndarray:
    """The 5 friction coefficients of every contact with the floor after a few steps from standing."""
    data = stand(model)
    for _ in range(n_steps):
        mujoco.mj_step(model, data)
    floor = model.geom("floor").id
    rows = [c.friction.copy() for c in data.contact[: data.ncon] if floor in (c.geom1, c.geom2)]
    assert rows, "the feet should touch the floor"
    return np.array(rows)


@pytest.mark.parametrize("robot", PLANTS)
@pytest.mark.parametrize("mu", [0.5, 1.7])
def test_friction_is_exactly_mu_in_every_foot_floor_contact(robot, mu):
    ref = floor_contact_frictions(compiled(robot))
    got = floor_contact_frictions(modified(robot, PlantModifiers(friction=mu)))
    assert np.all(ref[:, 0] == 1.0)
    np.testing.assert_array_equal(got[:, :2], mu)
    np.testing.assert_array_equal(got[:, 2:], ref[: len(got), 2:])  # torsional and rolling stay


def test_friction_overrides_explicit_pairs_and_priorities():
    spec = spec_of("rabbit")
    spec.geom("left-foot").priority = 2
    spec.geom("left-foot").friction = [3.0, 0.005, 0.0001]
    spec.add_pair(geomname1="floor", geomname2="right-foot", friction=[2.0, 2.0, 0.005, 1e-4, 1e-4], condim=3)
    FrictionEdit(0.6)(spec)
    np.testing.assert_array_equal(floor_contact_frictions(spec.compile())[:, :2], 0.6)


# --- validation, parsing, description -------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"mass_scale": 0.0}, "mass scale"),
        ({"mass_scale": -1.0}, "mass scale"),
        ({"mass_scale": float("nan")}, "mass scale"),
        ({"mass_scale": 11.0}, "mass scale"),
        ({"mass_scale": 0.0999}, r"mass scale \(--plant-mass-scale\) must be a number in \[0.1, 10\], got 0.0999"),
        ({"spring_scale": 10.01}, r"spring scale \(--plant-spring-scale\) must be a number in \[0, 10\], got 10.01"),
        ({"spring_scale": 1e300}, "spring scale"),
        ({"friction": 9.9e-6}, r"friction \(--friction\) must be a coefficient in \[1e-05, 10\], got 9.9e-06"),
        ({"payload_kg": -1.0}, "payload"),
        ({"payload_kg": float("inf")}, "payload"),
        ({"payload_kg": 101.0}, "payload"),
        ({"payload_kg": 5.0, "payload_pos_m": (0.0, 0.0)}, "3 numbers"),
        ({"payload_kg": 5.0, "payload_pos_m": (2.0, 0.0, 0.0)}, "within 1 m"),
        ({"payload_kg": 5.0, "payload_pos_m": (0.0, float("nan"), 0.0)}, "3 numbers"),
        ({"payload_pos_m": (0.1, 0.0, 0.0)}, "0 kg payload"),
        ({"spring_scale": -0.1}, "spring scale"),
        ({"spring_scale": float("inf")}, "spring scale"),
        ({"friction": 0.0}, "friction"),
        ({"friction": 10.5}, "friction"),
        ({"friction": float("nan")}, "friction"),
        ({"actuator_delay_ticks": -1}, "actuator delay"),
        ({"actuator_delay_ticks": 1.5}, "actuator delay"),
        ({"actuator_delay_ticks": 101}, "actuator delay"),
        ({"actuator_delay_ticks": True}, "actuator delay"),
        ({"limb_collisions": "yes"}, "limb collisions"),
    ],
)
def test_nonsensical_values_raise_one_line(kwargs, match):
    with pytest.raises(InputError, match=match) as err:
        PlantModifiers(**kwargs)
    assert "\n" not in str(err.value)


def test_the_bounds_themselves_are_accepted():
    for kwargs in ({"mass_scale": 0.1}, {"mass_scale": 10.0}, {"spring_scale": 0.0}, {"spring_scale": 10.0}):
        PlantModifiers(**kwargs)
    assert PlantModifiers(friction=1e-5).friction == mujoco.mjMINMU
    assert PlantModifiers(friction=10.0).friction == 10.0


def passive_fall(plant: str, edit) -> tuple[float, int]:
    """Largest |qvel| (m/s, rad/s) over 0.2 s from the stand keyframe with no actuation, and MuJoCo's count of
    unstable accelerations (``mjWARN_BADQACC``)."""
    spec = mujoco.MjSpec.from_file(str(MODELS_DIR / f"{plant}.xml"))
    edit(spec)
    model = spec.compile()
    data = stand(model)
    fastest = 0.0
    for _ in range(400):
        mujoco.mj_step(model, data)
        fastest = max(fastest, float(np.max(np.abs(data.qvel))))
    return fastest, int(data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number)


@pytest.mark.parametrize("plant", ["cassie", "cassie-closed-chain"])
def test_at_the_scale_bounds_the_plant_falls_as_a_body_and_past_them_it_diverges(plant):
    """The mass and spring scale bounds hold the plants that MuJoCo integrates stably at the 0.5 ms step."""
    for edit in (MassScaleEdit(0.1), MassScaleEdit(10.0), SpringScaleEdit(10.0), SpringScaleEdit(0.0)):
        fastest, unstable = passive_fall(plant, edit)
        assert unstable == 0 and fastest < 10.0, (edit, fastest)  # a limp robot falling: measured 2.2-5.9
    for edit in (MassScaleEdit(0.001), SpringScaleEdit(500.0)):
        fastest, unstable = passive_fall(plant, edit)
        assert unstable >= 1 and fastest > 1e4, (edit, fastest)  # measured 8.6e5-3.0e6
    # The closed chain, with its light rods and loop closures, diverges already at 200 x the springs.
    assert passive_fall("cassie-closed-chain", SpringScaleEdit(200.0))[1] >= 1


@pytest.mark.parametrize(
    "text, expected",
    [
        ("5", (5.0, (0.0, 0.0, 0.0))),
        ("5@-0.1,0,0", (5.0, (-0.1, 0.0, 0.0))),
        (" 2.5@0,0.05,-0.02 ", (2.5, (0.0, 0.05, -0.02))),
    ],
)
def test_parse_payload(text, expected):
    assert parse_payload(text) == expected


@pytest.mark.parametrize("text", ["", "five", "5@", "5@1,2", "5@a,b,c", "5@0,0,0,0", "-5", "5@0,0,nan", "5@@0,0,0"])
def test_parse_payload_refuses_malformed_text(text):
    with pytest.raises(InputError) as err:
        parse_payload(text)
    assert "\n" not in str(err.value)


def test_describe_lists_only_what_differs():
    mods = PlantModifiers(
        mass_scale=0.8, payload_kg=5, payload_pos_m=(-0.1, 0, 0), friction=0.5, actuator_delay_ticks=1
    )
    assert mods.describe() == {
        "mass_scale": 0.8,
        "payload_kg": 5.0,
        "payload_pos_m": [-0.1, 0.0, 0.0],
        "friction": 0.5,
        "actuator_delay_ticks": 1,
    }
    json.dumps(mods.describe())
    assert PlantModifiers(spring_scale=0.0).describe() == {"spring_scale": 0.0}
    assert [type(e).__name__ for e in mods.spec_edits("cassie-pelvis")] == [
        "MassScaleEdit",
        "PayloadEdit",
        "FrictionEdit",
    ]
