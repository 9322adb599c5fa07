"""The step-timing MPC's quadratic program, written once for numpy and CasADi (docs/ALIP_MPC.md).

Over a horizon of :data:`MPC_STEPS` touchdowns the ALIP (the pairs ``(p_x, L_y)`` and
``(p_y, Lt = -L_x)`` of docs/ALIP_NOTES.md, world axes) is stepped from the current estimate:
the current step ends after the time left ``tau_0`` (a variable) and the step after touchdown
``j`` lasts ``T_j`` (a variable, about the nominal ``T``). At touchdown ``j`` the contact moves
by the step ``d_j = r_j - r_{j-1}``
(two variables, world) and the momentum is transferred as in the one-step law::

    p(T_j+) = p(T_j-) - d_j
    L(T_j+) = L(T_j-) (1 - dz_j / H) + m v_z d_j      (v_z: the estimate at j = 1, 0 later)

The variables are ``x = (sigma, d_1x, d_1y, ..., d_Nx, d_Ny, sigma_1, ..., sigma_N)`` with
``sigma = exp(l tau_0)`` and ``sigma_j = exp(l T_j)``. In the divergent and convergent parts
``xi = p + L / (m H l)`` and ``eta = p - L / (m H l)`` the current step is
``xi(tau_0) = sigma xi`` (exact, linear) and ``eta(tau_0) = eta / sigma``, linearised about
``sigma_bar = exp(l tau_bar)`` (``1/sigma ~ 2/sigma_bar - sigma/sigma_bar^2``, exact at
``sigma = sigma_bar``). A later step multiplies an affine ``xi`` by ``sigma_j`` (and divides
``eta`` by it): both are linearised about ``sigma_bar_j = exp(l T_bar_j)`` and the last plan
``x_bar`` (the steps ``d_bar``), ``xi sigma_j ~ xi sigma_bar_j + xi(x_bar) (sigma_j - sigma_bar_j)``
and ``eta / sigma_j ~ eta / sigma_bar_j - eta(x_bar) (sigma_j - sigma_bar_j) / sigma_bar_j^2``:
exact wherever ``sigma_j = sigma_bar_j`` (whatever ``x_bar``), and at ``x = x_bar`` in error by
second order in ``sigma_j - sigma_bar_j``.

Cost: ``sum_j w_j |(L(T_{j+1}-) - L_des_j) / (m H)|^2`` (``w_j = 1``, ``w_N = w_terminal``;
``L_des_j`` the one-step law's desired momentum at the end of step ``j``, with the stance
side alternating and the heading advancing by ``turn_per_step``) plus
``w_time ((sigma - sigma_nom) / (l sigma_nom))^2``, about ``w_time (tau_0 - tau_nom)^2``, and the
same term for every ``sigma_j`` about ``exp(l T)`` with the weight ``w_time_later``. Its minimum
is 0 exactly at the one-step deadbeat steps and the nominal times whenever those satisfy the
constraints, so the MPC then reproduces the one-step law (with ``T_bar_j = T``: the
linearisation is exact there).

Constraints, for each touchdown ``j`` in its heading frame ``D_j`` (``s_j = +1`` when
the landing foot is the left one): leg reach ``|p_sw,x| <= reach_x`` and
``-reach_in <= -s_j p_sw,y <= reach_out`` with ``p_sw = p(T_j-) - d_j`` the CoM over the
landing foot; step ``|d_x| <= step_x``, ``width_min <= s_j d_y <= step_out`` (the feet do
not cross when ``width_min >= 0``; a negative one allows a crossover step); the foothold
``r_j - r_0 = d_1 + ... + d_j`` in a world box;
``tau_lo <= tau_0 <= tau_hi`` as ``exp(l tau_lo) <= sigma <= exp(l tau_hi)``; and
``T_lo <= T_j <= T_hi`` likewise.

``MPC_QP`` (inputs ``u``, :data:`MPC_QP_INPUTS`; SI units): the estimate ``p_st_x, p_st_y,
L_x, L_y`` (world, about the stance contact), ``v_z`` (m/s, clamped as the one-step law's),
the command ``vx_des, vy_des`` (end-of-step velocities in the heading frame, m/s),
``heading_next`` (``D_1``, rad), ``turn_per_step`` (rad), ``next_stance_sign``, the model
``m, H, T, W, g``, the times ``tau_nom, tau_lo, tau_hi, tau_bar`` (s), the limits
``reach_x, reach_out, reach_in, step_x, width_min, step_out`` (m), the weights
``w_time`` (1/s^2), ``w_terminal``, the later steps' bounds ``T_lo, T_hi`` (s) and weight
``w_time_later`` (1/s^2), the
linearisation point ``T_bar_1 .. T_bar_N`` (s) and ``d_bar_x_j, d_bar_y_j`` (m, world), the
heights ``dz_1 .. dz_N`` (m, contact ``j`` minus
contact ``j-1``) and the boxes ``x_lo_j, x_hi_j, y_lo_j, y_hi_j`` (m, world, relative to the
stance contact). Outputs (:data:`MPC_QP_N_OUT`): ``H`` (row-major), ``g``, ``C`` (row-major),
``lb``, ``l``, ``ub``, ``u`` of ``min 1/2 x'Hx + g'x s.t. l <= Cx <= u, lb <= x <= ub``
(:func:`split_qp`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from amlip_qp.alip import formulas as F

#: Touchdowns planned ahead (the current step's end and three more).
MPC_STEPS = 4
#: Variables: ``sigma``, the two step components per touchdown, then ``sigma_j`` of the step
#: after each touchdown.
N_VAR = 1 + 3 * MPC_STEPS
#: Index in ``x`` of ``sigma_1`` (the step after the first touchdown); ``x[1:I_SIGMA_LATER]`` are the steps.
I_SIGMA_LATER = 1 + 2 * MPC_STEPS
#: Constraint rows per touchdown: reach (2), step (2), foothold box (2).
ROWS_PER_STEP = 6
N_ROWS = ROWS_PER_STEP * MPC_STEPS
#: The reach rows (the first two of each touchdown): a solver may make them soft, so that a state
#: beyond reach still gets the steps nearest to it (the other rows can always be met together).
SOFT_ROWS = tuple(ROWS_PER_STEP * j + k for j in range(MPC_STEPS) for k in (0, 1))

MPC_QP_INPUTS = (
    ("p_st_x", "p_st_y", "L_x", "L_y", "v_z", "vx_des", "vy_des", "heading_next", "turn_per_step",
     "next_stance_sign", "m", "H", "T", "W", "g", "tau_nom", "tau_lo", "tau_hi", "tau_bar",
     "reach_x", "reach_out", "reach_in", "step_x", "width_min", "step_out", "w_time", "w_terminal",
     "T_lo", "T_hi", "w_time_later")
    + tuple(f"T_bar_{j}" for j in range(1, MPC_STEPS + 1))
    + tuple(f"d_bar_{k}_{j}" for j in range(1, MPC_STEPS + 1) for k in ("x", "y"))
    + tuple(f"dz_{j}" for j in range(1, MPC_STEPS + 1))
    + tuple(f"{k}_{j}" for j in range(1, MPC_STEPS + 1) for k in ("x_lo", "x_hi", "y_lo", "y_hi"))
)  # fmt: skip
#: Inputs before the per-step ones (``T_bar_j``, ``d_bar_j``, ``dz_j``, the boxes).
N_FIXED_INPUTS = len(MPC_QP_INPUTS) - 8 * MPC_STEPS
#: Sizes of the outputs ``H, g, C, lb, l, ub, u``, in order (the lower bounds of ``x`` and of the
#: rows stacked, then the upper ones: DAQP's layout).
MPC_QP_BLOCKS = (N_VAR * N_VAR, N_VAR, N_ROWS * N_VAR, N_VAR, N_ROWS, N_VAR, N_ROWS)
_OFFSETS = tuple(int(sum(MPC_QP_BLOCKS[:i])) for i in range(len(MPC_QP_BLOCKS) + 1))
MPC_QP_N_OUT = sum(MPC_QP_BLOCKS)
#: An absent bound (m or dimensionless), finite so the generated C needs no infinity.
NO_BOUND = 1e9

# --- affine expressions [constant, coefficient of x_0, ..., x_{n-1}] ---------------------


def _const(c) -> list:
    return [c] + [0.0] * N_VAR


def _var(i: int) -> list:
    a = [0.0] * (N_VAR + 1)
    a[1 + i] = 1.0
    return a


def _lin(*terms) -> list:
    """``sum k a`` over ``(k, a)`` pairs of scalars and affine expressions."""
    out = [0.0] * (N_VAR + 1)
    for k, a in terms:
        out = [o + k * e if not (isinstance(e, float) and e == 0.0) else o for o, e in zip(out, a)]
    return out


def _pair_after_touchdown(p, L, d, v_z, m, H, dz):
    """``(p, L)`` after a touchdown moving the contact by ``d`` (all affine)."""
    return _lin((1.0, p), (-1.0, d)), _lin((1.0 - dz / H, L), (m * v_z, d))


def _value(a, x_bar):
    """An affine expression's value at ``x_bar``."""
    out = a[0]
    for e, xb in zip(a[1:], x_bar):
        if not (isinstance(e, float) and e == 0.0):
            out = out + e * xb
    return out


def _flow_timed(p, L, i_sigma, sigma_bar, x_bar, mHl):
    """The pair over a step of duration ``log(x[i_sigma]) / l``, linearised about ``sigma_bar`` and
    ``x_bar`` (module doc): ``xi`` times ``sigma``, ``eta`` over it."""
    xi, eta = _lin((1.0, p), (1.0 / mHl, L)), _lin((1.0, p), (-1.0 / mHl, L))
    dsig = _lin((1.0, _var(i_sigma)), (-sigma_bar, _const(1.0)))
    xi_t = _lin((sigma_bar, xi), (_value(xi, x_bar), dsig))
    eta_t = _lin((1.0 / sigma_bar, eta), (-_value(eta, x_bar) / (sigma_bar * sigma_bar), dsig))
    return _lin((0.5, xi_t), (0.5, eta_t)), _lin((0.5 * mHl, xi_t), (-0.5 * mHl, eta_t))


def mpc_qp_terms(u: Sequence) -> list:
    """The QP's dense entries (layout in the module doc) for numpy floats or CasADi symbols."""
    n, N = N_FIXED_INPUTS, MPC_STEPS
    (p_x, p_y, L_x, L_y, v_z, vx, vy, D1, dD, sign, m, H, T, W, g, tau_nom, tau_lo, tau_hi, tau_bar,
     reach_x, reach_out, reach_in, step_x, width_min, step_out, w_time, w_terminal, T_lo, T_hi,
     w_time_later) = u[:n]  # fmt: skip
    T_bar = list(u[n : n + N])
    d_bar = list(u[n + N : n + 3 * N])
    dz = list(u[n + 3 * N : n + 4 * N])
    box = list(u[n + 4 * N :])
    xp = F.backend(*u)
    l = F.omega(H, g)
    mHl = m * H * l
    sigma_bar = xp.exp(l * tau_bar)
    sigma_bar_later = [xp.exp(l * t) for t in T_bar]
    x_bar = [sigma_bar, *d_bar, *sigma_bar_later]
    a, b = 2.0 / sigma_bar, -1.0 / (sigma_bar * sigma_bar)
    sig = _var(0)
    # The current step, per pair: xi(tau) = sigma xi, eta(tau) = eta (a + b sigma).
    pairs = []
    for p, L in ((p_x, L_y), (p_y, -L_x)):
        xi, eta = p + L / mHl, p - L / mHl
        xi_t = _lin((xi, sig))
        eta_t = _lin((eta * a, _const(1.0)), (eta * b, sig))
        pairs.append((_lin((0.5, xi_t), (0.5, eta_t)), _lin((0.5 * mHl, xi_t), (-0.5 * mHl, eta_t))))
    H_rows: list = [[0.0] * N_VAR for _ in range(N_VAR)]
    g_vec: list = [0.0] * N_VAR
    C_rows, lo, hi = [], [], []

    def add_cost(weight, r):
        for i in range(N_VAR):
            if isinstance(r[1 + i], float) and r[1 + i] == 0.0:
                continue
            g_vec[i] = g_vec[i] + 2.0 * weight * r[0] * r[1 + i]
            for k in range(N_VAR):
                if not (isinstance(r[1 + k], float) and r[1 + k] == 0.0):
                    H_rows[i][k] = H_rows[i][k] + 2.0 * weight * r[1 + i] * r[1 + k]

    def add_row(expr, low, high):
        C_rows.append(expr[1:])
        lo.append(low - expr[0])
        hi.append(high - expr[0])

    total = [_const(0.0), _const(0.0)]
    for j in range(MPC_STEPS):
        s_j = sign if j % 2 == 0 else -sign  # +1: the foot landing at touchdown j+1 is the left one
        D_j = D1 + j * dD
        cD, sD = xp.cos(D_j), xp.sin(D_j)
        d = [_var(1 + 2 * j), _var(2 + 2 * j)]
        vz_j = v_z if j == 0 else 0.0
        # Reach: the CoM over the landing foot just before touchdown, in the heading frame.
        p_sw = [_lin((1.0, pairs[k][0]), (-1.0, d[k])) for k in range(2)]
        add_row(_lin((cD, p_sw[0]), (sD, p_sw[1])), -reach_x, reach_x)
        add_row(_lin((s_j * sD, p_sw[0]), (-s_j * cD, p_sw[1])), -reach_in, reach_out)
        # Step from the stance foot: length, and the landing foot on its own side.
        add_row(_lin((cD, d[0]), (sD, d[1])), -step_x, step_x)
        add_row(_lin((-s_j * sD, d[0]), (s_j * cD, d[1])), width_min, step_out)
        # The foothold r_j - r_0 in its world box.
        total = [_lin((1.0, total[k]), (1.0, d[k])) for k in range(2)]
        add_row(total[0], box[4 * j], box[4 * j + 1])
        add_row(total[1], box[4 * j + 2], box[4 * j + 3])
        # Touchdown, then the next step, of duration T_{j+1} (the variable sigma_{j+1}).
        pairs = [_pair_after_touchdown(pairs[k][0], pairs[k][1], d[k], vz_j, m, H, dz[j]) for k in range(2)]
        i_sig = I_SIGMA_LATER + j
        pairs = [_flow_timed(pairs[k][0], pairs[k][1], i_sig, sigma_bar_later[j], x_bar, mHl) for k in range(2)]
        # L at the end of that step against the one-step law's L_des (world; lateral pair Lt = -L_x).
        L_des_x, L_des_y = F.desired_L_world(vx, vy, W, T, m, H, s_j, D_j, g)
        w = w_terminal if j == MPC_STEPS - 1 else 1.0
        add_cost(w, _lin((1.0 / (m * H), pairs[0][1]), (-L_des_y / (m * H), _const(1.0))))
        add_cost(w, _lin((1.0 / (m * H), pairs[1][1]), (L_des_x / (m * H), _const(1.0))))
    sigma_nom = xp.exp(l * tau_nom)
    k_time = 1.0 / (l * sigma_nom)
    add_cost(w_time, _lin((k_time, sig), (-k_time * sigma_nom, _const(1.0))))
    sigma_T = xp.exp(l * T)
    k_later = 1.0 / (l * sigma_T)
    for j in range(MPC_STEPS):
        add_cost(w_time_later, _lin((k_later, _var(I_SIGMA_LATER + j)), (-k_later * sigma_T, _const(1.0))))
    sig_lo, sig_hi = xp.exp(l * T_lo), xp.exp(l * T_hi)
    lb = [xp.exp(l * tau_lo)] + [-NO_BOUND] * (2 * MPC_STEPS) + [sig_lo] * MPC_STEPS
    ub = [xp.exp(l * tau_hi)] + [NO_BOUND] * (2 * MPC_STEPS) + [sig_hi] * MPC_STEPS
    flat_H = [e for row in H_rows for e in row]
    flat_C = [e for row in C_rows for e in row]
    return flat_H + g_vec + flat_C + lb + lo + ub + hi


def mpc_qp(u: np.ndarray) -> np.ndarray:
    """numpy reference of ``MPC_QP``: :data:`MPC_QP_INPUTS` -> :data:`MPC_QP_N_OUT` values (no validation)."""
    return np.array([float(v) for v in mpc_qp_terms([float(v) for v in u])])


def split_qp(y: np.ndarray) -> tuple[np.ndarray, ...]:
    """Views ``H (n, n), g, C (rows, n), lower, upper`` of ``MPC_QP``'s output ``y`` (a 1-D array):
    ``lower = (lb, l)`` and ``upper = (ub, u)``, the bounds of ``x`` then of the rows."""
    o = _OFFSETS
    return (y[o[0] : o[1]].reshape(N_VAR, N_VAR), y[o[1] : o[2]], y[o[2] : o[3]].reshape(N_ROWS, N_VAR),
            y[o[3] : o[5]], y[o[5] : o[7]])  # fmt: skip
