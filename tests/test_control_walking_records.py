"""What the walking controller reports: the step record, the tick's signals, the NaN signals of a safe-mode tick."""

import dataclasses
import math

import numpy as np
import pytest

from amlip_qp.control.walking import controller, records
from amlip_qp.control.walking.records import StepRecord, TickInfo, nan_tick_signals


@pytest.mark.parametrize("n_outputs", [4, 9])
def test_nan_tick_signals_are_all_nan_with_the_planner_shapes(n_outputs):
    est, plan, h = nan_tick_signals(n_outputs)
    assert h.shape == (n_outputs,) and np.isnan(h).all()
    for f in dataclasses.fields(est):
        value = getattr(est, f.name)
        assert value.shape == (3,) and np.isnan(value).all(), f.name
    shapes = {"L_hat_Nms": 2, "p_hat_m": 2, "L_des_Nms": 2, "p_sw_des_world_m": 2, "p_sw_des_heading_m": 2,
              "swing_target_world_m": 3, "h_d": n_outputs, "dh_d": n_outputs, "ddh_d": n_outputs}  # fmt: skip
    for name, size in shapes.items():
        value = getattr(plan, name)
        assert value.shape == (size,) and np.isnan(value).all(), name
    for name in ("s", "t_remaining_s", "heading_rad", "heading_next_rad", "turn_rad", "v_z_used_mps"):
        assert math.isnan(getattr(plan, name)), name
    # fresh arrays per call: a log that writes one leaves the next alone
    h[0] = 1.0
    assert np.isnan(nan_tick_signals(n_outputs)[2]).all()


def test_a_step_record_defaults_to_zero_velocity_and_correction_of_its_own():
    def record():
        z3 = np.zeros(3)
        return StepRecord(0.1, 0.45, "left", z3, z3, np.zeros(2), np.full(2, np.nan), z3, 0.2)

    a, b = record(), record()
    assert a.t_end_s - a.t_start_s == pytest.approx(0.35) and a.heading_rad == 0.2
    assert a.mean_velocity_heading_mps.tolist() == [0.0, 0.0] and a.speed_correction_mps.tolist() == [0.0, 0.0]
    a.speed_correction_mps[0] = 0.1
    assert b.speed_correction_mps[0] == 0.0


def test_tick_info_keeps_references_and_an_info_dict_of_its_own():
    est, plan, h = nan_tick_signals(4)
    tau = np.array([1.0, -2.0, 0.5, 0.0])
    a = TickInfo(0.5, "right", 0.25, est, plan, h, tau, True, False)
    b = TickInfo(0.5, "right", 0.25, est, plan, h, tau, True, False)
    assert a.tau_Nm is tau and a.h is h and a.phase == 0.25  # references, not copies
    a.info["safe_mode"] = True
    assert b.info == {}


def test_the_controller_module_still_exports_the_records():
    assert controller.StepRecord is records.StepRecord and controller.TickInfo is records.TickInfo
