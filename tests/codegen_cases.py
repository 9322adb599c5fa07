"""Shared helpers of the codegen tests: the compiler requirement and random kernel inputs (not a test module)."""

from __future__ import annotations

import functools
import shutil

import numpy as np
import pytest

from amlip_qp.alip import kernels, step_mpc
from amlip_qp.codegen.kernels import FastFunction


def needs_cc(test):
    """The test compiles generated C. The README requires a C compiler, so
    without one the test fails, naming the fix (it is never skipped)."""

    @functools.wraps(test)
    def run(*args, **kwargs):
        if shutil.which("cc") is None and shutil.which("gcc") is None:
            pytest.fail("no C compiler on the PATH: install one (e.g. apt-get install gcc), as the README requires")
        return test(*args, **kwargs)

    return run


N = 1500  # random samples per robot and kernel

# Physical ranges: (m kg, H m, T s, W m, z_cl m, lateral motion?)
ROBOTS = {
    "cassie": dict(m=(31.0, 35.0), H=(0.6, 1.0), T=(0.25, 0.45), W=(0.0, 0.35), z_cl=(0.05, 0.2), lateral=True),
    "rabbit": dict(m=(32.0, 32.0), H=(0.6, 0.8), T=(0.3, 0.5), W=(0.0, 0.0), z_cl=(0.05, 0.2), lateral=False),
}


def sample_alip_plan(rng, robot, n):
    r = ROBOTS[robot]
    lat = 1.0 if r["lateral"] else 0.0
    m, H, T = rng.uniform(*r["m"], n), rng.uniform(*r["H"], n), rng.uniform(*r["T"], n)
    vx, vy = rng.uniform(-1, 3, n), lat * rng.uniform(-1, 1, n)
    t_rem = rng.uniform(0, 1, n) * T
    t_rem[:20], t_rem[20:40] = 0.0, T[20:40]  # both ends of the step
    u = np.column_stack([
        rng.uniform(-0.3, 0.3, n), lat * rng.uniform(-0.2, 0.2, n),  # p_st
        -m * H * lat * rng.uniform(-1, 1, n), m * H * rng.uniform(-1, 3, n),  # L_x, L_y
        t_rem, rng.uniform(-0.3, 0.3, n), vx, vy,
        rng.uniform(-np.pi, np.pi, n), rng.choice([-1.0, 1.0], n),
        m, H, T, rng.uniform(*r["W"], n), np.full(n, 9.81),
        rng.uniform(-0.2, 0.2, n),  # dz_next
    ])  # fmt: skip
    u[:100, -1] = 0.0  # flat ground too
    return u


def sample_swing_reference(rng, robot, n):
    r = ROBOTS[robot]
    lat = 1.0 if r["lateral"] else 0.0
    s = rng.uniform(0, 1, n)
    s[:20], s[20:40] = 0.0, 1.0
    u = np.column_stack([
        s, rng.uniform(*r["T"], n), rng.uniform(*r["H"], n), rng.uniform(*r["z_cl"], n),
        lat * rng.uniform(-0.5, 0.5, n), lat * rng.uniform(-0.5, 0.5, n),
        rng.uniform(-0.4, 0.4, n), lat * rng.uniform(-0.3, 0.3, n),
        rng.uniform(-0.4, 0.4, n), lat * rng.uniform(-0.3, 0.3, n), lat * rng.uniform(-0.6, 0.6, n),
        rng.uniform(-0.15, 0.15, n), rng.uniform(-0.15, 0.15, n),  # dz_sw0, dz_sw
        lat * rng.uniform(-0.5, 0.5, n), lat * rng.uniform(-0.5, 0.5, n),  # slope_pitch0, slope_pitch
    ])  # fmt: skip
    u[:100, -4:] = 0.0  # flat ground too
    return u


def sample_mpc_qp(rng, robot, n):
    """Inputs of the step-timing MPC's QP (layout ``step_mpc.MPC_QP_INPUTS``)."""
    r = ROBOTS[robot]
    lat = 1.0 if r["lateral"] else 0.0
    m, H, T = rng.uniform(*r["m"], n), rng.uniform(*r["H"], n), rng.uniform(*r["T"], n)
    t_in = rng.uniform(0, 1.2, n) * T
    tau_nom = np.maximum(T - t_in, 0.0)
    tau_lo = np.minimum(np.maximum(0.6 * T - t_in, 0.05), np.maximum(1.4 * T - t_in, 0.0))
    tau_hi = np.maximum(1.4 * T - t_in, 0.0)
    tau_bar = tau_lo + rng.uniform(0, 1, n) * (tau_hi - tau_lo)
    big = np.full(n, step_mpc.NO_BOUND)
    cols = [
        rng.uniform(-0.3, 0.3, n), lat * rng.uniform(-0.2, 0.2, n),  # p_st
        -m * H * lat * rng.uniform(-1, 1, n), m * H * rng.uniform(-1, 3, n),  # L_x, L_y
        rng.uniform(-0.3, 0.3, n), rng.uniform(-1, 3, n), lat * rng.uniform(-1, 1, n),  # v_z, vx, vy
        lat * rng.uniform(-np.pi, np.pi, n), lat * rng.uniform(-0.3, 0.3, n), rng.choice([-1.0, 1.0], n),
        m, H, T, rng.uniform(*r["W"], n), np.full(n, 9.81), tau_nom, tau_lo, tau_hi, tau_bar,
        0.55 * H, 0.5 * H if lat else big, 0.1 * H if lat else big, H, 0.05 * H if lat else -big,
        0.75 * H if lat else big, rng.uniform(0.5, 10, n), rng.uniform(0.5, 3, n), 0.6 * T, 1.4 * T,
        rng.uniform(0.5, 100, n),
    ]  # fmt: skip
    cols += [rng.uniform(0.6, 1.4, n) * T for _ in range(step_mpc.MPC_STEPS)]  # T_bar_j
    for _ in range(step_mpc.MPC_STEPS):  # d_bar_j
        cols += [rng.uniform(-0.2, 0.6, n), lat * rng.uniform(-0.4, 0.4, n)]
    cols += [rng.uniform(-0.15, 0.15, n) for _ in range(step_mpc.MPC_STEPS)]  # dz_j
    for j in range(step_mpc.MPC_STEPS):
        x0, y0 = rng.uniform(-0.5, 1.5, n) * (j + 1), rng.uniform(-0.5, 0.5, n)
        cols += [x0, x0 + rng.uniform(0.1, 0.4, n), y0, y0 + rng.uniform(0.1, 0.4, n)]
    u = np.column_stack(cols)
    k = min(n, 100)
    u[:k, -5 * step_mpc.MPC_STEPS :] = np.tile([0.0] * step_mpc.MPC_STEPS + [-1e9, 1e9, -1e9, 1e9] * 4, (k, 1))
    return u


#: Largest error relative to max(1, |reference|) per kernel (default 1e-12). The MPC's Hessian sums
#: products of up to about 1e6 that cancel to order 1 (the later steps' time weights reach 100 here): the
#: C's and numpy's orders of operations differ there by up to 2.3e-12 on Cassie's samples.
TOLERANCE = {"alip_mpc_qp": 1e-11}
#: Numpy references are slow for the MPC's QP (about 1.5 ms a call): fewer samples of it.
N_SAMPLES = {"alip_mpc_qp": 300}
SAMPLERS = {
    "alip_plan": (sample_alip_plan, kernels.alip_plan),
    "swing_reference": (sample_swing_reference, kernels.swing_reference),
    "alip_mpc_qp": (sample_mpc_qp, step_mpc.mpc_qp),
}
SEEDS = {("cassie", "alip_plan"): 11, ("cassie", "swing_reference"): 12, ("cassie", "alip_mpc_qp"): 13,
         ("rabbit", "alip_plan"): 21, ("rabbit", "swing_reference"): 22, ("rabbit", "alip_mpc_qp"): 23}  # fmt: skip


def assert_matches_reference(fn: FastFunction, robot: str, seed: int):
    sample, reference = SAMPLERS[fn.name]
    rng = np.random.default_rng(seed)
    for u in sample(rng, robot, N_SAMPLES.get(fn.name, N)):
        y = fn(u).copy()
        ref = reference(u)
        err = np.abs(y - ref) / np.maximum(1.0, np.abs(ref))
        assert err.max() <= TOLERANCE.get(fn.name, 1e-12), (fn.name, robot, u, y, ref)
