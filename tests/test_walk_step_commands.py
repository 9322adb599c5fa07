"""Step commands from rest walk, with each tracker.

Each case of ``examples/step_commands.py`` (its ``CASES``, walked by its
``walk``, which prints the table of docs/RESULTS.md) is exactly
``amlip-qp walk --robot R --tracker T --vx V``: the
CLI's scenario (the robot's default gait, 10 s, a constant ``--vx`` from
t = 0, i.e. a step from rest), built and summarised as the CLI does. The
command shaping (:mod:`amlip_qp.alip.command_shaping`) turns the step into a
ramp; the robot must walk the 10 s and its mean speed over the last 3 s (the
summary's ``mean_velocity[0]``, heading frame) must be within 0.1 m/s of the
command.

The selected cases run once, in two worker processes (one per core), the
slowest first. Wall time of the 14: 3 min 40 s on the 2 shared cores (load
average 2.6-3.9 from other jobs), 4 min CPU.

Measured mean speeds (m/s), PBC / QP (docs/RESULTS.md, "Step commands from
rest"): Cassie 1.0: 0.998 / 1.000, 2.0: 1.995 / 2.002, 2.5: 2.501 / 2.495,
-0.5: -0.499 / -0.500; Rabbit 0.5: 0.501 / 0.502, 0.8: 0.798 / 0.802, 1.0:
0.992 / 1.000.
"""

from __future__ import annotations

import importlib.util
import pathlib
import sys

import pytest

pytestmark = pytest.mark.slow

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _example():
    """``examples/step_commands.py``: the cases and the walk, which also prints RESULTS.md's table."""
    spec = importlib.util.spec_from_file_location("step_commands", ROOT / "examples" / "step_commands.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["step_commands"] = module  # the worker processes find its walk by this name
    spec.loader.exec_module(module)
    return module


STEP_COMMANDS = _example()
#: (robot, tracker, vx m/s): each tracker walks these step commands (the example's list).
CASES = STEP_COMMANDS.CASES

#: Largest |mean speed - command| over the last 3 s, m/s.
SPEED_TOL_MPS = 0.1


@pytest.fixture(scope="module")
def results(request) -> dict:
    """The selected cases, run once in two worker processes (a ``-k`` selection runs only its cases)."""
    selected = [
        item.callspec.params["case"]
        for item in request.session.items
        if item.module is request.module and hasattr(item, "callspec") and "case" in item.callspec.params
    ]
    out = STEP_COMMANDS.walk_all(selected, jobs=2)
    for (robot, tracker, vx), r in out.items():  # the numbers, for the log (pytest -s)
        print(f"\n{robot} {tracker} --vx {vx}: fell={r['fell']} mean vx={r['mean_vx_mps']:.3f}")
    return out


@pytest.mark.parametrize("case", CASES, ids=[f"{r}-{t}-{v}" for r, t, v in CASES])
def test_a_step_command_from_rest_walks_at_the_commanded_speed(results, case):
    r = results[case]
    assert not r["fell"], f"fell at {r['fall_time_s']} s"
    assert r["sim_time_s"] == pytest.approx(r["duration_s"], abs=1e-3)
    assert abs(r["mean_vx_mps"] - case[2]) <= SPEED_TOL_MPS, r["mean_vx_mps"]
