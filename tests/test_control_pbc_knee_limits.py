"""Tests of the IK's straight-knee handling (amlip_qp.control.pbc.knee_limits)."""

import numpy as np
import pytest

from amlip_qp.control.pbc.ik_settings import IKSettings
from amlip_qp.control.pbc.knee_limits import KneeLimits, swap_rows
from amlip_qp.robots import OutputMap, load_robot


@pytest.fixture(scope="module")
def cassie():
    return load_robot("cassie")


def test_cassie_stance_and_swing_knees_with_their_straight_leg_limits(cassie):
    knees = KneeLimits(cassie, IKSettings())
    names = list(OutputMap(cassie).names)
    smap, m = cassie.state_map, cassie.pin_model
    for stance, swing in (("left", "right"), ("right", "left")):
        entries = {names[row]: (iq, iv, limit, other) for row, iq, iv, limit, other in knees.entries(stance)}
        assert set(entries) == {"com_z_over_stance", "com_x_over_swing"}
        assert entries["com_z_over_stance"][:2] == (
            smap.joint_pin_q[f"{stance}-knee"],
            smap.joint_pin_v[f"{stance}-knee"],
        )
        assert entries["com_x_over_swing"][:2] == (smap.joint_pin_q[f"{swing}-knee"], smap.joint_pin_v[f"{swing}-knee"])
        for iq, _, limit, other in entries.values():
            assert {limit, other} == {float(m.lowerPositionLimit[iq]), float(m.upperPositionLimit[iq])}


def test_split_swaps_an_unreachable_output_and_backs_off_a_reachable_one(cassie):
    knees = KneeLimits(cassie, IKSettings(swap_threshold=1e-3))
    row, iq, _, limit, _ = next(e for e in knees.entries("left") if e[0] == 4)  # com_z_over_stance
    q = np.zeros(cassie.nq)
    q[iq] = limit
    y, F = np.zeros(9), np.full(cassie.nv, 0.01)
    h_d = np.zeros(9)
    y[row], h_d[row] = 0.8, 1.1  # the CoM cannot reach 1.1 m: swap
    swap, back = knees.split("left", q, F, y, h_d)
    assert swap is not None and [e[0] for e in swap] == [row] and back == []
    h_d[row] = 0.7  # reachable: the straight knee is only a bad iterate
    swap, back = knees.split("left", q, F, y, h_d)
    assert swap is None and [e[0] for e in back] == [row]
    assert knees.split("left", q, np.zeros(cassie.nv), y, h_d) == (None, [])  # converged: nothing


def test_swap_rows_replaces_the_output_row_by_the_knee_row():
    A, F = np.ones((3, 4)), np.ones(3)
    q = np.array([0.0, 0.0, 0.25])
    swap_rows([(1, 2, 3, 0.5, -1.0)], q, A, F)
    np.testing.assert_array_equal(A[1], [0.0, 0.0, 0.0, 1.0])
    assert F[1] == pytest.approx(-0.25) and A[0].sum() == 4.0 and F[0] == 1.0
    swap_rows(None, q, A, F)  # nothing to swap: unchanged
    assert A[1, 3] == 1.0


def test_rabbit_has_no_coupling_but_its_knees_count_too():
    """Rabbit's layout has com_z_over_stance and com_x_over_swing too: both knees per stance."""
    rabbit = load_robot("rabbit")
    knees = KneeLimits(rabbit, IKSettings())
    assert len(knees.entries("left")) == len(knees.entries("right")) == 2


def test_split_holds_a_knee_short_of_its_limit_at_its_estimate_when_its_output_is_out_of_reach(cassie):
    """An output out of reach with the knee off its limit (a fold inside the range): with the
    estimate given, the knee is exchanged for "knee = its estimate"; without it, as before, nothing."""
    knees = KneeLimits(cassie, IKSettings(swap_threshold=1e-3))
    row, iq, iv, limit, other = next(e for e in knees.entries("left") if e[0] == 4)  # com_z_over_stance
    q = np.zeros(cassie.nq)
    q[iq] = limit + 0.3 * (other - limit)  # off the limit
    q_est = np.zeros(cassie.nq)
    q_est[iq] = limit + 0.4 * (other - limit)
    y, F, h_d = np.zeros(9), np.full(cassie.nv, 0.01), np.zeros(9)
    y[row], h_d[row] = 0.79, 0.80  # 1 cm short
    assert knees.split("left", q, F, y, h_d) == (None, [])
    swap, back = knees.split("left", q, F, y, h_d, q_est)
    assert back == [] and swap == [(row, iq, iv, pytest.approx(q_est[iq]), other)]
    y[row] = 0.8  # reachable: nothing
    assert knees.split("left", q, F, y, h_d, q_est) == (None, [])
    # an estimate outside the knee's range is clipped to it
    q_est[iq] = max(limit, other) + 0.5
    y[row] = 0.79
    swap, _ = knees.split("left", q, F, y, h_d, q_est)
    assert swap is not None and swap[0][3] == max(limit, other)


def test_only_the_stance_knee_is_held_short_of_its_limit(cassie):
    """The swing knee's output (com_x_over_swing) out of reach short of its limit: no hold, and
    short_of_limit says so; the stance CoM height out of reach: short_of_limit, unless converged."""
    knees = KneeLimits(cassie, IKSettings(swap_threshold=1e-3))
    row_sw, iq_sw, _, lim_sw, oth_sw = next(e for e in knees.entries("left") if e[0] == 5)  # com_x_over_swing
    row_st, iq_st, _, lim_st, oth_st = next(e for e in knees.entries("left") if e[0] == 4)
    q = np.zeros(cassie.nq)
    q[iq_sw] = lim_sw + 0.3 * (oth_sw - lim_sw)
    q[iq_st] = lim_st + 0.3 * (oth_st - lim_st)
    y, F, h_d = np.zeros(9), np.full(cassie.nv, 0.01), np.zeros(9)
    y[row_sw], h_d[row_sw] = 0.30, 0.50  # the swing foot 20 cm short
    assert not knees.short_of_limit("left", q, F, y, h_d)
    assert knees.split("left", q, F, y, h_d, q.copy()) == (None, [])
    y[row_st], h_d[row_st] = 0.79, 0.80  # and the CoM 1 cm low
    assert knees.short_of_limit("left", q, F, y, h_d)
    swap, _ = knees.split("left", q, F, y, h_d, q.copy())
    assert swap is not None and [e[0] for e in swap] == [row_st]
    assert not knees.short_of_limit("left", q, np.zeros(cassie.nv), y, h_d)  # converged
