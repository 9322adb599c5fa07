"""Tests of amlip_qp.messages: Command, StateEstimate and PlannerOutput, their conversion and validation."""

import math

import numpy as np
import pytest

from alip_cases import H, cmd, est
from amlip_qp.exceptions import InputError


def test_dataclasses_are_frozen():
    c = cmd()
    with pytest.raises(AttributeError):
        c.vx_mps = 2.0  # type: ignore[misc]
    e = est()
    assert isinstance(e.p_st_m, np.ndarray) and e.p_st_m.dtype == np.float64


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(step_time_s=0.0), r"step_time_s \(T\) must be > 0"),
        (dict(step_time_s=-0.3), r"step_time_s \(T\) must be > 0"),
        (dict(com_height_m=0.0), r"com_height_m \(H\) must be > 0"),
        (dict(com_height_m=-1.0, clearance_m=0.0), r"com_height_m \(H\) must be > 0"),
        (dict(clearance_m=0.95), r"clearance_m \(z_cl\) must satisfy"),
        (dict(clearance_m=-0.01), r"clearance_m \(z_cl\) must satisfy"),
        (dict(step_width_m=-0.1), "step_width_m must be >= 0"),
        (dict(vx_mps=float("nan")), "vx_mps must be a finite number"),
        (dict(turn_rate_radps=float("inf")), "turn_rate_radps must be a finite number"),
        (dict(vy_mps="fast"), "vy_mps must be a finite number"),
        (dict(step_time_s=True), "step_time_s must be a finite number"),
    ],
)
def test_bad_command_raises_input_error(kw, match):
    with pytest.raises(InputError, match=match):
        cmd(**kw)


def test_with_speeds_is_replace_checking_the_two_speeds():
    from dataclasses import replace

    c = cmd(turn_rate_radps=0.2)
    for vx, turn in ((1.25, -0.0), (-0.0, 0.3), (np.float64(0.7), 2)):
        got, ref = c.with_speeds(vx, turn), replace(c, vx_mps=vx, turn_rate_radps=turn)
        assert type(got) is type(ref) and got == ref and repr(got) == repr(ref)
        assert [type(getattr(got, f)) for f in got.__slots__] == [type(getattr(ref, f)) for f in ref.__slots__]
    assert math.copysign(1.0, c.with_speeds(-0.0, 0.0).vx_mps) == -1.0
    with pytest.raises(AttributeError):
        c.with_speeds(1.0, 0.0).vx_mps = 2.0  # type: ignore[misc]
    for vx, turn, match in ((np.nan, 0.0, "vx_mps"), (1.0, np.inf, "turn_rate_radps"), (True, 0.0, "vx_mps")):
        with pytest.raises(InputError, match=f"Command.{match} must be a finite number"):
            c.with_speeds(vx, turn)


def test_with_velocity_is_replace_checking_the_two_speeds():
    from dataclasses import replace

    c = cmd(turn_rate_radps=0.2, vy_mps=0.1)
    for vx, vy in ((1.25, -0.0), (-0.0, 0.3), (np.float64(0.7), 2)):
        got, ref = c.with_velocity(vx, vy), replace(c, vx_mps=vx, vy_mps=vy)
        assert type(got) is type(ref) and got == ref and repr(got) == repr(ref)
        assert [type(getattr(got, f)) for f in got.__slots__] == [type(getattr(ref, f)) for f in ref.__slots__]
    assert math.copysign(1.0, c.with_velocity(0.5, -0.0).vy_mps) == -1.0
    for vx, vy, match in ((np.nan, 0.0, "vx_mps"), (1.0, -np.inf, "vy_mps"), (0.0, False, "vy_mps")):
        with pytest.raises(InputError, match=f"Command.{match} must be a finite number"):
            c.with_velocity(vx, vy)


def test_with_step_time_is_replace_checking_the_time():
    from dataclasses import replace

    c = cmd(turn_rate_radps=0.2, vy_mps=0.1)
    for T in (0.25, np.float64(0.31), 1):
        got, ref = c.with_step_time(T), replace(c, step_time_s=T)
        assert type(got) is type(ref) and got == ref and repr(got) == repr(ref)
    for bad in (0.0, -0.1, np.inf, np.nan, True):
        with pytest.raises(InputError, match="Command.step_time_s"):
            c.with_step_time(bad)


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(stance="middle"), "stance must be 'left' or 'right'"),
        (dict(p_st_m=[0.0, np.nan, H]), r"NaN or inf in \['p_st_m'\]"),
        (dict(L_Nms=[np.inf, 0.0, 0.0]), r"NaN or inf in \['L_Nms'\]"),
        (dict(com_m=[0.0, 0.0, -np.inf]), r"NaN or inf in \['com_m'\]"),
        (dict(v_z_mps=np.nan), r"NaN or inf in \['v_z_mps'\]"),
        (dict(t_in_step_s=np.inf), r"NaN or inf in \['t_in_step_s'\]"),
        (dict(t_in_step_s=-0.01), "t_in_step_s must be >= 0"),
        (dict(p_st_m=[0.0, 0.1]), r"p_st_m must have shape \(3,\)"),
        (dict(L_Nms="abc"), "L_Nms must be 3 numbers"),
        (dict(v_z_mps="fast"), "v_z_mps and t_in_step_s must be numbers"),
    ],
)
def test_bad_estimate_raises_input_error(kw, match):
    with pytest.raises(InputError, match=match):
        est(**kw)


def test_state_estimate_converts_other_inputs_to_float64():
    """Lists, integer and float32 arrays take the checked conversion path; float64 arrays are kept."""
    p = np.array([0.03, -0.1, H])
    e = est(p_st_m=p, L_Nms=np.array([1, 12, 0]), com_m=np.array([1.0, 0.5, H], dtype=np.float32))
    assert e.p_st_m is p
    for a in (e.L_Nms, e.com_m):
        assert isinstance(a, np.ndarray) and a.dtype == np.float64 and a.shape == (3,)
    np.testing.assert_array_equal(e.L_Nms, [1.0, 12.0, 0.0])
    with pytest.raises(InputError, match=r"com_m must have shape \(3,\)"):
        est(com_m=np.zeros(4))
    with pytest.raises(InputError, match=r"NaN or inf in \['L_Nms'\]"):
        est(L_Nms=np.array([0.0, np.nan, 0.0]))


def test_terrain_prediction_defaults_to_flat_ground_and_is_validated():
    from amlip_qp.messages import TerrainPrediction

    flat = TerrainPrediction()
    assert (flat.dz_next_m, flat.dz_sw_m, flat.dz_sw0_m, flat.slope_pitch_rad, flat.slope_pitch0_rad) == (0.0,) * 5
    t = TerrainPrediction(dz_next_m=np.float32(0.1), dz_sw_m=1)
    assert type(t.dz_next_m) is float and t.dz_sw_m == 1.0
    with pytest.raises(AttributeError):
        t.dz_sw_m = 0.0  # type: ignore[misc]
    for kw, match in [
        (dict(dz_next_m=np.nan), "dz_next_m must be a finite number"),
        (dict(dz_sw_m="up"), "dz_sw_m must be a finite number"),
        (dict(dz_sw0_m=True), "dz_sw0_m must be a finite number"),
        (dict(slope_pitch_rad=1.6), r"slope_pitch_rad must be within \(-pi/2, pi/2\)"),
        (dict(slope_pitch0_rad=-2.0), r"slope_pitch0_rad must be within"),
    ]:
        with pytest.raises(InputError, match=match):
            TerrainPrediction(**kw)
