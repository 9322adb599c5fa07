"""Closed-loop tests: a 3-D constant-height point-mass LIP walking with the Planner.

The simulator is independent of the planner code: it integrates the point mass
exactly (c_xy'' = g/H (c - r)_xy at constant height), recomputes the angular
momentum about the contact as L = (c - r) x m v, and at touchdown moves the
contact to the planner's last ``swing_target_world_m``, checking the momentum
transfer L_2 = L_1 + (r_1 - r_2) x m v against the recomputed value.
"""

import numpy as np
import pytest

from alip_cases import OUT2, OUT3
from amlip_qp.alip import Planner, desired
from amlip_qp.alip.heading import world_to_heading
from amlip_qp.messages import Command, StateEstimate

M, H, G, T, DT = 32.0, 0.85, 9.81, 0.32, 1e-3
N_TICK = int(round(T / DT))
LAM = np.sqrt(G / H)


class PointMassLIP:
    """Constant-height point mass over a point contact on flat ground (z = 0)."""

    def __init__(self, c, v, r_st, stance):
        self.c = np.array(c, dtype=float)
        self.v = np.array(v, dtype=float)
        self.r = np.array(r_st, dtype=float)
        self.stance = stance
        self.transfer_errors = []

    def L(self, r=None):
        r = self.r if r is None else r
        return np.cross(self.c - r, M * self.v)

    def advance(self, dt):
        p = self.c[:2] - self.r[:2]
        ch, sh = np.cosh(LAM * dt), np.sinh(LAM * dt)
        p_new = p * ch + self.v[:2] / LAM * sh
        self.v[:2] = p * LAM * sh + self.v[:2] * ch
        self.c[:2] = self.r[:2] + p_new

    def touchdown(self, r_new):
        r_new = np.array([r_new[0], r_new[1], 0.0])
        L1 = self.L()
        L2 = L1 + np.cross(self.r - r_new, M * self.v)  # exact transfer
        self.transfer_errors.append(np.max(np.abs(L2 - self.L(r_new))))
        self.r = r_new
        self.stance = "right" if self.stance == "left" else "left"


def h0_of(sim, r_swing, heading_rad):
    """Cassie outputs at the step start for a point mass (ideal tracking: zeros for the orientation terms)."""
    xy = world_to_heading(sim.c[:2] - r_swing[:2], heading_rad)
    return np.array([0.0, 0.0, 0.0, 0.0, sim.c[2] - sim.r[2], xy[0], xy[1], sim.c[2] - r_swing[2], 0.0])


def walk(sim, planner, commands, t0=0.0):
    """Walk one step per command; returns per-step records (CoM at start/end, end velocity, contacts, headings)."""
    t = t0
    r_prev = sim.r - np.array([0.0, 0.2 if sim.stance == "left" else -0.2, 0.0])
    records = []
    for cmd in commands:
        planner.start_step(sim.stance, t, h0_of(sim, r_prev, planner.heading_next_rad))
        c_start = sim.c.copy()
        out = None
        for i in range(N_TICK):
            est = StateEstimate(
                stance=sim.stance, p_st_m=sim.c - sim.r, L_Nms=sim.L(), v_z_mps=sim.v[2],
                t_in_step_s=i * DT, com_m=sim.c.copy(),
            )  # fmt: skip
            out = planner.update(est, cmd)
            sim.advance(DT)
        t += T
        records.append(
            dict(c_start=c_start, c_end=sim.c.copy(), v_end=sim.v.copy(), r_st=sim.r.copy(), D=planner.heading_rad,
                 L_des=out.L_des_Nms, L_end=sim.L()[:2], target=out.swing_target_world_m)
        )  # fmt: skip
        r_prev = sim.r.copy()
        sim.touchdown(out.swing_target_world_m)
    return records


def _perturbed_sim(rng, stance="left"):
    c = np.array([rng.uniform(-0.05, 0.05), rng.uniform(-0.12, -0.02), H])
    v = np.array([rng.uniform(-0.3, 0.8), rng.uniform(-0.3, 0.3), 0.0])
    return PointMassLIP(c, v, [0.0, 0.0, 0.0], stance)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_converges_to_commanded_forward_speed(seed):
    rng = np.random.default_rng(seed)
    sim = _perturbed_sim(rng)
    planner = Planner(OUT3, M, G)
    cmd = Command(step_time_s=T, com_height_m=H, clearance_m=0.08, vx_mps=0.6, step_width_m=0.2)
    rec = walk(sim, planner, [cmd] * 8)
    v_mean = np.array([(r["c_end"] - r["c_start"])[:2] / T for r in rec])
    stride_mean_y = 0.5 * (v_mean[-1, 1] + v_mean[-2, 1])
    err_x = np.max(np.abs(v_mean[-4:, 0] - 0.6))
    v_end_expected = desired.end_of_step_velocity(0.6, T, H, G)
    print(
        f"seed {seed}: first-step mean vx {v_mean[0, 0]:.3f}, final |mean vx - 0.6| = {err_x:.2e}, "
        f"lateral stride mean {stride_mean_y:.2e}"
    )
    assert abs(v_mean[0, 0] - 0.6) > 1e-2  # the initial state is really perturbed
    assert err_x < 1e-3
    assert abs(stride_mean_y) < 1e-3
    assert rec[-1]["v_end"][0] == pytest.approx(v_end_expected, abs=1e-3)
    # Deadbeat: from the second step on, L at the end of each step is the L_des planned a step before.
    for prev, cur in zip(rec[1:-1], rec[2:]):
        np.testing.assert_allclose(cur["L_end"], prev["L_des"], atol=1e-6)
    assert max(sim.transfer_errors) < 1e-12


def test_walking_in_place_gives_the_step_width_and_no_drift():
    rng = np.random.default_rng(3)
    sim = _perturbed_sim(rng)
    W = 0.24
    planner = Planner(OUT3, M, G)
    cmd = Command(step_time_s=T, com_height_m=H, clearance_m=0.08, step_width_m=W)
    rec = walk(sim, planner, [cmd] * 10)
    contacts = np.array([r["r_st"] for r in rec])
    widths = np.abs(np.diff(contacts[:, 1]))
    drift_x = rec[-1]["c_end"][0] - rec[-3]["c_end"][0]
    drift_y = rec[-1]["c_end"][1] - rec[-3]["c_end"][1]
    print(f"in place: widths {widths[-4:]}, 2-step drift ({drift_x:.1e}, {drift_y:.1e}) m")
    np.testing.assert_allclose(widths[-4:], W, atol=1e-3)
    assert abs(np.diff(contacts[-4:, 0])).max() < 1e-3
    assert abs(drift_x) < 1e-3 and abs(drift_y) < 1e-3
    # The left foot is left of the right foot.
    for r_left, r_right in zip(contacts[-4::2], contacts[-3::2]):
        assert r_left[1] > r_right[1]


def test_diagonal_walking_reaches_vx_vy():
    rng = np.random.default_rng(4)
    sim = _perturbed_sim(rng)
    planner = Planner(OUT3, M, G)
    cmd = Command(step_time_s=T, com_height_m=H, clearance_m=0.08, vx_mps=0.4, vy_mps=0.2, step_width_m=0.2)
    rec = walk(sim, planner, [cmd] * 10)
    stride = (rec[-1]["c_end"] - rec[-3]["c_end"])[:2] / (2 * T)
    print(f"diagonal: stride mean velocity {stride}")
    np.testing.assert_allclose(stride, [0.4, 0.2], atol=1e-3)


def test_turning_90_degrees():
    rng = np.random.default_rng(5)
    sim = _perturbed_sim(rng)
    planner = Planner(OUT3, M, G)
    n_turn = 10
    rate = (np.pi / 2) / (n_turn * T)  # ~28 deg/s
    turn = Command(step_time_s=T, com_height_m=H, clearance_m=0.08, vx_mps=0.5, step_width_m=0.2, turn_rate_radps=rate)
    straight = Command(step_time_s=T, com_height_m=H, clearance_m=0.08, vx_mps=0.5, step_width_m=0.2)
    rec = walk(sim, planner, [straight] * 2 + [turn] * n_turn + [straight] * 6)
    headings = np.array([r["D"] for r in rec])
    stride = (rec[-1]["c_end"] - rec[-3]["c_end"])[:2] / (2 * T)
    direction_deg = np.degrees(np.arctan2(stride[1], stride[0]))
    print(
        f"turn: final heading {np.degrees(headings[-1]):.3f} deg, stride velocity {stride}, "
        f"direction {direction_deg:.3f} deg"
    )
    assert np.degrees(headings[-1]) == pytest.approx(90.0, abs=1e-9)
    np.testing.assert_allclose(np.diff(headings[2:13]), rate * T, atol=1e-12)
    assert direction_deg == pytest.approx(90.0, abs=2.0)
    np.testing.assert_allclose(stride, [0.0, 0.5], atol=1e-3)
    # Velocity along the new heading: the heading-frame components.
    np.testing.assert_allclose(world_to_heading(stride, headings[-1]), [0.5, 0.0], atol=1e-3)


def test_rabbit_planar_walk_converges():
    rng = np.random.default_rng(6)
    sim = PointMassLIP([rng.uniform(-0.1, 0.0), 0.0, H], [0.1, 0.0, 0.0], [0.0, 0.0, 0.0], "left")
    planner = Planner(OUT2, M, G)
    cmd = Command(step_time_s=T, com_height_m=H, clearance_m=0.05, vx_mps=0.8, step_width_m=0.2, vy_mps=0.3)
    t = 0.0
    r_prev = sim.r - np.array([0.2, 0.0, 0.0])
    v_mean = []
    for _ in range(6):
        h0 = np.array([0.0, H, sim.c[0] - r_prev[0], H])
        planner.start_step(sim.stance, t, h0)
        c0 = sim.c.copy()
        for i in range(N_TICK):
            est = StateEstimate(stance=sim.stance, p_st_m=sim.c - sim.r, L_Nms=sim.L(), v_z_mps=0.0,
                                t_in_step_s=i * DT, com_m=sim.c.copy())  # fmt: skip
            out = planner.update(est, cmd)
            assert out.h_d.shape == (4,)
            sim.advance(DT)
        t += T
        v_mean.append((sim.c - c0) / T)
        r_prev = sim.r.copy()
        sim.touchdown(out.swing_target_world_m)
    print(f"rabbit: mean vx per step {np.array(v_mean)[:, 0]}")
    assert v_mean[-1][0] == pytest.approx(0.8, abs=1e-3)
    assert abs(v_mean[-1][1]) < 1e-12  # lateral command ignored by the planar robot


class PointMassOnSlope:
    """A point mass on the constraint plane z = k x + H over the ground z = k x (slope along world x).

    Kajita's LIP on a plane: with the contact force along p = c - r and the CoM
    kept on the plane, m c'' = (m g / H) p - m g e_z, so the horizontal motion is
    the flat LIP p_xy'' = (g/H) p_xy exactly, for any grade k, and v_z = k v_x.
    The angular momentum about the contact is L = p x m v (recomputed, not the
    planner's pairs). At touchdown the contact moves to the ground under the
    planner's target, and L about it is checked against the transfer
    L_2 = L_1 + (r_1 - r_2) x m v with the contacts' height difference.
    """

    def __init__(self, k, c_xy, v_xy, stance):
        self.k = k
        self.r = np.zeros(3)
        self.c = np.array([c_xy[0], c_xy[1], k * c_xy[0] + H])
        self.v = np.array([v_xy[0], v_xy[1], k * v_xy[0]])
        self.stance = stance
        self.transfer_errors = []

    def L(self, r=None):
        return np.cross(self.c - (self.r if r is None else r), M * self.v)

    def advance(self, dt):
        p = self.c[:2] - self.r[:2]
        ch, sh = np.cosh(LAM * dt), np.sinh(LAM * dt)
        self.c[:2] = self.r[:2] + p * ch + self.v[:2] / LAM * sh
        self.v[:2] = p * LAM * sh + self.v[:2] * ch
        self.c[2], self.v[2] = self.k * self.c[0] + H, self.k * self.v[0]

    def vz_at_touchdown(self, t_rem):
        """The CoM's vertical velocity at the end of the step, predicted exactly (the planner's v_z input)."""
        p_x = self.c[0] - self.r[0]
        return self.k * (p_x * LAM * np.sinh(LAM * t_rem) + self.v[0] * np.cosh(LAM * t_rem))

    def touchdown(self, target_xy):
        r_new = np.array([target_xy[0], target_xy[1], self.k * target_xy[0]])
        L2 = self.L() + np.cross(self.r - r_new, M * self.v)
        self.transfer_errors.append(np.max(np.abs(L2 - self.L(r_new))))
        self.r = r_new
        self.stance = "right" if self.stance == "left" else "left"


def walk_on_slope(slope_deg, full_transfer, n_steps=8, seed=7):
    """Walk the slope sim with the Planner. The height difference to the next contact is the ground's at the
    previous tick's target, as a controller gets it: the law is a contraction in it, converged by touchdown."""
    from amlip_qp.messages import TerrainPrediction

    k = np.tan(np.radians(slope_deg))
    rng = np.random.default_rng(seed)
    sim = PointMassOnSlope(k, [rng.uniform(-0.05, 0.05), rng.uniform(-0.12, -0.02)], [0.1, 0.1], "left")
    planner = Planner(OUT3, M, G)
    cmd = Command(step_time_s=T, com_height_m=H, clearance_m=0.08, vx_mps=0.6, step_width_m=0.2)
    t, records = 0.0, []
    r_prev = sim.r - np.array([0.0, 0.2, 0.0])
    target = sim.r[:2].copy()
    for _ in range(n_steps):
        planner.start_step(sim.stance, t, h0_of(sim, r_prev, planner.heading_next_rad))
        c_start = sim.c.copy()
        for i in range(N_TICK):
            t_in = i * DT
            est = StateEstimate(
                stance=sim.stance, p_st_m=sim.c - sim.r, L_Nms=sim.L(), v_z_mps=sim.vz_at_touchdown(T - t_in),
                t_in_step_s=t_in, com_m=sim.c.copy(),
            )  # fmt: skip
            dz = k * (target[0] - sim.r[0])
            terrain = TerrainPrediction(dz_next_m=dz, dz_sw_m=dz) if full_transfer else None
            out = planner.update(est, cmd, terrain)
            target = out.swing_target_world_m[:2].copy()
            sim.advance(DT)
        t += T
        records.append(dict(c_start=c_start, c_end=sim.c.copy(), L_des=out.L_des_Nms, L_end=sim.L()[:2]))
        r_prev = sim.r.copy()
        sim.touchdown(target)
    return sim, records


@pytest.mark.parametrize("slope_deg", [0.0, 10.0, -10.0, 15.0, -15.0])
def test_full_transfer_placement_is_deadbeat_on_a_slope(slope_deg):
    """docs/ALIP_SLOPES.md: on the slope LIP the sagittal pair is exactly the flat ALIP and the full transfer
    (v_z and dz) makes the placement deadbeat; the v_z-only law of flat ground misses L_des every step."""
    sim, rec = walk_on_slope(slope_deg, full_transfer=True)
    assert max(sim.transfer_errors) < 1e-12
    err_y = [abs(cur["L_end"][1] - prev["L_des"][1]) for prev, cur in zip(rec[1:-1], rec[2:])]
    err_x = [abs(cur["L_end"][0] - prev["L_des"][0]) for prev, cur in zip(rec[1:-1], rec[2:])]
    _, old = walk_on_slope(slope_deg, full_transfer=False)
    old_y = [abs(cur["L_end"][1] - prev["L_des"][1]) for prev, cur in zip(old[1:-1], old[2:])]
    v_mean = (rec[-1]["c_end"][0] - rec[-3]["c_end"][0]) / (2 * T)
    L_ref = M * H * 0.6
    print(
        f"slope {slope_deg:+.0f} deg: sagittal |L_end - L_des| max {max(err_y):.1e} (v_z-only law {max(old_y):.2e}), "
        f"lateral max {max(err_x):.2e} kg m^2/s, stride vx {v_mean:.4f} m/s"
    )
    assert max(err_y) < 1e-6 * L_ref  # deadbeat in the sagittal plane, every step from the second
    assert v_mean == pytest.approx(0.6, abs=1e-3)
    # The lateral pair drifts by -k L_z / (m H) on a slope (the notes): bounded, not deadbeat.
    assert max(err_x) < 0.05 * L_ref
    if slope_deg == 0.0:
        assert max(err_x) < 1e-6 * L_ref and max(old_y) < 1e-6 * L_ref
    else:
        assert min(old_y[-4:]) > 1e-2 * L_ref  # the old law's error is large and persists
