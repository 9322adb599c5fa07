"""The ALIP planner: one object a walking controller calls every control tick.

Per step ``k`` (stance leg ``st``, heading ``D_k``) the planner

1. predicts ``L(T-)`` and ``p_st(T-)`` of the current step from the estimated
   ``p_st`` and ``L`` about the stance contact (paper eq. LIP_AM_Preiction);
2. decides ``L^des`` at the end of the *next* step in the heading frame
   ``D_{k+1}`` (forward speed, lateral speed, step width) and rotates it to
   world axes. ``D_{k+1} = psi(t) + turn_rate * t_remaining`` with ``psi`` the
   time integral of the commanded turn rate: the commanded heading at the end
   of the current step. For steps of exactly ``T`` at a constant rate that is
   the paper's ``D_{k+1} = D_k + turn_rate * T``; when steps end early or late
   the headings stay on the commanded integral instead of advancing by a
   fixed amount per step (a 90 degree turn command turns 90 degrees);
3. places the swing foot, deadbeat in ``L`` at the end of the next step, with the
   momentum transfer at touchdown to the next contact: its ``v_z`` correction
   and, off flat ground, the height difference ``dz_next`` (docs/ALIP_SLOPES.md);
4. evaluates the reference outputs ``h_d(s)``, ``dh_d/dt``, ``d^2h_d/dt^2``
   (off flat ground with the swing foot's start and end heights and the ground
   pitches for the toe).

Steps 1-3 are the dense kernel ``ALIP_PLAN`` and step 4 is ``SWING_REFERENCE``
(:mod:`amlip_qp.alip.kernels`). Both are injectable (``plan_fn``,
``reference_fn``) so the controller can pass the CasADi-generated C functions,
which use identical dense layouts.

Use::

    planner = Planner(robot.output_names, mass_kg=31.0)
    planner.start_step("left", t_s, h0)          # at every touchdown
    out = planner.update(estimate, command)       # every control tick (flat ground)
    out = planner.update(estimate, command, TerrainPrediction(dz_next_m=0.1, dz_sw_m=0.1))

Terrain: :class:`~amlip_qp.messages.TerrainPrediction` (optional third
argument of :meth:`Planner.update`; ``None`` is flat ground and gives today's
numbers bit for bit) carries the ground heights relative to the stance
contact and the ground pitches. ``H`` stays the CoM height over the stance
contact. Where they come from is the controller's choice: the last footholds
(:class:`amlip_qp.alip.footholds.FootholdPlane`, blind) or a height function
(terrain-aware).

Late touchdown: the phase is held at 1 after ``T``. By default every
reference holds its end value; with ``late_descent`` the swing foot keeps
descending (``com_z_over_swing`` grows at a constant rate,
:func:`amlip_qp.alip.outputs.late_descent`) until the controller calls
:meth:`Planner.start_step` at contact.

``h0`` (the measured outputs at the step start) must express
``com_x_over_swing`` / ``com_y_over_swing`` in the new step's heading frame,
which is :attr:`Planner.heading_next_rad` just before ``start_step`` (or the
``heading_rad`` passed to it).

A planar output set (no ``com_y_over_swing``: a robot in the sagittal plane
x-z) has its lateral terms (``vy``, step width, turn rate, ``p_st,y``,
``L_x``) ignored and its heading held at 0.

Velocity command: ``Command.vx_mps`` / ``vy_mps`` are by default the *mean*
CoM velocity over a step (what a user means by "walk at 1 m/s"). The paper's
``L^des = m H v`` fixes the velocity at the *end* of a step, which on the
periodic LIP gait is larger by ``(lT/2)/tanh(lT/2)``; the planner converts
(:func:`amlip_qp.alip.desired.end_of_step_velocity`). Pass
``speed_reference="end_of_step"`` to use the paper's meaning unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from amlip_qp.alip import _checks as C
from amlip_qp.alip import kernels
from amlip_qp.alip import outputs as O
from amlip_qp.alip.clock import StepClock
from amlip_qp.alip.formulas import GRAVITY_MPS2, world_to_heading_xy
from amlip_qp.alip.planner_inputs import check_settings, check_tick, ground_terms
from amlip_qp.alip.planner_output import planner_output
from amlip_qp.alip.step_timing import StepTiming, retime
from amlip_qp.exceptions import InputError
from amlip_qp.messages import Command, PlannerOutput, StateEstimate, TerrainPrediction

__all__ = ["VZ_CLAMP_FRACTION", "Planner"]

_F64 = np.dtype(np.float64)

#: The ``v_z`` fed to the foot-placement law is clamped to ``+-`` this fraction
#: of ``H l tanh(lT)``, where the law's denominator vanishes (see
#: :func:`amlip_qp.alip.lip.vz_limit`); at 0.5 the denominator stays at least
#: half its ``v_z = 0`` value, so a glitch in the ``v_z`` estimate cannot throw
#: the swing foot away. The clamp is symmetric to bound glitches of either sign.
VZ_CLAMP_FRACTION = 0.5


class Planner:
    """ALIP foot-placement planner and reference generator (module doc).

    Args:
        outputs: The robot's output names, in its order (``Robot.output_names``; the names of
            :mod:`amlip_qp.profiles.outputs`), or their :class:`~amlip_qp.alip.outputs.OutputSet`.
            A set without ``com_y_over_swing`` is planar: the planner keeps heading 0 and
            plans the sagittal plane only.
        mass_kg: total robot mass, kg (> 0).
        g: gravity magnitude, m/s^2 (> 0).
        plan_fn: ``ALIP_PLAN`` implementation, 16 floats -> 8 floats (default
            :func:`kernels.alip_plan`).
        reference_fn: ``SWING_REFERENCE`` implementation, 15 floats -> 30 floats
            (default :func:`kernels.swing_reference`).
        heading_rad: heading of the first step, rad.
        speed_reference: ``"mean"`` (default) if ``Command.vx_mps``/``vy_mps`` are
            mean velocities over a step, ``"end_of_step"`` for the paper's meaning.
        vz_correction: use ``StateEstimate.v_z_mps`` in the momentum transfer
            (True, default) or the basic law with ``v_z = 0`` (False).
        clock: the :class:`~amlip_qp.alip.clock.StepClock` of the walk (a
            walking controller passes its own, which reads the phase from it);
            a new one by default. The planner starts its steps
            (:meth:`start_step`) and resets it (:meth:`reset`).
        late_descent: after ``T`` (a late touchdown, phase held at 1):
            ``None`` (default) holds the references at their end values;
            ``"landing"`` keeps the swing foot descending at the reference's
            own vertical velocity at s = 1 (``d com_z_over_swing/dt``, velocity
            continuous); a number > 0 descends at that constant rate, m/s.
    """

    def __init__(
        self,
        outputs: Sequence[str] | O.OutputSet,
        mass_kg: float,
        g: float = GRAVITY_MPS2,
        plan_fn: Callable[[np.ndarray], np.ndarray] | None = None,
        reference_fn: Callable[[np.ndarray], np.ndarray] | None = None,
        *,
        heading_rad: float = 0.0,
        speed_reference: str = "mean",
        vz_correction: bool = True,
        clock: StepClock | None = None,
        late_descent: str | float | None = None,
    ):
        #: The outputs the references are for (:class:`~amlip_qp.alip.outputs.OutputSet`).
        self.outputs = O.output_set(outputs)
        check_settings(mass_kg, g, plan_fn, reference_fn, speed_reference, clock, late_descent)
        #: The late-descent setting (see the class doc).
        self.late_descent = late_descent
        self._descent_landing = late_descent == "landing"
        self._descent_rate_mps = 0.0 if late_descent is None or self._descent_landing else float(late_descent)
        self.mass_kg = float(mass_kg)
        self.g = float(g)
        self.plan_fn = plan_fn or kernels.alip_plan
        self.reference_fn = reference_fn or kernels.swing_reference
        self.speed_reference = speed_reference
        self.vz_correction = bool(vz_correction)
        #: Stance side and start of the current step (the walk's one step clock).
        self.clock = StepClock() if clock is None else clock
        #: Output names in order.
        self.output_names = self.outputs.names
        self._planar = self.outputs.planar
        self._u_plan = np.zeros(len(kernels.ALIP_PLAN_INPUTS))
        self._u_ref = np.zeros(len(kernels.SWING_REFERENCE_INPUTS))
        self._h0 = np.zeros(len(self.output_names))
        self._i_swing_z = self.output_names.index("com_z_over_swing")
        self.reset(heading_rad)

    def reset(self, heading_rad: float = 0.0) -> None:
        """Forget the walk (a new run): no step yet, first heading ``heading_rad``
        (rad; a planar set: 0), the step clock reset and the commanded-heading integral restarted."""
        C.finite("heading_rad", heading_rad)
        self._heading = 0.0 if self._planar else float(heading_rad)
        self._heading_next = self._heading
        # The commanded heading psi (the turn-rate integral, rad) and the time
        # (s) up to which it is integrated (None: before the first step).
        self._heading_cmd = self._heading
        self._t_heading_cmd: float | None = None
        self._rate_cmd: float | None = None  # the turn rate of the last update, rad/s
        self.clock.reset()
        self._h0[:] = 0.0
        self._steps = 0

    # --- read-only state -----------------------------------------------------

    @property
    def n_outputs(self) -> int:
        """Number of reference outputs."""
        return len(self.output_names)

    @property
    def stance(self) -> str | None:
        """Stance side of the current step (``None`` before the first :meth:`start_step`)."""
        return self.clock.stance

    @property
    def heading_rad(self) -> float:
        """Heading ``D_k`` of the current step, rad."""
        return self._heading

    @property
    def heading_next_rad(self) -> float:
        """Heading ``D_{k+1}`` planned by the last :meth:`update` (``D_k`` before any
        update); :meth:`start_step` makes it the new step's heading. Use it to
        express ``h0_start`` in the new step's heading frame."""
        return self._heading_next

    @property
    def step_count(self) -> int:
        """Number of :meth:`start_step` calls so far."""
        return self._steps

    @property
    def h0_start(self) -> np.ndarray:
        """Copy of the outputs measured at the start of the current step (robot order)."""
        return self._h0.copy()

    # --- per step ------------------------------------------------------------

    def start_step(self, stance: str, t_start_s: float, h0_start, heading_rad: float | None = None) -> None:
        """Begin a step at touchdown (on :attr:`clock`).

        Args:
            stance: the new stance leg, ``"left"`` or ``"right"``.
            t_start_s: touchdown time, s.
            h0_start: the robot's outputs measured at touchdown, in robot order
                (rad / m; ``com_x_over_swing``/``com_y_over_swing`` in the new
                step's heading frame, see :attr:`heading_next_rad`).
            heading_rad: the new step's heading ``D_k`` (rad); by default the
                ``D_{k+1}`` of the step that just ended (a planar set: always 0).
                Given, it also resets the commanded heading (the turn-rate
                integral) to it.
        """
        C.side("stance", stance)
        C.finite("t_start_s", t_start_s)
        h0 = C.vector("h0_start", h0_start, self.n_outputs)
        if heading_rad is not None:
            C.finite("heading_rad", heading_rad)
            if not self._planar:
                self._heading = float(heading_rad)
                self._heading_cmd = self._heading
        else:
            self._heading = self._heading_next
        self._heading_next = self._heading
        clock = self.clock
        clock.start(stance, t_start_s)
        if self._t_heading_cmd is None:
            # The turn-rate integral starts with the first step.
            self._t_heading_cmd = clock.t_start_s
        self._h0[:] = h0
        self._steps += 1

    # --- per tick ------------------------------------------------------------

    def update(
        self,
        estimate: StateEstimate,
        command: Command,
        terrain: TerrainPrediction | None = None,
        foothold: Callable[[float, float, float, float], tuple[float, float]] | None = None,
        *,
        timing: StepTiming | None = None,
    ) -> PlannerOutput:
        """Plan the foot placement and evaluate ``h_d`` for one control tick.

        Args:
            estimate: the current :class:`StateEstimate` (its ``stance`` must match
                the last :meth:`start_step`).
            command: the current :class:`Command`.
            terrain: the ground heights and pitches relative to the stance contact
                (:class:`TerrainPrediction`); ``None`` is flat ground (the same
                numbers as all zeros). The pitches matter only to ``swing_toe_pitch``.
            foothold: ``(x, y, heading_next, s) -> (x, y)``: the law's target (world, m) -> where the foot
                goes instead (a terrain-aware controller moves targets off stair edges; the next step's
                placement corrects for it). ``None``: the law's target.
            timing: with ``foothold``: when it moves the target, the current step ends when the law's
                target is the moved foothold, within these bounds (:mod:`amlip_qp.alip.step_timing`; the
                duration is planned on the step clock). ``None``: the step time stays the command's.

        Returns:
            A :class:`PlannerOutput`.
        """
        clock = self.clock
        stance = clock.stance
        check_tick(stance, estimate, command)
        T = command.step_time_s
        H = command.com_height_m
        dz_next, dz_sw, ground = ground_terms(terrain, H, command.clearance_m)
        m = self.mass_kg
        g = self.g
        # Inlined hot-path versions of phase.step_phase_clipped / phase.time_remaining,
        # desired.mean_to_end_factor (inputs already validated).
        t_in = estimate.t_in_step_s
        s = t_in / T
        if s > 1.0:
            s = 1.0
        t_rem = T - t_in
        if t_rem < 0.0:
            t_rem = 0.0

        l = math.sqrt(g / H)
        if self.speed_reference == "mean":
            half = 0.5 * l * T
            factor = half / math.tanh(half)
        else:
            factor = 1.0
        v_z = estimate.v_z_mps if self.vz_correction else 0.0
        vz_max = VZ_CLAMP_FRACTION * H * l * math.tanh(l * T)
        if v_z > vz_max:
            v_z = vz_max
        elif v_z < -vz_max:
            v_z = -vz_max

        p0, p1, p2 = estimate.p_st_m.tolist()
        L0, L1, _ = estimate.L_Nms.tolist()
        if self._planar:
            heading_next = 0.0
            u_p1 = u_L0 = vy = width = 0.0
        else:
            # Integrate the commanded turn rate up to now, then look ahead to
            # the end of the step (module doc, step 2). The rate held since the
            # last update applies to the time since (the first update of a run:
            # its own rate, since the step start).
            rate = command.turn_rate_radps
            t_abs = clock.t_start_s + t_in
            if self._t_heading_cmd is not None and t_abs > self._t_heading_cmd:
                held = rate if self._rate_cmd is None else self._rate_cmd
                self._heading_cmd += held * (t_abs - self._t_heading_cmd)
            self._t_heading_cmd = t_abs
            self._rate_cmd = rate
            heading_next = self._heading_cmd + rate * t_rem
            u_p1, u_L0, vy, width = p1, L0, command.vy_mps * factor, command.step_width_m
        self._heading_next = heading_next
        # The dense ALIP_PLAN layout (kernels module doc); the next stance leg is the other one.
        sign = 1.0 if stance == "right" else -1.0
        u = self._u_plan
        u[:] = (
            p0, u_p1, u_L0, L1, t_rem, v_z, command.vx_mps * factor, vy, heading_next, sign, m, H, T, width, g, dz_next,
        )  # fmt: skip
        # The kernels may return a shared buffer: copy once, hand out views.
        y = self.plan_fn(u)
        if type(y) is np.ndarray and y.dtype is _F64 and y.ndim == 1:
            y = y.copy()  # the generated kernels' output: np.array(y, dtype=float)'s bits, cheaper
        else:
            y = np.array(y, dtype=float).reshape(-1)
        if y.size != len(kernels.ALIP_PLAN_OUTPUTS):
            raise InputError(
                f"plan_fn returned {y.size} values; ALIP_PLAN has {len(kernels.ALIP_PLAN_OUTPUTS)} outputs"
            )
        yl = y.tolist()
        y2, y3, px_w, py_w = yl[2], yl[3], yl[6], yl[7]
        c0, c1, c2 = estimate.com_m.tolist()
        if foothold is not None:
            # The target is CoM - p_st + p_hat - p_sw (world); a moved target moves p_sw the other way.
            tx, ty = c0 - p0 + y2 - px_w, c1 - p1 + y3 - py_w
            s_hook = s if timing is None else min(t_in / clock.step_time_s(T), 1.0)
            fx, fy = C.placed_foothold(foothold, tx, ty, heading_next, s_hook)
            if timing is not None and (fx != tx or fy != ty or clock.planned_step_time_s is not None):
                T_cur = retime(timing, clock, self.plan_fn, u, y, fx - (c0 - p0), fy - (c1 - p1), T, t_in)
                s, t_rem = min(t_in / T_cur, 1.0), max(T_cur - t_in, 0.0)
                yl = y.tolist()
                y2, y3 = yl[2], yl[3]
                tx, ty = c0 - p0 + y2 - yl[6], c1 - p1 + y3 - yl[7]
                c, sn = math.cos(heading_next), math.sin(heading_next)
                along = c * (fx - tx) + sn * (fy - ty)  # the foothold's place along the heading, the law's across
                fx, fy = tx + along * c, ty + along * sn
                T = T_cur
            px_w, py_w = yl[6], yl[7]
            if fx != tx or fy != ty:
                px_w, py_w = px_w - (fx - tx), py_w - (fy - ty)
                y[6], y[7] = px_w, py_w

        # p_sw_des into the current heading frame D_k for the swing-x/y references.
        p_sw_h = np.array(world_to_heading_xy(px_w, py_w, math.cos(self._heading), math.sin(self._heading)))
        turn = heading_next - self._heading
        ur = self.outputs.pack_swing_reference_input(
            s, T, H, command.clearance_m, self._h0, p_sw_h, turn, out=self._u_ref, ground=ground
        )
        yr = self.reference_fn(ur)
        if not (type(yr) is np.ndarray and yr.dtype is _F64 and yr.ndim == 1):  # the generated kernels' is
            yr = np.asarray(yr, dtype=float).reshape(-1)
        if yr.size != kernels.SWING_REFERENCE_N_OUT:
            raise InputError(
                f"reference_fn returned {yr.size} values; SWING_REFERENCE has {kernels.SWING_REFERENCE_N_OUT}"
            )
        h_d, dh_d, ddh_d = self.outputs.split_reference(yr)
        if self.late_descent is not None and t_in > T:
            i = self._i_swing_z
            rate = float(dh_d[i]) if self._descent_landing else self._descent_rate_mps
            h_d[i], dh_d[i], ddh_d[i] = O.late_descent(h_d[i], rate, t_in - T)

        target = np.array([c0 - p0 + y2 - px_w, c1 - p1 + y3 - py_w, c2 - p2 + dz_sw])
        return planner_output(
            s, t_rem, y[0:2], y[2:4], y[4:6], y[6:8], p_sw_h, target, h_d, dh_d, ddh_d,
            self._heading, heading_next, turn, v_z,
        )  # fmt: skip
