"""The step-timing MPC planner: footholds and step durations, several steps ahead.

:class:`MPCPlanner` is a :class:`~amlip_qp.alip.planner.Planner` whose foot placement
and step duration come from the quadratic program of :mod:`amlip_qp.alip.step_mpc`
(docs/ALIP_MPC.md) instead of the one-step deadbeat law. Every tick it

1. builds the QP (``MPC_QP``: the numpy reference, or the generated C passed as
   ``mpc_fn``) from the estimate, the command and the limits (:class:`MPCSettings`),
   linearised about the last planned durations and steps (those of the tick before; at a
   step's start the previous step's plan, shifted by one step);
2. solves it with ``solve_fn`` (the solver is the caller's: this package is numpy
   only; :mod:`amlip_qp.control.mpc` passes a hot-started DAQP), re-linearising
   ``iterations`` times at most, while a planned duration moves;
3. writes the planned duration ``T_0`` on the step clock
   (:meth:`~amlip_qp.alip.clock.StepClock.plan_step_time`) and runs the one-step
   planner's tick with ``T = T_0`` (phase, prediction, references) and the first
   planned foothold as the swing target.

The time left may not drop below ``min_time_left_s`` by re-planning: once the planned
end is that close, the duration is kept (a step cannot be postponed by shortening it
tick after tick), also after it when the touchdown is late (the phase is then held at 1
and the swing foot may keep descending, as with the one-step law after ``T``). A planned
duration within :data:`NOMINAL_TOL_S` of ``T`` is ``T``. A failed solve
(:class:`~amlip_qp.exceptions.QPError`) falls back to the one-step law for that tick (at
the duration planned so far, else ``T``), counted in :attr:`MPCPlanner.failures`.

With the limits inactive the QP's minimum is the one-step law's footholds at the nominal
``T`` (module doc of :mod:`~amlip_qp.alip.step_mpc`): the MPC then gives the one-step
planner's numbers to the solver's precision.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from amlip_qp.alip import _checks as C
from amlip_qp.alip import step_mpc as S
from amlip_qp.alip.planner import VZ_CLAMP_FRACTION, Planner
from amlip_qp.alip.step_timing import StepTiming
from amlip_qp.exceptions import InputError, QPError
from amlip_qp.messages import Command, PlannerOutput, StateEstimate, TerrainPrediction

#: ``solve_fn(H, g, C, lower, upper) -> x`` (:func:`~amlip_qp.alip.step_mpc.split_qp`'s views;
#: raises QPError when it cannot solve).
SolveFunction = Callable[..., np.ndarray]
#: A foothold region: world box ``(x_lo, x_hi, y_lo, y_hi)`` and the ground height ``z`` in it, m.
Region = tuple[float, float, float, float, float]
_I_TAU_BAR = S.MPC_QP_INPUTS.index("tau_bar")
_I_T_BAR = S.MPC_QP_INPUTS.index("T_bar_1")
_I_D_BAR = S.MPC_QP_INPUTS.index("d_bar_x_1")
_I_REGIONS = S.MPC_QP_INPUTS.index("dz_1")
#: A planned duration this close to the command's ``T`` (s) is ``T`` itself.
NOMINAL_TOL_S = 1e-9
# The durations' entries of the MPC's solution x (the current step's sigma, then the later ones'), and the
# ufuncs the per-tick solve uses: np.clip's, np.max's and np.cumsum's Python layers cost more than the
# arithmetic on these few entries (clip(a, lo, hi) is minimum(maximum(a, lo), hi), cumsum is
# add.accumulate: the same values).
_SIGMA_IDX = np.array([0, *range(S.I_SIGMA_LATER, S.N_VAR)])
# The entries of the MPC's inputs linearised about those durations (tau_bar, then T_bar_1 ..)
_TAU_BAR_IDX = np.array([_I_TAU_BAR, *range(_I_T_BAR, _I_D_BAR)])
_maximum, _minimum, _max_reduce, _accumulate = np.maximum, np.minimum, np.maximum.reduce, np.add.accumulate
#: The region inputs without regions: flat, boxes of +-NO_BOUND.
_NO_REGIONS = np.concatenate([np.zeros(S.MPC_STEPS), np.tile([-S.NO_BOUND, S.NO_BOUND] * 2, S.MPC_STEPS)])


@dataclass(frozen=True, kw_only=True)
class MPCSettings:
    """Limits and weights of the step-timing MPC (docs/ALIP_MPC.md). Lengths in units of ``H``.

    Attributes:
        step_time_min: shortest step (the current one and every later one), in units of the
            command's ``T`` (> 0).
        step_time_max: longest step, in units of ``T`` (>= step_time_min).
        step_time_min_s: shortest step in seconds, whatever ``T`` (>= 0; 0: none): the shortest
            step the tracker's swing leg follows (``Tracker.shortest_step_s``; the walking loop
            sets it). The bound on every step is ``max(step_time_min T, min(step_time_min_s, T))``:
            it keeps the MPC from shortening a step below it, never lengthens the nominal ``T``.
        min_time_left_s: the least time left a re-plan may give the current step, s (>= 0).
        reach_x: ``|p_sw|`` along the heading at touchdown, at most this times ``H`` (> 0).
        reach_out: the landing foot's lateral distance outward from the CoM, at most this times ``H``.
        reach_in: its distance inward (under and past the CoM), at most this times ``H`` (>= 0).
        step_x: the step along the heading, at most this times ``H`` (> 0).
        width_min: the landing foot at least this times ``H`` to its side of the stance foot
            (>= 0: the feet do not cross; negative: a crossover step, the landing foot at most
            ``-width_min H`` past the stance foot; finite).
        step_out: the step's lateral component at most this times ``H`` (> width_min).
        weight_time: the cost of ``(T_0 - T)^2`` against ``(L error / (m H))^2``, 1/s^2 (> 0).
        weight_time_later: the cost of each later step's ``(T_j - T)^2``, 1/s^2 (> 0).
        weight_terminal: the last step's weight against 1 for the others (> 0).
        iterations: linearisations per tick (>= 1).
    """

    step_time_min: float = 0.6
    step_time_max: float = 1.4
    step_time_min_s: float = 0.0
    min_time_left_s: float = 0.05
    reach_x: float = 0.55
    reach_out: float = 0.65
    reach_in: float = 0.2
    step_x: float = 1.0
    width_min: float = -0.2
    step_out: float = 1.25
    weight_time: float = 4.0
    weight_terminal: float = 1.0
    weight_time_later: float = 400.0
    iterations: int = 2

    def __post_init__(self):
        for name in (
            "step_time_min",
            "reach_x",
            "reach_out",
            "step_x",
            "step_out",
            "weight_time",
            "weight_terminal",
            "weight_time_later",
        ):
            C.positive(f"MPCSettings.{name}", getattr(self, name), "")
        for name in ("step_time_min_s", "min_time_left_s", "reach_in"):
            C.non_negative(f"MPCSettings.{name}", getattr(self, name), "")
        C.finite("MPCSettings.width_min", self.width_min)
        if not self.step_time_max >= self.step_time_min:
            raise InputError(
                f"MPCSettings.step_time_max ({self.step_time_max!r}) must be >= step_time_min ({self.step_time_min!r})"
            )
        if not self.step_out > self.width_min:
            raise InputError(f"MPCSettings.step_out ({self.step_out!r}) must be > width_min ({self.width_min!r})")
        if isinstance(self.iterations, bool) or not isinstance(self.iterations, int) or self.iterations < 1:
            raise InputError(f"MPCSettings.iterations must be an integer >= 1, got {self.iterations!r}")


@dataclass(frozen=True)
class MPCPlan:
    """The last tick's MPC solution (world axes, SI).

    Attributes:
        step_time_s: the current step's planned duration ``T_0``, s.
        footholds_m: ``(MPC_STEPS, 2)`` planned contact points ``r_1 .. r_N`` (x, y), world, m.
        later_step_times_s: ``(MPC_STEPS,)`` planned durations ``T_1 .. T_N`` of the steps after
            each of those touchdowns, s.
        iterations: linearisations used.
        solved: False when the solve failed and the one-step law planned this tick.
    """

    step_time_s: float
    footholds_m: np.ndarray
    later_step_times_s: np.ndarray
    iterations: int
    solved: bool


class MPCPlanner(Planner):
    """The one-step :class:`~amlip_qp.alip.planner.Planner` with the step-timing MPC's
    footholds and step duration (module doc).

    Args:
        outputs, mass_kg, g, plan_fn, reference_fn: as :class:`~amlip_qp.alip.planner.Planner`.
        solve_fn: ``(H, g, C, lower, upper) -> x`` for ``min 1/2 x'Hx + g'x``,
            ``l <= Cx <= u``, ``lb <= x <= ub`` with ``lower = (lb, l)``, ``upper = (ub, u)``
            stacked (:func:`~amlip_qp.alip.step_mpc.split_qp`); raises QPError on failure. When it
            has a ``solve_stacked(y)`` method (:class:`~amlip_qp.qp.small_qp.SmallQPSolver`), that
            is called with ``MPC_QP``'s output ``y`` whole (the same QP, in DAQP's order) instead;
            when it has a ``producer`` (not ``None``) and a ``solve_inputs(u)`` method, that is called
            with ``MPC_QP``'s inputs and makes the QP itself (with ``mpc_fn``'s function:
            :func:`amlip_qp.control.mpc.make_mpc_planner`).
        mpc_fn: ``MPC_QP`` implementation (default the numpy reference :func:`step_mpc.mpc_qp`).
        settings: :class:`MPCSettings`.
        **planner_kwargs: the :class:`Planner`'s keyword arguments.
    """

    def __init__(
        self,
        outputs,
        mass_kg: float,
        solve_fn: SolveFunction,
        g: float | None = None,
        plan_fn: Callable[[np.ndarray], np.ndarray] | None = None,
        reference_fn: Callable[[np.ndarray], np.ndarray] | None = None,
        mpc_fn: Callable[[np.ndarray], np.ndarray] | None = None,
        *,
        settings: MPCSettings | None = None,
        **planner_kwargs,
    ):
        if not callable(solve_fn):
            raise InputError(f"solve_fn must be callable (H, g, C, lower, upper) -> x, got {solve_fn!r}")
        if mpc_fn is not None and not callable(mpc_fn):
            raise InputError(f"mpc_fn must be callable ({len(S.MPC_QP_INPUTS)} floats -> QP data), got {mpc_fn!r}")
        if settings is not None and not isinstance(settings, MPCSettings):
            raise InputError(f"settings must be MPCSettings, got {type(settings).__name__}")
        self.solve_fn = solve_fn
        self._solve_stacked: Callable[[np.ndarray], np.ndarray] | None = getattr(solve_fn, "solve_stacked", None)
        self._solve_inputs: Callable[[np.ndarray], np.ndarray] | None = (
            getattr(solve_fn, "solve_inputs", None) if getattr(solve_fn, "producer", None) is not None else None
        )
        self.mpc_fn = mpc_fn or S.mpc_qp
        self.settings = settings or MPCSettings()
        self._u_mpc = np.zeros(len(S.MPC_QP_INPUTS))
        #: Ticks whose QP failed (the one-step law planned them).
        self.failures = 0
        #: The last tick's QP time (its matrices and solves, every linearisation), µs.
        self.last_solve_us = 0.0
        #: The last tick's solution (``None`` before the first update of a step).
        self.last_plan: MPCPlan | None = None
        self._T_plan: float | None = None
        # the last plan's later durations T_j (s; NaN: the nominal T) and steps d_j (m, world)
        self._T_later: np.ndarray | None = None
        self._d_later: np.ndarray | None = None
        kwargs = dict(planner_kwargs)
        if g is not None:
            kwargs["g"] = g
        super().__init__(outputs, mass_kg, plan_fn=plan_fn, reference_fn=reference_fn, **kwargs)

    def reset(self, heading_rad: float = 0.0) -> None:
        """As :meth:`Planner.reset`; also forgets the planned duration and the failure count."""
        super().reset(heading_rad)
        self._T_plan = None
        self._T_later = self._d_later = None
        self.last_plan = None
        self.failures = 0

    def start_step(self, stance: str, t_start_s: float, h0_start, heading_rad: float | None = None) -> None:
        """As :meth:`Planner.start_step`; the new step's duration is planned afresh, the later
        ones are linearised about the last plan's, shifted by one step."""
        super().start_step(stance, t_start_s, h0_start, heading_rad)
        self._T_plan = None
        if self._T_later is not None and self._d_later is not None:
            self._T_later = np.append(self._T_later[1:], math.nan)
            self._d_later = np.concatenate([self._d_later[1:], self._d_later[-1:]])
        self.last_plan = None

    def update(
        self,
        estimate: StateEstimate,
        command: Command,
        terrain: TerrainPrediction | None = None,
        foothold: Callable[[float, float, float, float], tuple[float, float]] | None = None,
        regions: Sequence[Region] | None = None,
        *,
        timing: StepTiming | None = None,
    ) -> PlannerOutput:
        """Plan with the MPC, then as :meth:`Planner.update` with the planned ``T`` and foothold.

        Args:
            estimate, command, terrain: as :meth:`Planner.update`.
            foothold: applied to the MPC's first foothold (as to the law's target in :meth:`Planner.update`).
            regions: ``MPC_STEPS`` foothold regions, one per touchdown ahead (:data:`Region`, world, m),
                or ``None`` (anywhere, flat).
            timing: refused (not ``None``): the MPC plans the step's duration itself.
        """
        if timing is not None:
            raise InputError("the MPC plans the step's duration itself: pass no timing to MPCPlanner.update")
        if self.clock.stance is None:
            raise InputError("Planner.update called before start_step(); call start_step at the first touchdown")
        if not isinstance(estimate, StateEstimate) or not isinstance(command, Command):
            raise InputError(
                "update needs a StateEstimate and a Command, "
                f"got {type(estimate).__name__} and {type(command).__name__}"
            )
        r0 = estimate.com_m - estimate.p_st_m
        plan = self._solve(estimate, command, terrain, r0, self._region_inputs(regions, r0))
        self.last_plan = plan
        if not plan.solved:  # the one-step law, at the duration planned so far
            cmd = command if self._T_plan is None else command.with_step_time(self._T_plan)
            return super().update(estimate, cmd, terrain, foothold)
        T0 = plan.step_time_s
        self.clock.plan_step_time(T0)
        fx, fy = plan.footholds_m[0].tolist()
        if foothold is None:
            hook = lambda x, y, heading, s: (fx, fy)  # noqa: E731
        else:
            user = foothold
            hook = lambda x, y, heading, s: user(fx, fy, heading, s)  # noqa: E731
        cmd = command if T0 == command.step_time_s else command.with_step_time(T0)
        return super().update(estimate, cmd, terrain, hook)

    # --- the QP ---------------------------------------------------------------

    def _region_inputs(self, regions, r0: np.ndarray) -> np.ndarray:
        """``(dz_2.., boxes)``: heights between regions and boxes relative to ``r0`` (``NO_BOUND`` without)."""
        n = S.MPC_STEPS
        out = _NO_REGIONS.copy()
        if regions is None:
            return out
        if len(regions) != n:
            raise InputError(f"regions must hold {n} boxes (x_lo, x_hi, y_lo, y_hi, z), one per step, got {regions!r}")
        z_prev = float(r0[2])
        for j, reg in enumerate(regions):
            box = C.vector(f"regions[{j}]", reg, 5)
            if not (box[0] <= box[1] and box[2] <= box[3]):
                raise InputError(f"regions[{j}] = {tuple(box)} must have x_lo <= x_hi and y_lo <= y_hi (m)")
            out[j] = box[4] - z_prev
            z_prev = float(box[4])
            out[n + 4 * j : n + 4 * j + 4] = box[:4] - np.repeat(r0[:2], 2)
        return out

    def _solve(self, estimate, command, terrain, r0, region_inputs) -> MPCPlan:
        st = self.settings
        T, H, m, g = command.step_time_s, command.com_height_m, self.mass_kg, self.g
        l = math.sqrt(g / H)
        t_in = estimate.t_in_step_s
        half = 0.5 * l * T
        factor = half / math.tanh(half) if self.speed_reference == "mean" else 1.0
        v_z = estimate.v_z_mps if self.vz_correction else 0.0
        vz_max = VZ_CLAMP_FRACTION * H * l * math.tanh(l * T)
        v_z = min(max(v_z, -vz_max), vz_max)
        tau_nom = max(T - t_in, 0.0)
        # the shortest step: a fraction of T, and the tracker's own bound (never above T)
        T_lo = max(st.step_time_min * T, min(st.step_time_min_s, T))
        T_hi = max(st.step_time_max * T, T_lo)
        committed = self._T_plan is not None and self._T_plan - t_in <= st.min_time_left_s
        if committed:
            tau_lo = tau_hi = max(self._T_plan - t_in, 0.0)  # the end is near (or late): keep it
        else:
            tau_hi = max(T_hi - t_in, 0.0)
            tau_lo = min(max(T_lo - t_in, st.min_time_left_s), tau_hi)
        tau_bar = tau_nom if self._T_plan is None else self._T_plan - t_in
        tau_bar = min(max(tau_bar, tau_lo), tau_hi)
        planar = self.outputs.planar
        sign = 1.0 if self.clock.stance == "right" else -1.0
        p0, p1, _ = estimate.p_st_m.tolist()
        L0, L1, _ = estimate.L_Nms.tolist()
        big = S.NO_BOUND
        if planar:
            p1 = L0 = vy = W = heading = turn = 0.0
            lateral = (big, big, -big, big)
        else:
            vy, W = command.vy_mps * factor, command.step_width_m
            heading, turn = self.heading_next_rad, command.turn_rate_radps * T
            lateral = (st.reach_out * H, st.reach_in * H, st.width_min * H, st.step_out * H)
        N = S.MPC_STEPS
        u = self._u_mpc
        u[:_I_T_BAR] = (
            p0, p1, L0, L1, v_z, command.vx_mps * factor, vy, heading, turn, sign, m, H, T, W, g,
            tau_nom, tau_lo, tau_hi, tau_bar, st.reach_x * H, lateral[0], lateral[1], st.step_x * H,
            lateral[2], lateral[3], st.weight_time, st.weight_terminal, T_lo, T_hi, st.weight_time_later,
        )  # fmt: skip
        if self._T_later is None or self._d_later is None:
            u[_I_T_BAR:_I_D_BAR] = T
            u[_I_D_BAR:_I_REGIONS] = 0.0
        else:
            u[_I_T_BAR:_I_D_BAR] = _minimum(_maximum(np.where(np.isnan(self._T_later), T, self._T_later), T_lo), T_hi)
            u[_I_D_BAR:_I_REGIONS] = self._d_later.reshape(-1)
        u[_I_REGIONS:] = region_inputs
        if terrain is not None:
            u[_I_REGIONS] = terrain.dz_next_m  # the first transfer's height: the one-step law's
        if planar:
            u[_I_REGIONS + N + 2 :: 4] = -big
            u[_I_REGIONS + N + 3 :: 4] = big
        x = None
        it = 0
        t0 = time.perf_counter_ns()
        try:
            for it in range(1, st.iterations + 1):
                if self._solve_inputs is not None:
                    x = self._solve_inputs(u)
                else:
                    y = np.asarray(self.mpc_fn(u), dtype=float).reshape(-1)
                    if y.size != S.MPC_QP_N_OUT:
                        raise InputError(f"mpc_fn returned {y.size} values; MPC_QP has {S.MPC_QP_N_OUT} outputs")
                    if self._solve_stacked is not None:
                        x = np.asarray(self._solve_stacked(y), dtype=float).reshape(-1)
                    else:
                        x = np.asarray(self.solve_fn(*S.split_qp(y)), dtype=float).reshape(-1)
                taus = np.log(_maximum(x[_SIGMA_IDX], 1e-300)) / l
                moved_by = taus - u[_TAU_BAR_IDX]
                moved = float(_max_reduce(np.abs(moved_by, out=moved_by)))
                if moved < 1e-9 or it == st.iterations:
                    break
                # re-linearise at the new durations and steps
                u[_I_TAU_BAR] = min(max(taus[0], tau_lo), tau_hi)
                u[_I_T_BAR:_I_D_BAR] = _minimum(_maximum(taus[1:], T_lo), T_hi)
                u[_I_D_BAR:_I_REGIONS] = x[1 : S.I_SIGMA_LATER]
        except QPError:
            x = None
        self.last_solve_us = (time.perf_counter_ns() - t0) * 1e-3
        if x is None or not math.isfinite(sum(x.tolist())):
            self.failures += 1
            T_kept = T if self._T_plan is None else self._T_plan
            return MPCPlan(T_kept, np.full((N, 2), np.nan), np.full(N, np.nan), it, False)
        if committed and self._T_plan is not None:
            T_plan = self._T_plan
        else:
            tau = min(max(math.log(max(x[0], 1e-300)) / l, tau_lo), tau_hi)
            # the nominal end to the solver's precision is the nominal end (the one-step law's phase, bit for bit)
            T_plan = T if abs(t_in + tau - T) < NOMINAL_TOL_S else t_in + tau
        self._T_plan = T_plan
        T_later = _minimum(_maximum(np.log(_maximum(x[S.I_SIGMA_LATER :], 1e-300)) / l, T_lo), T_hi)
        T_later[np.abs(T_later - T) < NOMINAL_TOL_S] = T  # the nominal duration, as for the current step
        steps = x[1 : S.I_SIGMA_LATER].reshape(N, 2)
        self._T_later, self._d_later = T_later, steps.copy()
        footholds = r0[:2] + _accumulate(steps, axis=0)
        return MPCPlan(T_plan, footholds, T_later, it, True)
