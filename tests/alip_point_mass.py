"""A point-mass ALIP walker for the step-timing MPC tests: constant height, exact flow, ideal swing.

The mass moves exactly (``c_xy'' = g/H (c - r)_xy``) over its stance contact; every tick the
planner is updated and the step ends when the time in it reaches the step clock's duration
(the planned one, else the command's ``T``). The foot then lands at the planner's swing
target, clipped to the leg's reach: a box of half sizes ``reach_m`` about the CoM at touchdown
in the next step's heading frame (``None``: anywhere). ``L = (c - r) x m v`` is recomputed
about each contact, so the momentum transfer is exact (``v_z = 0``).
"""

import math

import numpy as np

from amlip_qp.alip.heading import heading_to_world, world_to_heading
from amlip_qp.messages import StateEstimate

M, H, G, T = 32.0, 0.8, 9.81, 0.3
LAM = math.sqrt(G / H)
#: Cassie-like outputs (the references are evaluated but not used by the point mass).
OUTPUTS = (
    "torso_pitch", "torso_roll", "stance_hip_yaw", "swing_hip_yaw", "com_z_over_stance",
    "com_x_over_swing", "com_y_over_swing", "com_z_over_swing", "swing_toe_pitch",
)  # fmt: skip
#: |c - r| beyond this (m) is a fall.
FALL_M = 1.5
#: The leg's reach: half sizes (m) of the box about the CoM at touchdown, along and across the
#: heading (the MPC's default limits, ``MPCSettings.reach_x`` and ``reach_out`` times ``H``).
REACH_M = (0.55 * H, 0.65 * H)


def flow_xy(p, v, tau):
    """CoM offset and velocity after ``tau`` s of the LIP from ``(p, v)`` (arrays, m and m/s)."""
    ch, sh = math.cosh(LAM * tau), math.sinh(LAM * tau)
    return p * ch + v / LAM * sh, p * LAM * sh + v * ch


class Walk:
    """Walk the point mass with ``planner``; ``steps`` lists per step ``(t_start, t_end, foothold_xy,
    clipped_m, com_xy_end, vel_xy_end)``; ``fell`` and ``t_s`` after :meth:`run`."""

    def __init__(self, planner, command, dt_s=2e-3, reach_m=None, hook=None):
        self.planner, self.command, self.dt, self.reach, self.hook = planner, command, dt_s, reach_m, hook
        self.c = np.array([0.0, -0.1, H])
        self.v = np.zeros(3)
        self.r = np.zeros(3)
        self.r_prev = np.array([0.0, 0.25, 0.0])
        self.stance = "left"
        self.t_s = 0.0
        self.t_start = 0.0
        self.steps = []
        self.fell = False
        self.plans = []
        planner.start_step(self.stance, 0.0, self._h0())

    def _h0(self):
        xy = world_to_heading(self.c[:2] - self.r_prev[:2], self.planner.heading_next_rad)
        return np.array([0.0, 0.0, 0.0, 0.0, H, xy[0], xy[1], H, 0.0])

    def L(self):
        return np.cross(self.c - self.r, M * self.v)

    def run(self, t_end_s, push=None):
        """Walk until ``t_end_s``; ``push = (t_s, dv_xy)`` adds ``dv_xy`` (m/s) to the CoM velocity then."""
        while self.t_s < t_end_s - 1e-9:
            est = StateEstimate(
                stance=self.stance, p_st_m=self.c - self.r, L_Nms=self.L(), v_z_mps=0.0,
                t_in_step_s=self.t_s - self.t_start, com_m=self.c.copy(),
            )  # fmt: skip
            out = (
                self.planner.update(est, self.command, None, self.hook)
                if self.hook
                else self.planner.update(est, self.command)
            )
            self.plans.append((self.t_s, out))
            if push is not None and abs(self.t_s - push[0]) < 0.5 * self.dt:
                self.v[:2] += push[1]
            p, v = flow_xy(self.c[:2] - self.r[:2], self.v[:2], self.dt)
            self.c[:2], self.v[:2] = self.r[:2] + p, v
            self.t_s += self.dt
            if self.t_s - self.t_start >= self.planner.clock.step_time_s(self.command.step_time_s) - 1e-9:
                self._touchdown(out)
            if np.linalg.norm(self.c[:2] - self.r[:2]) > FALL_M:
                self.fell = True
                return self

        return self

    def _touchdown(self, out):
        target = out.swing_target_world_m[:2].copy()
        clipped = 0.0
        if self.reach is not None:
            D = self.planner.heading_next_rad
            d = world_to_heading(target - self.c[:2], D)
            dc = np.clip(d, -np.asarray(self.reach), np.asarray(self.reach))
            clipped = float(np.max(np.abs(dc - d)))
            target = self.c[:2] + heading_to_world(dc, D)
        self.steps.append((self.t_start, self.t_s, target.copy(), clipped, self.c[:2].copy(), self.v[:2].copy()))
        self.r_prev = self.r.copy()
        self.r = np.array([target[0], target[1], 0.0])
        self.stance = "right" if self.stance == "left" else "left"
        self.t_start = self.t_s
        self.planner.start_step(self.stance, self.t_s, self._h0())


def reach_clip_hook(walk, reach_m):
    """A foothold hook for the one-step law: its target clipped to the reach box about the CoM
    predicted at the nominal end of the step (the law's own prediction), as a reach-limited
    one-step planner would place it."""

    def hook(x, y, heading_rad, s):
        tau = max(walk.command.step_time_s - (walk.t_s - walk.t_start), 0.0)
        p, _ = flow_xy(walk.c[:2] - walk.r[:2], walk.v[:2], tau)
        c_end = walk.r[:2] + p
        d = np.clip(world_to_heading(np.array([x, y]) - c_end, heading_rad), -np.asarray(reach_m), np.asarray(reach_m))
        return tuple(c_end + heading_to_world(d, heading_rad))

    return hook
