"""The README's examples run as written: the quickstart walks Cassie, the planner example plans a step."""

import re
from pathlib import Path

import mujoco
import numpy as np

README = Path(__file__).resolve().parents[1] / "README.md"


def _python_blocks() -> list[str]:
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert len(blocks) >= 2, "the README lost its python examples"
    return blocks


def test_the_quickstart_is_short_and_uses_only_the_top_level_names():
    quickstart = _python_blocks()[0]
    assert len(quickstart.strip().splitlines()) <= 15
    imports = [line for line in quickstart.splitlines() if line.startswith(("import ", "from "))]
    assert imports == ["import mujoco", "import amlip_qp"]


def test_the_quickstart_walks_cassie_at_the_commanded_speed(capsys):
    namespace: dict = {}
    exec(compile(_python_blocks()[0], "README.md", "exec"), namespace)
    robot, model, data, loop, command = (namespace[k] for k in ("robot", "model", "data", "loop", "command"))
    printed = capsys.readouterr().out
    assert printed.startswith("walked ") and "np.float64" not in printed
    # 3 s from rest: upright (the pelvis stands 0.99 m high), about 1.2 m forward (measured 1.22 m),
    # the command ramping up at the profile's 0.5 m/s^2
    assert abs(data.time - 3.0) < 1e-9 and 0.9 < data.qpos[2] < 1.05
    assert 1.0 < data.qpos[0] < 1.45 and len(loop.controller.steps) >= 8
    # the next 0.5 s walk at the command (measured 0.49 m/s), the controls finite and within their ranges
    x0, lo, hi, limits = data.qpos[0], *robot.actuated.ctrl_range.T, robot.actuated.torque_limit_Nm
    for _ in range(1000):
        tau = loop.step(command).tau_Nm
        assert np.isfinite(data.ctrl).all() and np.all(loop.ctrl >= lo) and np.all(loop.ctrl <= hi)
        assert np.all(tau >= limits[:, 0]) and np.all(tau <= limits[:, 1])  # N m, the motors' limits
        mujoco.mj_step(model, data)
        assert 0.9 < data.qpos[2] < 1.05
    speed = (data.qpos[0] - x0) / 0.5
    assert abs(speed - command.vx_mps) < 0.1, speed
    assert abs(data.qpos[1]) < 0.25  # little lateral drift (measured 0.10 m)
    assert loop.controller.fallback_ticks == 0 and loop.controller.safe_mode_ticks == 0


def test_the_planner_example_plans_a_step(capsys):
    block = next(b for b in _python_blocks() if "Planner(" in b)
    namespace: dict = {}
    exec(compile(block, "README.md", "exec"), namespace)
    out, kin = namespace["out"], namespace["kin"]
    r_st = kin.contact_position("left")
    # The target is the predicted CoM at T- minus the desired swing-to-CoM offset.
    np.testing.assert_allclose(out.swing_target_world_m[:2], r_st[:2] + out.p_hat_m - out.p_sw_des_world_m, atol=1e-12)
    # The right foot steps to the right of the left stance foot, by a width
    # of the order of the commanded 0.25 m.
    assert 0.1 < r_st[1] - out.swing_target_world_m[1] < 0.45
    assert np.isfinite(out.h_d).all()
    printed = capsys.readouterr().out
    assert "swing foot target" in printed
    assert "np.float64" not in printed, "the example should print plain floats"
