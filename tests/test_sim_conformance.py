"""``amlip-qp check-robot``: every bundled profile passes, a broken one fails the check it breaks, bad input exits 2.

The checks' numbers are asserted against what they measure (the mass, the
torque limits, the output count, the stand pose's gap to the floor), and the
broken profiles are copies of bundled ones in ``tmp_path`` with one thing
changed.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from amlip_qp.experiments import conformance as C
from amlip_qp.experiments import conformance_cli
from amlip_qp.experiments import conformance_control as CC
from amlip_qp.paths import MODELS_DIR
from amlip_qp.profiles import bundled_names, get_profile
from amlip_qp.robots import OutputMap
from amlip_qp.sim.scenarios import factory
from cli_bad_input_support import run_main

#: Every check that runs without the walk, in order.
MODEL_AND_TICK_NAMES = [name for name, _ in C.MODEL_CHECKS] + [CC.tick_name(t) for t in CC.TICK_TRACKERS]


@pytest.fixture(scope="module")
def bundled_results():
    """Robot name -> check name -> result, for every bundled robot, without the walk."""
    return {name: {r.name: r for r in conformance_cli.conformance_checks(name, walk=False)} for name in bundled_names()}


def _profile_copy(tmp_path, robot: str, changes: dict[str, str] | None = None, model_file: str | None = None) -> str:
    """A copy of ``robot``'s bundled profile in ``tmp_path``, its model file named by absolute path
    (``model_file``: another one), with each ``old -> new`` text change made (each must occur)."""
    text = (MODELS_DIR / f"{robot}.toml").read_text()
    profile = get_profile(robot)
    old_file = re.search(r'^file = "([^"]+)"', text, re.M)
    assert old_file is not None
    text = text.replace(old_file.group(0), f'file = "{model_file or profile.model.path}"')
    for old, new in (changes or {}).items():
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / f"{robot}-copy{len(list(tmp_path.glob('*.toml')))}.toml"
    path.write_text(text)
    return str(path)


def _lines(out: str) -> dict[str, tuple[str, str]]:
    """Printed check lines: name -> (status, detail)."""
    found = {}
    for line in out.splitlines():
        for name in [*MODEL_AND_TICK_NAMES, CC.WALK_NAME]:
            m = re.match(rf"(PASS|FAIL|SKIP)\s+{re.escape(name)}\s+(.*)$", line)
            if m:
                found[name] = (m.group(1), m.group(2))
    return found


@pytest.mark.parametrize("robot", bundled_names())
def test_every_bundled_profile_passes_the_model_checks(bundled_results, robot):
    results = bundled_results[robot]
    assert list(results) == MODEL_AND_TICK_NAMES
    assert [r.name for r in results.values() if r.status == C.FAIL] == []
    loaded = factory.load(robot)
    mass = results[C.MASS_NAME]
    assert mass.value is not None and mass.value <= 1e-9
    assert f"mass {loaded.mass_kg:.6g} kg in both" in mass.detail
    for name in (C.SITES_NAME, C.BODIES_NAME):
        assert results[name].value is not None and results[name].value <= 1e-9
    # every site of the library (contact and force sites of both feet) is among those compared
    n_sites = int(re.search(r"over (\d+) sites", results[C.SITES_NAME].detail).group(1))
    assert n_sites >= len({*loaded.contact_sites.values(), *(s for f in loaded.force_sites.values() for s in f)})
    assert results[C.NAMES_NAME].value == 0
    assert results[C.ROLES_NAME].value == 2 * len(loaded.profile.joint_roles)
    lo, hi = C.STAND_GAP_M
    assert lo <= results[C.FLOOR_NAME].value <= hi
    n_out = OutputMap(loaded).size
    rank = results[C.RANK_NAME]
    assert f"rank {n_out} of {n_out}," in rank.detail and rank.value > C.RANK_TOL


@pytest.mark.parametrize("robot", bundled_names())
@pytest.mark.parametrize("tracker", CC.TICK_TRACKERS)
def test_one_tick_at_stand_solves_inside_the_torque_limits(bundled_results, robot, tracker):
    result = bundled_results[robot][CC.tick_name(tracker)]
    loaded = factory.load(robot)
    if tracker not in loaded.profile.trackers:
        assert (result.status, result.detail) == (C.SKIP, f"the profile has no {tracker} configuration")
        assert result.passed is None
        return
    assert result.status == C.PASS
    res = CC.stand_tick(loaded, tracker)
    tau, lim = res.tau_Nm, loaded.actuated.torque_limit_Nm
    assert res.ok and np.all(np.isfinite(tau))
    assert np.all(tau >= lim[:, 0] - CC.TORQUE_LIMIT_TOL_NM) and np.all(tau <= lim[:, 1] + CC.TORQUE_LIMIT_TOL_NM)
    assert result.value == pytest.approx(np.max(np.abs(tau)), rel=1e-9)
    # the stand pose needs torque: the robot's weight is carried by the joints
    assert result.value > 1.0


@pytest.mark.slow
@pytest.mark.parametrize("robot", ["cassie", "rabbit", "h1"])
def test_the_walk_in_place_does_not_fall(robot):
    result = CC.check_walk(robot, factory.load(robot))
    assert result.name == CC.WALK_NAME and result.status == C.PASS, result.detail
    steps = int(re.search(r"\((\d+) steps", result.detail).group(1))
    gait = get_profile(robot).gait
    # about one step per T over the 3 s (the first starts at 0), drifting less than a step width
    assert CC.WALK_DURATION_S / gait.step_time_s - 2 <= steps <= CC.WALK_DURATION_S / gait.step_time_s + 1
    assert 0.0 <= result.value < 0.3


def test_the_command_prints_one_line_per_check_and_writes_the_json(capsys, tmp_path):
    path = tmp_path / "checks.json"
    code, out, err = run_main(["check-robot", "rabbit", "--no-walk", "--json", str(path)], capsys)
    assert code == 0, err
    lines = _lines(out)
    assert list(lines) == MODEL_AND_TICK_NAMES and {s for s, _ in lines.values()} == {"PASS"}
    assert out.splitlines()[-1] == "rabbit: 9 passed, 0 failed, 0 skipped"
    report = json.loads(path.read_text())
    assert report["robot"] == "rabbit" and report["passed"] is True
    assert [c["name"] for c in report["checks"]] == MODEL_AND_TICK_NAMES
    assert all(set(c) == {"name", "status", "passed", "value", "unit", "detail"} for c in report["checks"])
    assert report["checks"][0]["unit"] == "kg" and report["checks"][0]["value"] <= 1e-9


def test_json_to_stdout_moves_the_lines_to_stderr(capsys, tmp_path):
    profile = _profile_copy(tmp_path, "h1", {"[trackers.pbc]\n": ""})  # no PBC table: its tick is skipped
    code, out, err = run_main(["check-robot", profile, "--no-walk", "--json", "-"], capsys)
    assert code == 0
    report = json.loads(out)
    skipped = [c for c in report["checks"] if c["status"] == "skip"]
    assert [c["name"] for c in skipped] == [CC.tick_name("pbc")] and skipped[0]["passed"] is None
    assert report["passed"] is True
    assert _lines(err)[CC.tick_name("pbc")] == ("SKIP", "the profile has no pbc configuration")


def _failed(out: str) -> dict[str, str]:
    return {name: detail for name, (status, detail) in _lines(out).items() if status == "FAIL"}


def test_feet_in_the_air_fail_the_floor_check(capsys, tmp_path):
    profile = _profile_copy(tmp_path, "h1", {"base_pos_m = [0.0, 0.0, 0.982]": "base_pos_m = [0.0, 0.0, 1.282]"})
    code, out, _ = run_main(["check-robot", profile, "--no-walk"], capsys)
    assert code == 1
    failed = _failed(out)
    assert list(failed) == [C.FLOOR_NAME]
    assert "left 301.0 mm, right 301.0 mm above the floor" in failed[C.FLOOR_NAME]
    assert len(_lines(out)) == len(MODEL_AND_TICK_NAMES)  # every check still ran


def test_straight_legs_fail_the_rank_check(capsys, tmp_path):
    """Rabbit standing on straight, vertical legs (the spheres touching the floor): the legs cannot
    lengthen and both feet are under the hips, so two outputs lose their rank."""
    stand = '[model.stand]\nbase_pos_m = [0.0, 0.0, 0.0]\n[model.stand.joints]\n"root-z" = 0.82\n\n[roles]'
    profile = _profile_copy(tmp_path, "rabbit", {"[roles]": stand})
    results = {r.name: r for r in conformance_cli.conformance_checks(profile, walk=False)}
    rank = results[C.RANK_NAME]
    assert rank.status == C.FAIL and rank.value < 1e-9 and "rank 2 of 4" in rank.detail
    for name in (C.MASS_NAME, C.SITES_NAME, C.BODIES_NAME, C.ROLES_NAME, C.FLOOR_NAME):
        assert results[name].status == C.PASS, results[name].detail
    assert abs(results[C.FLOOR_NAME].value) < 1e-9
    code, out, _ = run_main(["check-robot", profile, "--no-walk"], capsys)
    assert code == 1 and C.RANK_NAME in _failed(out)


def test_an_unnamed_free_joint_fails_the_joint_name_check(capsys, tmp_path):
    """Menagerie's H1 leaves its free joint unnamed; without ``free_joint_name`` the plant cannot be mapped."""
    profile = _profile_copy(tmp_path, "h1", {'free_joint_name = "floating_base"': "# no free_joint_name"})
    code, out, _ = run_main(["check-robot", profile, "--no-walk"], capsys)
    assert code == 1
    failed = _failed(out)
    assert list(failed) == [C.NAMES_NAME]
    assert failed[C.NAMES_NAME] == "1 of 20 joints have no name (the free joint: set free_joint_name in [model])"


def test_a_role_naming_no_joint_fails_the_role_check(capsys, tmp_path):
    profile = _profile_copy(tmp_path, "h1", {'knee = "{side}_knee"': 'knee = "{side}_shin"'})
    code, out, _ = run_main(["check-robot", profile, "--no-walk"], capsys)
    assert code == 1
    failed = _failed(out)
    assert C.ROLES_NAME in failed
    assert "8 of 10 joints found" in failed[C.ROLES_NAME] and "knee 'left_shin'" in failed[C.ROLES_NAME]


def test_a_check_that_raises_fails_with_its_reason_and_the_others_still_run(capsys, tmp_path):
    """Without hip-yaw joints the hip-yaw outputs have no joint: the checks that need the outputs raise."""
    profile = _profile_copy(tmp_path, "h1", {'hip_yaw = "{side}_hip_yaw"': 'hip_yaw = "{side}_yaw"'})
    code, out, _ = run_main(["check-robot", profile, "--no-walk"], capsys)
    assert code == 1
    lines = _lines(out)
    assert list(lines) == MODEL_AND_TICK_NAMES
    status, detail = lines[C.RANK_NAME]
    assert status == "FAIL" and detail.startswith("raised MJCFError: ") and "needs a hip_yaw joint" in detail
    assert lines[C.MASS_NAME][0] == lines[C.FLOOR_NAME][0] == "PASS"


def _weak_rabbit(tmp_path) -> str:
    """Rabbit with motors of +-1 N m instead of +-150 N m (an MJCF copy)."""
    xml = (MODELS_DIR / "rabbit.xml").read_text()
    assert 'ctrlrange="-150 150"' in xml
    weak = tmp_path / "rabbit-weak.xml"
    weak.write_text(xml.replace('ctrlrange="-150 150"', 'ctrlrange="-1 1"'))
    return _profile_copy(tmp_path, "rabbit", model_file=str(weak))


def test_tiny_torque_limits_fail_the_pbc_tick(tmp_path):
    """The PBC asks for the torques the stand needs; the QP keeps within the limits (at them)."""
    profile = _weak_rabbit(tmp_path)
    results = {r.name: r for r in conformance_cli.conformance_checks(profile, walk=False)}
    pbc = results[CC.tick_name("pbc")]
    assert pbc.status == C.FAIL and pbc.value > 10.0
    assert re.search(r"needs [-\d.]+ N m, outside its limits \[-1, 1\] N m", pbc.detail)
    qp = results[CC.tick_name("qp")]
    assert qp.status == C.PASS and 0.9 < qp.value <= 1.0 + CC.TORQUE_LIMIT_TOL_NM


@pytest.mark.slow
def test_tiny_torque_limits_fail_the_walk(capsys, tmp_path):
    code, out, _ = run_main(["check-robot", _weak_rabbit(tmp_path)], capsys)
    assert code == 1
    failed = _failed(out)
    assert set(failed) == {CC.tick_name("pbc"), CC.WALK_NAME}
    fall_s = float(re.match(r"fell at ([\d.]+) s", failed[CC.WALK_NAME]).group(1))
    assert 0.0 < fall_s < CC.WALK_DURATION_S


@pytest.mark.parametrize(
    "argv, message",
    [
        (["check-robot", "walker"], "unknown robot 'walker'"),
        (["check-robot", "{tmp}/missing.toml"], "robot profile not found"),
        (["check-robot", "{bad_key}"], "unknown key 'stride'"),
        (["check-robot", "{bad_joint}"], "the profile's stand pose names 'left_shin'"),
        (["check-robot", "{bad_gain}"], "[trackers.qp]: unknown key 'output_gain'"),
        (["check-robot", "rabbit", "--json", "/proc/x"], "--json /proc/x: cannot write"),
    ],
    ids=[
        "unknown-robot",
        "missing-profile",
        "unknown-key",
        "stand-names-no-joint",
        "bad-tracker-key",
        "unwritable-json",
    ],
)
def test_bad_input_exits_2_with_one_line_before_any_check(capsys, tmp_path, argv, message):
    fill = {
        "tmp": str(tmp_path),
        "bad_key": _profile_copy(tmp_path, "h1", {"[gait]\n": "[gait]\nstride = 1.0\n"}),
        "bad_joint": _profile_copy(tmp_path, "h1", {"left_knee = 0.8": "left_shin = 0.8"}),
        "bad_gain": _profile_copy(tmp_path, "h1", {"output_weight = ": "output_gain = "}),
    }
    code, out, err = run_main([a.format(**fill) for a in argv], capsys)
    assert code == 2
    assert out == ""  # no check ran
    assert len(err.strip().splitlines()) == 1 and message in err
