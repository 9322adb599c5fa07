"""amlip_qp.profiles.reader: a profile file is read key by key, and every bad key is named in one line."""

import math
import re
from pathlib import Path

import pytest

from amlip_qp.exceptions import InputError, ProfileError
from amlip_qp.paths import MODELS_DIR
from amlip_qp.profiles import get_profile, load_profile, read_profile

CASSIE_TOML = (MODELS_DIR / "cassie.toml").read_text()


def _profile_copy(tmp_path: Path, text: str, name: str = "robot.toml") -> Path:
    """A copy of a profile whose model file is the bundled one (an absolute path)."""
    path = tmp_path / name
    text = text.replace('file = "cassie.xml"', f'file = "{MODELS_DIR / "cassie.xml"}"')
    text = text.replace(
        'cassie-closed-chain = "cassie-closed-chain.xml"',
        f'cassie-closed-chain = "{MODELS_DIR / "cassie-closed-chain.xml"}"',
    )
    path.write_text(text)
    return path


def test_the_bundled_profile_reads_the_values_its_file_gives():
    p = get_profile("cassie")
    assert p.model.path == MODELS_DIR / "cassie.xml" and not p.model.edits_needed
    assert (p.gait.step_time_s, p.gait.com_height_m, p.gait.clearance_m, p.gait.step_width_m) == (0.3, 0.8, 0.1, 0.25)
    assert p.bounds.vx_mps == (-4.14, 4.14) and p.bounds.turn_rate_max_radps == math.radians(180.0)
    assert p.bounds.step_time_min_s == 0.25
    assert p.verified.vx_mps == (-0.5, 3.0) and p.verified.turn_rate_max_radps == math.radians(45.0)
    assert p.shaping.vy_accel_mps2 == math.inf and p.shaping.max_step_length_m == 0.63
    assert p.joint_roles["ankle_pitch"] == "{side}-foot" and p.joint_name("knee", "right") == "right-knee"
    assert p.feet.passive_in_stance == ("ankle_pitch",) and p.feet.body is None
    assert (p.imu.body, p.imu.pos_m, p.imu.quat_wxyz) == (None, (0.03155, 0.0, -0.07996), (1.0, 0.0, 0.0, 0.0))
    assert set(p.plants) == {"cassie", "cassie-closed-chain"}
    qp = p.tracker_config("qp")
    assert qp.output_kp[0] == 400.0 and qp.stance_foot_torque_max_Nm == 0.01 and qp.friction_mu == 0.9
    assert p.tracker_config("qp") is qp  # built once
    pbc = p.tracker_config("pbc")
    assert pbc.kd_stance_ps == 44.72 and pbc.spring_model_linkage.heel_stiffness_Nmprad == 1250.0
    assert p.compare is not None and p.compare.realtime_goal == {"qp": 2.5, "pbc": 1.5}
    assert get_profile("rabbit").compare.realtime_goal == {}  # no goal: the key is optional
    assert p.shaping.gait_scale_by_speed == ()  # no gait schedule: the key is optional
    rows = get_profile("rabbit").shaping.gait_scale_by_speed  # 0.35 -> 0.40 s, 0.68 -> 0.56 m, 0.06 -> 0.12 m
    assert rows[0] == (1.0, 1.0, 1.0, 1.0) and rows[1] == pytest.approx((1.5, 0.40 / 0.35, 0.56 / 0.68, 2.0), rel=1e-15)


def test_a_copy_of_a_bundled_profile_reads_alike(tmp_path):
    p = load_profile(_profile_copy(tmp_path, CASSIE_TOML))
    b = get_profile("cassie")
    assert (p.gait, p.bounds, p.shaping, p.feet, p.imu) == (b.gait, b.bounds, b.shaping, b.feet, b.imu)
    assert p.tracker_config("qp") == b.tracker_config("qp")
    assert load_profile(tmp_path / "robot.toml") is p  # read once per process


def test_an_imu_quaternion_near_unit_norm_is_normalised_and_an_imu_body_the_model_lacks_is_refused(tmp_path):
    text = _profile_copy(tmp_path, CASSIE_TOML).read_text()
    near = text.replace("[imu]\n", "[imu]\nquat_wxyz = [0.0, 0.0, 0.0, 1.0000005]\n", 1)
    (tmp_path / "near.toml").write_text(near)
    assert read_profile(tmp_path / "near.toml").imu.quat_wxyz == (0.0, 0.0, 0.0, 1.0)
    from amlip_qp.robots import load_robot

    (tmp_path / "nobody.toml").write_text(text.replace("[imu]\n", '[imu]\nbody = "cassie-torso"\n', 1))
    with pytest.raises(ProfileError) as info:
        load_robot(tmp_path / "nobody.toml")
    message = str(info.value)
    assert "\n" not in message and "imu.body: the model cassie.xml has no body 'cassie-torso'" in message, message


@pytest.mark.parametrize(
    "old, new, message",
    [
        ("[gait]\n", "[gait]\nspeed = 1.0\n", "gait: unknown key 'speed' (known here: clearance_m"),
        ("step_time_s = 0.3", 'step_time_s = "fast"', "gait.step_time_s: must be a number (s), got 'fast'"),
        ("step_time_s = 0.3", "step_time_s = 30.0", "gait.step_time_s: 30 s is outside [0.05, 2]"),
        ("step_time_s = 0.3", "step_time_s = nan", "gait.step_time_s: must be a finite number"),
        ("step_time_s = 0.3\n", "", "gait.step_time_s: is required"),
        ("vx_mps = [-4.14, 4.14]", "vx_mps = [2.5]", "bounds.vx_mps: must be a list of 2 numbers (m/s)"),
        ("vx_mps = [-4.14, 4.14]", "vx_mps = [1.0, 2.5]", "min <= 0 <= max"),
        ('"swing_toe_pitch",\n]', '"swing_toe_ptich",\n]', "outputs: unknown output 'swing_toe_ptich'; known"),
        ('"swing_toe_pitch",\n]', '"swing_toe_pitch", "torso_pitch",\n]', "output 'torso_pitch' is declared more"),
        ('"com_y_over_swing", ', "", "outputs: a 3-D robot needs com_y_over_swing"),
        ('"com_x_over_swing", ', "", "outputs: outputs must include com_x_over_swing"),
        ("outputs = [", "outputs = 3\nunused = [", "outputs: must be a list of output names, got 3"),
        ("planar = false", "planar = 0", "planar: must be true or false, got 0"),
        ('hip_yaw = "{side}-hip-yaw"', 'hip_yaw = "left-hip-yaw"', "roles.hip_yaw: must contain '{side}' once"),
        ('hip_yaw = "{side}-hip-yaw"', 'hip_spin = "{side}-hip-yaw"', "unknown joint role 'hip_spin'"),
        (
            'passive_in_stance = ["ankle_pitch"]',
            'passive_in_stance = ["toe"]',
            "feet.passive_in_stance: must be a list",
        ),
        ("[feet]\n", "[feet]\ncontact_point_m = [0.0, 0.0, 0.0]\n", "feet.body: is required with 'contact_point_m'"),
        ("[model]\n", "[model]\ntimestep_s = 0.5\n", "model.timestep_s: 0.5 s is outside [1e-05, 0.01]"),
        ("[model]\n", '[model]\nservos = "ignore"\n', "model.servos: must be one of refuse, convert"),
        ('cassie.xml"  #', 'nothing.xml"  #', "model.file: file not found"),
        ("[trackers.pbc]\n", "[trackers.lqr]\n", "trackers: unknown tracker 'lqr' (known: qp, pbc)"),
        ("name = ", "nom = ", "name: is required"),
        ("pos_m = [0.03155, 0.0, -0.07996]", "pos_m = [0.03, 0.0]", "imu.pos_m: must be a list of 3 numbers (m)"),
        ("[imu]\n", "[imu]\nquat_wxyz = [1.0, 0.0, 0.0]\n", "imu.quat_wxyz: must be a list of 4 numbers"),
        ("[imu]\n", "[imu]\nquat_wxyz = [1.0, 0.0, 0.1, 0.0]\n", "imu.quat_wxyz: must be a unit quaternion"),
        ("[imu]\n", "[imu]\nbody = 3\n", "imu.body: must be a non-empty string, got 3"),
        ("[imu]\n", "[imu]\npos_in_base_m = [0.0, 0.0, 0.0]\n", "imu: unknown key 'pos_in_base_m' (known here: body"),
        ("realtime_goal = { qp = 2.5,", "realtime_goal = { lqr = 2.5,", "compare.realtime_goal.lqr: unknown tracker"),
        ("realtime_goal = { qp = 2.5,", "realtime_goal = { qp = 0.0,", "compare.realtime_goal.qp: 0 is outside"),
        ("realtime_goal = { qp = 2.5,", 'realtime_goal = { qp = "fast",', "compare.realtime_goal.qp: must be a number"),
        (
            "[shaping]\n",
            "[shaping]\ngait_scale_by_speed = [[1.0, 1.0, 1.0]]\n",
            "shaping.gait_scale_by_speed: must be a list of rows of 4",
        ),
        (
            "[shaping]\n",
            "[shaping]\ngait_scale_by_speed = [[1.0, 1.1, 1.0, 1.0], [2.0, 1.2, 0.9, 1.5]]\n",
            "shaping.gait_scale_by_speed: the first row's scales must be 1",
        ),
        (
            "[shaping]\n",
            "[shaping]\ngait_scale_by_speed = [[1.0, 1.0, 1.0, 1.0], [0.5, 1.2, 0.9, 1.5]]\n",
            "shaping.gait_scale_by_speed: the speeds must be >= 0 and increasing",
        ),
        (
            "[shaping]\n",
            "[shaping]\ngait_scale_by_speed = [[1.0, 1.0, 1.0, 1.0], [2.0, 1.2, 0.0, 1.5]]\n",
            "shaping.gait_scale_by_speed: every scale must be positive",
        ),
    ],
)
def test_each_bad_key_is_named_in_one_line(tmp_path, old, new, message):
    text = _profile_copy(tmp_path, CASSIE_TOML.replace("\n# ", "\n#~ ")).read_text()  # no match in comments
    assert old in text
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(ProfileError) as info:
        read_profile(path)
    text = str(info.value)
    assert "\n" not in text and text.startswith(str(path)) and message in text, text


def test_an_invalid_tracker_table_is_named_when_the_configuration_is_built(tmp_path):
    path = _profile_copy(tmp_path, CASSIE_TOML.replace("spring_weight = 1e-2", "spring_wieght = 1e-2"))
    profile = read_profile(path)  # the tables are the trackers' to check
    with pytest.raises(InputError, match=re.escape(f"{path}: [trackers.qp]: unknown key 'spring_wieght'")):
        profile.tracker_config("qp")
    with pytest.raises(InputError, match="no 'mpc' tracker configuration; known: pbc, qp"):
        profile.tracker_config("mpc")


def test_the_qp_solver_is_a_profile_key_and_a_bad_one_is_named(tmp_path):
    solver_line = 'qp_solver = "daqp"'
    assert CASSIE_TOML.count(solver_line) == 1  # Cassie's profile names DAQP
    assert read_profile(_profile_copy(tmp_path, CASSIE_TOML)).tracker_config("qp").qp_solver == "daqp"
    proxqp = read_profile(_profile_copy(tmp_path, CASSIE_TOML.replace(solver_line, 'qp_solver = "proxqp"')))
    assert proxqp.tracker_config("qp").qp_solver == "proxqp"
    unset = read_profile(_profile_copy(tmp_path, CASSIE_TOML.replace(solver_line, "")))
    assert unset.tracker_config("qp").qp_solver == "proxqp"  # QPConfig's default when the profile is silent
    path = _profile_copy(tmp_path, CASSIE_TOML.replace(solver_line, 'qp_solver = "gurobi"'))
    with pytest.raises(InputError, match=re.escape("qp_solver must be one of proxqp, daqp, got 'gurobi'")):
        read_profile(path).tracker_config("qp")


def test_a_tracker_the_profile_says_cannot_run_is_refused_with_its_reason(tmp_path):
    path = _profile_copy(tmp_path, CASSIE_TOML + '\n[unsupported]\npbc = "no knees"\n')
    profile = read_profile(path)
    with pytest.raises(InputError, match="the pbc tracker does not run on cassie: no knees"):
        profile.tracker_config("pbc")
    profile.check_supported("qp")  # the others still run
    bad = _profile_copy(tmp_path, CASSIE_TOML + '\n[unsupported]\nlqr = "no"\n', "bad.toml")
    with pytest.raises(ProfileError, match="unsupported: unknown tracker 'lqr'"):
        read_profile(bad)


def test_files_that_are_missing_or_not_toml_are_one_line_errors(tmp_path):
    with pytest.raises(ProfileError, match="robot profile not found: .*nothing.toml"):
        read_profile(tmp_path / "nothing.toml")
    (tmp_path / "x.toml").write_text("name = [unclosed\n")
    with pytest.raises(ProfileError, match="not a valid TOML file"):
        read_profile(tmp_path / "x.toml")
    (tmp_path / "y.toml").write_text(CASSIE_TOML.replace("step_width_m = 0.25", "step_width_m = 0.0"))
    with pytest.raises(ProfileError, match="model.file: file not found"):
        read_profile(tmp_path / "y.toml")  # relative to the profile's own folder


def test_a_planar_flag_must_match_the_step_width(tmp_path):
    path = _profile_copy(tmp_path, CASSIE_TOML.replace("step_width_m = 0.25", "step_width_m = 0.0"))
    with pytest.raises(ProfileError, match="planar: a planar robot has gait.step_width_m = 0"):
        read_profile(path)


H1_LINE = "force_points_m = [[0.14, 0.0, -0.07], [-0.035, 0.0, -0.07]]"


@pytest.mark.parametrize(
    "new, message",
    [
        (
            "force_points_m = [[0.1, 0.0, -0.07], [0.0, 0.0, -0.07], [-0.03, 0.0, -0.07]]",
            "feet.force_points_m: must be a list of 1 point, 2 points (toe, heel) or 4 points",
        ),
        (
            "force_points_m = [[0.14, -0.03, -0.07], [0.14, 0.03, -0.07], [-0.03, 0.03, -0.07], [-0.03, -0.03, -0.07]]",
            "feet.force_points_m: four points go toe left, toe right, heel left, heel right",
        ),
        (
            "force_points_m = [[-0.03, 0.03, -0.07], [-0.03, -0.03, -0.07], [0.14, 0.03, -0.07], [0.14, -0.03, -0.07]]",
            "feet.force_points_m: four points go toe left, toe right, heel left, heel right",
        ),
        (
            "force_points_m = [[0.14, 0.0, -0.07], [0.14, 0.0, -0.07], [-0.03, 0.03, -0.07], [-0.03, -0.03, -0.07]]",
            "only the heel pair may coincide",
        ),
        (
            f"{H1_LINE}\nsole_rectangle_m = {{ x_front = 0.14, x_back = -0.035, half_width = 0.03, z = -0.07 }}",
            "feet.sole_rectangle_m: give either 'force_points_m' or 'sole_rectangle_m', not both",
        ),
        (
            "sole_rectangle_m = { x_front = -0.1, x_back = 0.1, half_width = 0.03, z = -0.07 }",
            "feet.sole_rectangle_m.x_front: must be ahead of x_back",
        ),
        (
            "sole_rectangle_m = { x_front = 0.14, x_back = -0.035, half_width = 0.0, z = -0.07 }",
            "feet.sole_rectangle_m.half_width: must be positive",
        ),
        (
            "sole_rectangle_m = { x_front = 0.14, x_back = -0.035, width = 0.06, z = -0.07 }",
            "feet.sole_rectangle_m.half_width: is required",
        ),
        ("sole_rectangle_m = [0.14, -0.035, 0.03, -0.07]", "feet.sole_rectangle_m: must be a table"),
    ],
)
def test_a_bad_number_or_order_of_force_points_is_named_in_one_line(tmp_path, new, message):
    text = (MODELS_DIR / "h1.toml").read_text()
    assert H1_LINE in text
    text = text.replace(H1_LINE, new).replace('file = "unitree_', f'file = "{MODELS_DIR}/unitree_')
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ProfileError) as info:
        read_profile(path)
    text = str(info.value)
    assert "\n" not in text and text.startswith(str(path)) and message in text, text


def test_a_sole_rectangle_gives_its_four_corners_and_four_points_are_read_as_given(tmp_path):
    text = (MODELS_DIR / "h1.toml").read_text().replace('file = "unitree_', f'file = "{MODELS_DIR}/unitree_')
    rect = "sole_rectangle_m = { x_front = 0.14, x_back = -0.035, half_width = 0.03, z = -0.07 }"
    corners = ((0.14, 0.03, -0.07), (0.14, -0.03, -0.07), (-0.035, 0.03, -0.07), (-0.035, -0.03, -0.07))
    (tmp_path / "rect.toml").write_text(text.replace(H1_LINE, rect))
    assert read_profile(tmp_path / "rect.toml").feet.force_points_m == corners
    four = "force_points_m = [[0.14, 0.03, -0.07], [0.14, -0.03, -0.07], [-0.035, 0.03, -0.07], [-0.035, -0.03, -0.07]]"
    (tmp_path / "four.toml").write_text(text.replace(H1_LINE, four))
    assert read_profile(tmp_path / "four.toml").feet.force_points_m == corners
    # a triangular sole: the heel pair at one point
    tri = "force_points_m = [[0.14, 0.03, -0.07], [0.14, -0.03, -0.07], [-0.035, 0.0, -0.07], [-0.035, 0.0, -0.07]]"
    (tmp_path / "tri.toml").write_text(text.replace(H1_LINE, tri))
    assert read_profile(tmp_path / "tri.toml").feet.force_points_m[2:] == ((-0.035, 0.0, -0.07),) * 2
