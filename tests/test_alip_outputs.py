"""Tests of amlip_qp.alip.outputs: names, order, values and derivatives of h_d(s)."""

import numpy as np
import pytest

from alip_cases import OUT2, OUT3
from amlip_qp.alip import kernels, outputs
from amlip_qp.exceptions import InputError
from amlip_qp.profiles.outputs import OUTPUT_PRIMITIVES

T, H, ZCL = 0.35, 0.8, 0.08
H0_CASSIE = np.array([0.02, -0.01, 0.04, -0.06, 0.79, -0.21, 0.13, 0.78, 0.05])
H0_RABBIT = np.array([0.03, 0.79, -0.18, 0.77])
TARGET = np.array([0.17, -0.11])


def test_the_kernel_gives_every_declarable_output_in_its_order():
    assert outputs.REFERENCE_OUTPUTS == (
        "torso_pitch", "torso_roll", "stance_hip_yaw", "swing_hip_yaw", "com_z_over_stance",
        "com_x_over_swing", "com_y_over_swing", "com_z_over_swing", "swing_toe_pitch", "swing_foot_roll",
    )  # fmt: skip
    assert set(outputs.REFERENCE_OUTPUTS) == set(OUTPUT_PRIMITIVES)
    assert kernels.swing_reference(np.ones(15)).shape == (3 * len(outputs.REFERENCE_OUTPUTS),)
    assert outputs.OutputSet(OUT3).reference_index.tolist() == list(range(9))
    assert outputs.OutputSet(OUT2).reference_index.tolist() == [0, 4, 5, 7]
    assert outputs.OutputSet(OUT2).planar and not outputs.OutputSet(OUT3).planar


def test_start_and_end_values():
    h, dh, ddh = outputs.reference_outputs(OUT3, 0.0, T, H, ZCL, H0_CASSIE, TARGET, 0.2)
    np.testing.assert_allclose(h, [0, 0, 0.04, -0.06, H, -0.21, 0.13, H, 0], atol=1e-15)
    h, dh, ddh = outputs.reference_outputs(OUT3, 1.0, T, H, ZCL, H0_CASSIE, TARGET, 0.2)
    np.testing.assert_allclose(h, [0, 0, -0.1, 0.1, H, 0.17, -0.11, H, 0], atol=1e-15)
    h, _, _ = outputs.reference_outputs(OUT3, 0.5, T, H, ZCL, H0_CASSIE, TARGET, 0.2)
    assert h[7] == pytest.approx(H - ZCL)


def test_a_subset_takes_the_same_entries_in_its_own_order():
    h0 = H0_CASSIE.copy()
    h0[5] = H0_RABBIT[2]
    hc = outputs.reference_outputs(OUT3, 0.37, T, H, ZCL, h0, TARGET, 0.0)
    hr = outputs.reference_outputs(OUT2, 0.37, T, H, ZCL, H0_RABBIT, TARGET, 0.0)
    idx = [OUT3.index(n) for n in OUT2]
    for a, b in zip(hr, hc):
        assert a.shape == (4,)
        np.testing.assert_allclose(a, b[idx], atol=1e-15)
    assert hr[0][2] == pytest.approx(0.5 * ((1 + np.cos(np.pi * 0.37)) * -0.18 + (1 - np.cos(np.pi * 0.37)) * 0.17))


@pytest.mark.parametrize("robot, h0", [(OUT3, H0_CASSIE), (OUT2, H0_RABBIT)])
def test_derivatives_match_finite_differences(robot, h0):
    dt = 1e-5
    for s in (0.1, 0.33, 0.5, 0.81):
        t = s * T
        h, dh, ddh = outputs.reference_outputs(robot, s, T, H, ZCL, h0, TARGET, 0.25)
        hp = outputs.reference_outputs(robot, (t + dt) / T, T, H, ZCL, h0, TARGET, 0.25)[0]
        hm = outputs.reference_outputs(robot, (t - dt) / T, T, H, ZCL, h0, TARGET, 0.25)[0]
        np.testing.assert_allclose(dh, (hp - hm) / (2 * dt), atol=1e-6)
        np.testing.assert_allclose(ddh, (hp - 2 * h + hm) / dt**2, atol=2e-3)
    assert np.max(np.abs(ddh)) > 1.0  # the check is not vacuous


def test_injected_reference_fn_is_used():
    calls = []

    def fn(u):
        calls.append(np.array(u))
        return kernels.swing_reference(u)

    outputs.reference_outputs(OUT3, 0.2, T, H, ZCL, H0_CASSIE, TARGET, 0.1, reference_fn=fn)
    assert len(calls) == 1
    np.testing.assert_allclose(calls[0], [0.2, T, H, ZCL, 0.04, -0.06, -0.21, 0.13, 0.17, -0.11, 0.1, 0, 0, 0, 0])


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(outputs=("atlas",)), "unknown output 'atlas'"),
        (dict(s=1.2), r"s=1.2 must be in \[0, 1\]"),
        (dict(s=-0.1), r"must be in \[0, 1\]"),
        (dict(s=np.nan), "s must be finite"),
        (dict(T_s=0.0), "T_s.*must be > 0"),
        (dict(H_m=-0.8), "H_m.*must be > 0"),
        (dict(z_cl_m=0.9), "must be smaller than H_m"),
        (dict(z_cl_m=-0.01), "z_cl_m.*>= 0"),
        (dict(h0_start=H0_CASSIE[:4]), r"h0_start must have shape \(9,\)"),
        (dict(h0_start=np.full(9, np.nan)), "h0_start must be finite"),
        (dict(p_sw_des_heading_m=[0.1, np.inf]), "p_sw_des_heading_m must be finite"),
    ],
)
def test_bad_input_raises_input_error(kwargs, match):
    args = dict(outputs=OUT3, s=0.3, T_s=T, H_m=H, z_cl_m=ZCL, h0_start=H0_CASSIE, p_sw_des_heading_m=TARGET)
    args.update(kwargs)
    with pytest.raises(InputError, match=match):
        outputs.reference_outputs(**args)


def test_ground_inputs_reach_the_references_and_are_checked():
    ground = dict(dz_sw0_m=-0.06, dz_sw_m=0.1, slope_pitch0_rad=0.05, slope_pitch_rad=-0.2)
    h0, _, _ = outputs.reference_outputs(OUT3, 0.0, T, H, ZCL, H0_CASSIE, TARGET, 0.2, **ground)
    h1, _, _ = outputs.reference_outputs(OUT3, 1.0, T, H, ZCL, H0_CASSIE, TARGET, 0.2, **ground)
    np.testing.assert_allclose(h0[[4, 7, 8]], [H - 0.06, H, 0.05], atol=1e-15)
    np.testing.assert_allclose(h1[[4, 7, 8]], [H, H - 0.1, -0.2], atol=1e-15)
    r1, _, _ = outputs.reference_outputs(OUT2, 1.0, T, H, ZCL, H0_CASSIE[[0, 4, 5, 7]], TARGET, **ground)
    np.testing.assert_allclose(r1[[1, 3]], [H, H - 0.1], atol=1e-15)
    with pytest.raises(InputError, match="swing foot path too high"):
        outputs.reference_outputs(OUT3, 0.5, T, H, ZCL, H0_CASSIE, TARGET, dz_sw_m=H - ZCL)
    with pytest.raises(InputError, match="slope_pitch_rad=2.0 rad must be within"):
        outputs.reference_outputs(OUT3, 0.5, T, H, ZCL, H0_CASSIE, TARGET, slope_pitch_rad=2.0)
    with pytest.raises(InputError, match="dz_sw0_m must be finite"):
        outputs.reference_outputs(OUT3, 0.5, T, H, ZCL, H0_CASSIE, TARGET, dz_sw0_m=np.nan)


def test_late_descent_is_a_constant_rate_continuation():
    assert outputs.late_descent(0.8, 0.4, 0.05) == (pytest.approx(0.82), 0.4, 0.0)
    assert outputs.late_descent(0.8, 0.4, 0.0) == (0.8, 0.4, 0.0)


def test_split_reference_gives_each_outputs_value_and_derivatives_in_new_memory():
    """``h_d, dh_d, ddh_d`` are the kernel output's entries at the set's indices, in the set's order, in
    memory of their own (writing them leaves the kernel's output alone)."""
    y = np.arange(3 * kernels.N_REFERENCE_OUTPUTS, dtype=float) * 1.5
    n = kernels.N_REFERENCE_OUTPUTS
    for names in (OUT2, OUT3):
        s = outputs.OutputSet(names)
        idx = s.reference_index
        h, dh, ddh = s.split_reference(y)
        for got, want in ((h, y[idx]), (dh, y[n + idx]), (ddh, y[2 * n + idx])):
            np.testing.assert_array_equal(got, want)
            assert got.shape == (len(names),) and not np.shares_memory(got, y)
        h[:] = -1.0
        np.testing.assert_array_equal(dh, y[n + idx])
