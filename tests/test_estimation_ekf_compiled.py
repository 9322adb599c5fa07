"""The generated-C EKF tick against the numpy reference (same estimate to rounding), leg kinematics
included, over contact changes."""

import numpy as np
import pytest

from amlip_qp.estimation import make_base_estimator
from amlip_qp.estimation.bench import stand_in_measurements
from amlip_qp.estimation.invariant_ekf import EkfNoise
from amlip_qp.robots import load_robot

IMU = [0.03, 0.0, 0.09]


@pytest.fixture(scope="module")
def cassie():
    return load_robot("cassie")


@pytest.mark.parametrize("ground_pitch_rad", [0.0, -0.4])
def test_the_compiled_tick_equals_the_numpy_filter(cassie, ground_pitch_rad):
    """Level ground, and a ground pitched 0.4 rad up along the heading that the blades are taken
    flat against (``set_ground_pitch``)."""
    ms = stand_in_measurements(cassie, 1500, seed=3)
    rng = np.random.default_rng(4)
    for m in ms:  # the joints move independently, so each leg's chain is exercised
        m.q[7:] += 0.3 * rng.normal(size=cassie.nq - 7)
    noise = EkfNoise(max_blade_slope_rad=0.3)  # the joints jitter by 0.3 rad: some blades are that flat
    ref = make_base_estimator("ekf", cassie, 0.0005, IMU, noise=noise, backend="numpy")
    c = make_base_estimator("ekf", cassie, 0.0005, IMU, noise=noise, backend="c")
    assert c.compiled is not None
    for est in (ref, c):
        est.set_ground_pitch(ground_pitch_rad)
    worst = 0.0
    used, gated = 0, 0  # ticks a switched-on foot was used / left out (its blade not flat)
    for m in ms:
        a, b = ref.fill(m), c.fill(m)
        worst = max(worst, np.abs(a.q - b.q).max(), np.abs(a.v - b.v).max())
        assert tuple(c.compiled.contacts == 1.0) == ref.ekf.in_contact
        switches = [m.foot_contact[s] for s in cassie.foot_sides]
        used += sum(ref.ekf.in_contact)
        gated += sum(s and not u for s, u in zip(switches, ref.ekf.in_contact))
    assert worst < 1e-10
    assert used > 100 and gated > 100  # both branches of the flat-blade gate ran
    sa, sb = ref.state(), c.state()
    for name in ("R", "v", "p", "d", "bg", "ba", "P"):
        np.testing.assert_allclose(getattr(sb, name), getattr(sa, name), atol=1e-10, err_msg=name)
    assert sa.P[0, 0] > 0 and np.abs(sa.bg).max() > 0  # a filter that moved, not a trivial one
