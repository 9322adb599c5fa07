"""QPConfig validation, the tuned configurations and their lookup through the profile registry."""

import math
import shutil

import pytest

from amlip_qp.control.wbc.config import QPConfig, default_config
from amlip_qp.exceptions import InputError
from amlip_qp.profiles import PROFILES, get_profile
from amlip_qp.robots import load_robot
from robot_states import tuned_config

CASSIE_CONFIG = tuned_config("cassie", "qp")
RABBIT_CONFIG = tuned_config("rabbit", "qp")


@pytest.fixture(scope="module")
def cassie():
    return load_robot("cassie")


@pytest.fixture(scope="module")
def rabbit():
    return load_robot("rabbit")


def test_bundled_robots_get_their_registered_configuration(cassie, rabbit):
    assert get_profile("cassie").tracker_config("qp") is CASSIE_CONFIG
    assert get_profile("rabbit").tracker_config("qp") is RABBIT_CONFIG
    assert default_config(cassie) is CASSIE_CONFIG
    assert default_config(rabbit) is RABBIT_CONFIG
    assert all("qp" in p.tracker_configs for p in PROFILES.values())
    assert len(CASSIE_CONFIG.output_kp) == 9 and len(RABBIT_CONFIG.output_kp) == 4


@pytest.mark.parametrize("bundled, expected", [("rabbit", "RABBIT_CONFIG"), ("cassie", "CASSIE_CONFIG")])
def test_another_mjcf_file_gets_the_configuration_of_its_output_layout(tmp_path, bundled, expected):
    """A robot that is not bundled (its name is the file's stem) falls back on
    the bundled configuration whose gains fit its outputs one for one."""
    path = tmp_path / "my_biped.xml"
    shutil.copy(load_robot(bundled).path, path)
    robot = load_robot(str(path))
    assert robot.name == "my_biped" and robot.name not in PROFILES
    assert default_config(robot) is {"RABBIT_CONFIG": RABBIT_CONFIG, "CASSIE_CONFIG": CASSIE_CONFIG}[expected]


def test_validation_names_the_field():
    with pytest.raises(InputError, match="friction_mu"):
        CASSIE_CONFIG.with_(friction_mu=-0.1)
    with pytest.raises(InputError, match="rigid_springs"):
        CASSIE_CONFIG.with_(rigid_springs="maybe")
    with pytest.raises(InputError, match="one entry per output"):
        QPConfig(output_kp=(1.0,), output_kd=(1.0, 2.0), output_weight=(1.0,))
    with pytest.raises(InputError, match="min_normal_force_N"):
        CASSIE_CONFIG.with_(min_normal_force_N=2000.0)
    with pytest.raises(InputError, match="touchdown_blend"):
        RABBIT_CONFIG.with_(touchdown_blend=1.5)
    with pytest.raises(InputError, match="joint_limit_horizon_s"):
        RABBIT_CONFIG.with_(joint_limit_horizon_s=0.0)
    with pytest.raises(InputError, match="stance_foot_torque_max_Nm"):
        CASSIE_CONFIG.with_(stance_foot_torque_max_Nm=-1.0)
    with pytest.raises(InputError, match="stance_foot_torque_max_Nm"):
        CASSIE_CONFIG.with_(stance_foot_torque_max_Nm=math.nan)
    with pytest.raises(InputError, match="stance_yaw_moment_weight"):
        CASSIE_CONFIG.with_(stance_yaw_moment_weight=-1.0)
    with pytest.raises(InputError, match="posture_weight"):
        CASSIE_CONFIG.with_(posture_weight=math.inf)  # only the stance-foot bound may be infinite


def test_with_changes_only_the_named_fields():
    changed = CASSIE_CONFIG.with_(friction_mu=0.5)
    assert changed.friction_mu == 0.5 and CASSIE_CONFIG.friction_mu == 0.9
    assert changed.with_(friction_mu=0.9) == CASSIE_CONFIG


def test_cassie_leaves_the_stance_toe_passive_and_penalises_yaw_moment():
    # Passive stance toe up to a band that active-set solvers handle (docs/TUNING.md).
    assert 0.0 < CASSIE_CONFIG.stance_foot_torque_max_Nm <= 0.05
    assert CASSIE_CONFIG.stance_yaw_moment_weight > 0.0
    assert CASSIE_CONFIG.hip_yaw_feedback > 0.0
    # Point feet: no foot motor, no yaw moment, no hip yaw.
    assert math.isinf(RABBIT_CONFIG.stance_foot_torque_max_Nm)
    assert RABBIT_CONFIG.stance_yaw_moment_weight == 0.0
    # No forces on a landing foot before its touchdown, on both robots (docs/TUNING.md).
    assert CASSIE_CONFIG.touchdown_blend == 0.0 and RABBIT_CONFIG.touchdown_blend == 0.0
