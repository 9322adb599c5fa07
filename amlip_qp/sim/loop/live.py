"""Driving the closed loop live: the key -> command state machine, the stepping in real time, the overlay line.

``amlip-qp view`` (:mod:`amlip_qp.experiments.view`) shows the robot in MuJoCo's viewer
and hands every key press to a :class:`LiveLoop`; everything else is here, with
no window, so it can be tested and used without one:

- :class:`LiveCommand`: the velocity command the keys change (steps of
  :mod:`~amlip_qp.sim.loop.live_keys`), clipped to the robot's
  :class:`~amlip_qp.profiles.CommandBounds`. The controller shapes it as any
  command (its :class:`~amlip_qp.alip.command_shaping.CommandShaper`: a key
  press is a step, the planner sees a ramp).
- :class:`LiveLoop`: the :class:`~amlip_qp.sim.loop.harness.Simulation`'s own tick
  (:meth:`~amlip_qp.sim.loop.harness.Simulation.ticker`) stepped as far as the
  wall clock allows and no further (:meth:`LiveLoop.frame`), pausing,
  resetting to the stand keyframe, a key script at simulated times, the
  overlay line and a summary.

Speeds are m/s, the turn rate deg/s at the keys (rad/s in the :class:`Command`).
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import replace

import numpy as np

from amlip_qp.exceptions import InputError
from amlip_qp.messages import Command
from amlip_qp.profiles import CommandBounds
from amlip_qp.sim.loop.harness import TICK_OK, Simulation
from amlip_qp.sim.loop.live_keys import ACTION_OF_CODE, TURN_STEP_DEGPS, VX_STEP_MPS, VY_STEP_MPS

#: Digits kept of a command value (m/s, deg/s): sums of key steps are exact to this.
_DIGITS = 9


class LiveCommand:
    """The velocity command set by keys: forward and lateral speed (m/s), turn rate (deg/s), inside the bounds.

    Args:
        base: The command's fixed fields (step time, CoM height, clearance, step width):
            a :class:`~amlip_qp.messages.Command` of the scenario.
        bounds: The robot's bounds; every value is clipped to them (a planar robot's
            lateral speed and turn rate stay 0).
        vx_mps: Starting forward speed, m/s.
        vy_mps: Starting lateral speed, m/s (left positive).
        turn_rate_degps: Starting turn rate, deg/s (left positive).
    """

    def __init__(
        self,
        base: Command,
        bounds: CommandBounds,
        vx_mps: float = 0.0,
        vy_mps: float = 0.0,
        turn_rate_degps: float = 0.0,
    ):
        self.base, self.bounds = base, bounds
        self.turn_max_degps = math.degrees(bounds.turn_rate_max_radps)
        self._start = (self._vx(vx_mps), self._vy(vy_mps), self._turn(turn_rate_degps))
        self.vx_mps, self.vy_mps, self.turn_rate_degps = self._start
        self._command: Command | None = None

    def _vx(self, v: float) -> float:
        lo, hi = self.bounds.vx_mps
        return round(min(max(v, lo), hi), _DIGITS)

    def _vy(self, v: float) -> float:
        m = self.bounds.vy_max_mps
        return round(min(max(v, -m), m), _DIGITS)

    def _turn(self, v: float) -> float:
        m = self.turn_max_degps
        return round(min(max(v, -m), m), _DIGITS)

    @property
    def values(self) -> tuple[float, float, float]:
        """``(vx_mps, vy_mps, turn_rate_degps)``."""
        return (self.vx_mps, self.vy_mps, self.turn_rate_degps)

    def apply(self, action: str) -> bool:
        """Carry out a key's action on the command (:data:`~amlip_qp.sim.loop.live_keys.ACTIONS`); True if it changed.

        ``pause`` and ``reset`` are the loop's (:class:`LiveLoop`), not the command's: they change nothing here.

        Raises:
            InputError: An unknown action.
        """
        before = self.values
        if action == "vx+":
            self.vx_mps = self._vx(self.vx_mps + VX_STEP_MPS)
        elif action == "vx-":
            self.vx_mps = self._vx(self.vx_mps - VX_STEP_MPS)
        elif action == "vy+":
            self.vy_mps = self._vy(self.vy_mps + VY_STEP_MPS)
        elif action == "vy-":
            self.vy_mps = self._vy(self.vy_mps - VY_STEP_MPS)
        elif action == "turn+":
            self.turn_rate_degps = self._turn(self.turn_rate_degps + TURN_STEP_DEGPS)
        elif action == "turn-":
            self.turn_rate_degps = self._turn(self.turn_rate_degps - TURN_STEP_DEGPS)
        elif action == "stop":
            self.vx_mps = self.vy_mps = self.turn_rate_degps = 0.0
        elif action not in ("pause", "reset"):
            raise InputError(f"unknown key action {action!r}")
        changed = self.values != before
        if changed:
            self._command = None
        return changed

    def reset(self) -> None:
        """Back to the starting command."""
        self.vx_mps, self.vy_mps, self.turn_rate_degps = self._start
        self._command = None

    def command(self) -> Command:
        """The :class:`Command` now (the same object while the values hold)."""
        if self._command is None:
            self._command = replace(
                self.base,
                vx_mps=float(self.vx_mps),
                vy_mps=float(self.vy_mps),
                turn_rate_radps=math.radians(self.turn_rate_degps),
            )
        return self._command


class LiveLoop:
    """A :class:`Simulation` driven by keys and stepped no faster than the wall clock.

    Args:
        sim: The closed loop (its ``command_fn`` is replaced by the live command's).
        command: The live command.
        script: ``(t_s, key code)`` key presses at simulated times
            (:func:`~amlip_qp.sim.loop.live_keys.parse_key_script`),
            counted over the whole session (every start's ticks).
        clock: The wall clock, s (for the frame's stepping deadline).
        max_frame_s: Longest wall time one :meth:`frame` steps, s (the viewer then redraws).
        max_lag_s: Most simulated time one frame may catch up, s: after a longer stall
            the loop drops the rest rather than run faster than real time.
        window_s: Simulated time over which the speed is measured, s; the real-time factor
            is measured over the same samples (at most three times as long in wall time).
        duration_s: The session's simulated time, s, over every start (then :attr:`finished`);
            ``None``: no end.
    """

    def __init__(
        self,
        sim: Simulation,
        command: LiveCommand,
        script: Iterable[tuple[float, int]] = (),
        clock: Callable[[], float] = time.perf_counter,
        max_frame_s: float = 1.0 / 30.0,
        max_lag_s: float = 0.1,
        window_s: float = 1.0,
        duration_s: float | None = None,
    ):
        self.sim, self.command = sim, command
        sim.command_fn = self._command_at
        self.script = tuple(script)
        self.clock, self.max_frame_s, self.max_lag_s, self.window_s = clock, max_frame_s, max_lag_s, window_s
        self.dt_s = sim.controller.dt_s
        self.end_ticks = None if duration_s is None else int(round(duration_s / self.dt_s))
        self._keys: deque[int] = deque()  # appended by the viewer's thread, drained by the loop's
        self.paused = False
        self.falls = self.resets = self.keys_handled = self.frames = self.push_frames = 0
        self.max_push_N = 0.0  # the largest push of the mouse seen (notice_plant), N
        self.wall_s = 0.0  # wall time the loop ran (not paused)
        self.ticks = 0  # control ticks over every start
        self._next_event = 0  # the script's next key press
        self._last_frame_s: float | None = None  # the wall clock at the last frame, s
        self._viewer_reset_due = False  # a Backspace carried out, the viewer's sync not yet come
        self._base = sim.plant.base_body_id
        self._start()

    # ------------------------------------------------------------------ keys
    def key(self, code: int) -> None:
        """Take a key press (GLFW key code): the viewer's ``key_callback``; safe from any thread."""
        self._keys.append(int(code))

    def _drain(self) -> None:
        """Carry out the key presses taken since the last time."""
        while self._keys:
            action = ACTION_OF_CODE.get(self._keys.popleft())
            if action is None:
                continue  # a key of the viewer's own
            self.keys_handled += 1
            if action == "pause":
                self.paused = not self.paused
            elif action == "reset":
                self._reset_pending = True
                self._viewer_reset_due = True  # Backspace is the viewer's own reset too: at its next sync
            else:
                self.command.apply(action)
        if self._reset_pending or self._echo_pending:
            self._reset(count=self._reset_pending)

    @property
    def finished(self) -> bool:
        """The session's ``duration_s`` has been simulated."""
        return self.end_ticks is not None and self.ticks >= self.end_ticks

    def _command_at(self, t_s: float) -> Command:
        return self.command.command()

    # ----------------------------------------------------------- start, reset
    def _start(self) -> None:
        """Start a run from the plant's state now."""
        self._tick = self.sim.ticker()
        self.t_s = self.t0_s = float(self.sim.data.time)
        self.fell, self.fall_time_s = False, math.nan
        self._reset_pending = self._echo_pending = False  # a reset to do; the echo of one done
        self._budget_s = 0.0
        self._qpos_seen = self.sim.data.qpos.copy()  # the plant as the loop left it
        x, y = self._base_xy()
        self._start_xy = (x, y)
        self._samples: deque[tuple[float, float, float, float]] = deque()  # (wall s, sim s, x m, y m)
        self._sample(self.clock())

    def reset(self) -> None:
        """Back to the stand keyframe with the starting command; the controller starts over."""
        self._reset(count=True)

    def _reset(self, count: bool) -> None:
        self.sim.reset_to_keyframe()
        self.command.reset()
        self.resets += int(count)
        self._start()

    def notice_plant(self) -> None:
        """After the viewer touched the plant (its ``sync``): its push, and any reset of its own.

        The viewer writes the mouse's push (MuJoCo's perturbation of the selected body) into
        ``xfrc_applied``: its largest force is kept (:attr:`max_push_N`, frames with one in
        :attr:`push_frames`). A reset of its own (its "Reset" button, Backspace, a keyframe)
        changes the plant's state: the loop resets to the stand keyframe (after a fall the plant
        stays as it is until a reset key). The viewer's reset that echoes a Backspace the loop
        has carried out already is undone without counting a second reset.
        """
        data = self.sim.data
        forces = data.xfrc_applied[:, :3]
        push = float(np.sqrt((forces * forces).sum(axis=1).max())) if forces.size else 0.0
        if push > 0.0:
            self.push_frames += 1
            self.max_push_N = max(self.max_push_N, push)
        changed = float(data.time) != self.t_s or not np.array_equal(data.qpos, self._qpos_seen)
        if changed and not self.fell:
            if self._viewer_reset_due:
                self._echo_pending = True
            else:
                self._reset_pending = True
        self._viewer_reset_due = False  # the sync after the key has come

    # --------------------------------------------------------------- stepping
    def step_ticks(self, n: int, deadline_s: float = math.inf) -> int:
        """Step up to ``n`` control ticks, fewer at a fall, a pause or the wall clock's ``deadline_s``; how many ran."""
        self._drain()
        script, clock, dt = self.script, self.clock, self.dt_s
        done = 0
        if self.end_ticks is not None:
            n = min(n, self.end_ticks - self.ticks)
        while done < n and not (self.fell or self.paused):
            while self._next_event < len(script) and script[self._next_event][0] <= self.ticks * dt:
                self.key(script[self._next_event][1])
                self._next_event += 1
                self._drain()
            if self.paused:
                break
            status, t, self.t_s = self._tick()
            done += 1
            self.ticks += 1
            if status != TICK_OK:
                self.fell, self.fall_time_s = True, t
                self.falls += 1
            elif deadline_s != math.inf and clock() >= deadline_s:
                break
        self._qpos_seen[:] = self.sim.data.qpos
        self._sample(clock())
        return done

    def frame(self, now_s: float | None = None) -> int:
        """One frame of the viewer: the keys, then the ticks the wall clock allows since the last frame; how many.

        Never more simulated time than wall time: the frame steps at most the wall time
        since the last one (at most :attr:`max_lag_s`), for at most :attr:`max_frame_s`,
        and drops what it could not step.
        """
        now = self.clock() if now_s is None else now_s
        self.frames += 1
        self._drain()
        elapsed = 0.0 if self._last_frame_s is None else max(0.0, now - self._last_frame_s)
        self._last_frame_s = now
        done = 0
        if self.paused or self.fell:
            self._budget_s = 0.0
        else:
            self.wall_s += elapsed
            self._budget_s = min(self._budget_s + elapsed, self.max_lag_s)
            due = int(self._budget_s / self.dt_s)
            done = self.step_ticks(due, now + self.max_frame_s)
            self._budget_s = 0.0 if done < due else self._budget_s - done * self.dt_s
        return done

    # -------------------------------------------------------------- measures
    def _base_xy(self) -> tuple[float, float]:
        x, y, _ = self.sim.data.xpos[self._base].tolist()
        return x, y

    def _sample(self, wall_s: float) -> None:
        """Keep the base's position now, for the last window's speed and real-time factor."""
        x, y = self._base_xy()
        samples, t_old, wall_old = self._samples, self.t_s - self.window_s, wall_s - 3.0 * self.window_s
        samples.append((wall_s, self.t_s, x, y))
        while len(samples) > 2 and (samples[1][1] <= t_old or samples[1][0] <= wall_old):
            samples.popleft()

    def measured_velocity(self) -> tuple[float, float]:
        """The base's mean velocity over the last :attr:`window_s` of simulated time, heading frame, m/s."""
        (_, t0, x0, y0), (_, t1, x1, y1) = self._samples[0], self._samples[-1]
        if t1 - t0 < 0.5 * self.window_s:
            return (math.nan, math.nan)
        r = self.sim.data.xmat[self._base].tolist()
        yaw = math.atan2(r[3], r[0])
        vx, vy = (x1 - x0) / (t1 - t0), (y1 - y0) / (t1 - t0)
        c, s = math.cos(yaw), math.sin(yaw)
        return (c * vx + s * vy, -s * vx + c * vy)

    def realtime_factor(self) -> float:
        """Simulated over wall time in the last window (0 while paused; NaN before a second frame)."""
        (w0, t0, _, _), (w1, t1, _, _) = self._samples[0], self._samples[-1]
        return (t1 - t0) / (w1 - w0) if w1 > w0 else math.nan

    def distance_m(self) -> float:
        """The base's horizontal distance from where it started (the last reset), m."""
        x, y = self._base_xy()
        return math.hypot(x - self._start_xy[0], y - self._start_xy[1])

    def overlay(self) -> str:
        """The overlay's one line: measured speed, command, steps, real-time factor, and any pause or fall."""
        vx, vy, turn = self.command.values
        mx, my = self.measured_velocity()
        rtf = self.realtime_factor()
        speed = "v n/a" if math.isnan(mx) else f"v fwd {mx:+.2f} lat {my:+.2f} m/s"
        line = (
            f"{speed} | cmd fwd {vx:+.2f} lat {vy:+.2f} m/s turn {turn:+.0f} deg/s | "
            f"step {len(self.sim.controller.steps)} | {'n/a' if math.isnan(rtf) else f'{rtf:.2f}'}x real time"
        )
        if self.fell:
            return line + f" | FELL at {self.fall_time_s - self.t0_s:.2f} s: Backspace resets"
        return line + " | PAUSED (Space)" if self.paused else line

    def summary(self) -> dict:
        """What the session did: the final command (and the shaped one), the distance walked since the last start,
        the simulated and wall times, the counts of steps, falls, resets, keys handled and frames, and the
        mouse's pushes (frames with one, the largest force in N)."""
        vx, vy, turn = self.command.values
        svx, svy, sturn = self.sim.controller.shaper.value
        ctrl = self.sim.controller
        return {
            "robot": self.sim.robot.name,
            "tracker": ctrl.tracker.name,
            "command": {"vx_mps": vx, "vy_mps": vy, "turn_rate_degps": turn},
            "shaped_command": {"vx_mps": svx, "vy_mps": svy, "turn_rate_degps": math.degrees(sturn)},
            "sim_time_s": self.t_s - self.t0_s,
            "total_sim_time_s": self.ticks * self.dt_s,
            "wall_time_s": self.wall_s,
            "realtime_factor": self.ticks * self.dt_s / self.wall_s if self.wall_s > 0 else None,
            "distance_m": self.distance_m(),
            "steps": len(ctrl.steps),
            "fell": self.fell,
            "falls": self.falls,
            "resets": self.resets,
            "keys": self.keys_handled,
            "frames": self.frames,
            "push_frames": self.push_frames,
            "max_push_N": self.max_push_N,
        }
