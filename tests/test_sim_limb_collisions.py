"""The limb-collision plant modifier (``--limb-collisions``): Cassie's legs collide with each other and
nothing else changes; a walk whose legs never touch is the same walk to the bit; crossed legs push apart."""

from __future__ import annotations

import dataclasses
import itertools

import mujoco
import numpy as np
import pytest

from amlip_qp.exceptions import MJCFError
from amlip_qp.paths import MODELS_DIR
from amlip_qp.sim.scenarios.factory import build_simulation
from amlip_qp.sim.scenarios.named import get_scenario
from amlip_qp.sim.world.plant_modifiers import LimbCollisionEdit, PlantModifiers


def _cassie(limb_collisions: bool) -> mujoco.MjModel:
    spec = mujoco.MjSpec.from_file(str(MODELS_DIR / "cassie.xml"))
    for edit in PlantModifiers(limb_collisions=limb_collisions).spec_edits("cassie-pelvis"):
        edit(spec)
    return spec.compile()


def _collide(m: mujoco.MjModel, a: int, b: int) -> bool:
    """MuJoCo's collision filter of two geoms by their bits (the parent-child filter aside)."""
    return bool((m.geom_contype[a] & m.geom_conaffinity[b]) or (m.geom_contype[b] & m.geom_conaffinity[a]))


def _leg(m: mujoco.MjModel, side: str) -> list[int]:
    return [g for g in range(m.ngeom) if (mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or "").startswith(side)]


def test_the_legs_collide_with_each_other_and_nothing_else_changes():
    before, after = _cassie(False), _cassie(True)
    left, right = _leg(after, "left-"), _leg(after, "right-")
    assert len(left) == len(right) == 6  # per leg 4 capsules, the toe and the heel sphere
    for a, b in itertools.product(left, right):
        assert not _collide(before, a, b) and _collide(after, a, b)
    for leg in (left, right):
        for a, b in itertools.combinations(leg, 2):
            assert not _collide(after, a, b)  # the geoms of one leg still do not collide with each other
    legs = set(left) | set(right)
    for a, b in itertools.product(range(after.ngeom), repeat=2):
        if not (a in legs and b in legs):  # everything but a leg against a leg, the floor too: as it was
            assert _collide(after, a, b) == _collide(before, a, b)


def test_a_walk_whose_legs_never_touch_is_the_same_walk_to_the_bit():
    """At 1 m/s Cassie's legs stay about 10 cm apart: no new contact, so the same torques and states."""
    sc = get_scenario("cassie-1mps").with_(duration_s=1.0)
    colliding = sc.with_(setting=dataclasses.replace(sc.setting, modifiers=PlantModifiers(limb_collisions=True)))
    logs = []
    for scenario in (sc, colliding):
        sim = build_simulation(scenario, "qp")
        logs.append(sim.run(1.0, log="full").log)
    assert colliding.setting.modifiers.limb_collisions and not sc.setting.modifiers.limb_collisions
    for key in ("tau", "com", "base_pos_true", "h"):
        np.testing.assert_array_equal(logs[0][key], logs[1][key])


def test_crossed_legs_push_each_other_apart():
    """Both hip rolls turned inwards to their limits put the shins 8 cm into each other."""
    for collide in (False, True):
        m = _cassie(collide)
        d = mujoco.MjData(m)
        mujoco.mj_resetDataKeyframe(m, d, 0)
        for joint, angle_rad in (("left-hip-roll", -0.26), ("right-hip-roll", 0.26)):
            d.qpos[m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, joint)]] = angle_rad
        mujoco.mj_forward(m, d)
        left, right = set(_leg(m, "left-")), set(_leg(m, "right-"))
        between = [i for i in range(d.ncon) if {d.contact[i].geom1, d.contact[i].geom2} & left
                   and {d.contact[i].geom1, d.contact[i].geom2} & right]  # fmt: skip
        assert bool(between) == collide
        force = np.zeros(6)
        for i in between:
            assert d.contact[i].dist < 0.0  # they overlap
            mujoco.mj_contactForce(m, d, i, force)
            assert force[0] > 0.0  # a normal force that pushes the legs apart


def test_a_base_with_one_limb_is_refused_in_one_line():
    spec = mujoco.MjSpec()
    base = spec.worldbody.add_body(name="base")
    base.add_geom(size=[0.1, 0, 0])
    base.add_body(name="only-limb").add_geom(size=[0.05, 0, 0])
    with pytest.raises(MJCFError, match="carries 1 limb") as err:
        LimbCollisionEdit("base")(spec)
    assert "\n" not in str(err.value)
    with pytest.raises(MJCFError, match="no body 'nowhere'"):
        LimbCollisionEdit("nowhere")(spec)
