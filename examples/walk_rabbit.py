"""Rabbit (planar, five links) stands for 1 s, then speeds up to 0.8 m/s: the walking controller assembled by hand.

Usage: ``python examples/walk_rabbit.py [--duration S] [--tracker qp|pbc]``

Shows the pieces :class:`amlip_qp.MujocoLoop` builds from a tracker alone: the Pinocchio
kinematics the controller and the tracker share, and the walking controller (estimator,
gait logic, ALIP planner on the generated C, tracker) with options of its own, here a
gentler rate limit of the speed command than the profile's (0.2 m/s^2: 0.8 m/s in 4 s).
Prints the forward speed of each simulated second; exit status 0 if Rabbit walked,
1 if it fell, 2 with one line on bad input.
"""

from __future__ import annotations

import math

import mujoco

import amlip_qp
from amlip_qp.cli.parsing import Parser, float_in
from amlip_qp.profiles import CommandShaping


def main(argv=None) -> int:
    ap = Parser(description=__doc__.splitlines()[0])  # one-line errors, exit status 2
    ap.add_argument("--duration", type=float_in(0.0, 600.0, "s"), default=8.0, help="simulated time, s (default 8)")
    ap.add_argument("--tracker", choices=["qp", "pbc"], default="qp")
    args = ap.parse_args(argv)

    robot = amlip_qp.load_robot("rabbit")
    tracker = amlip_qp.QPTracker(robot) if args.tracker == "qp" else amlip_qp.PBCTracker(robot)
    shaping = CommandShaping(vx_accel_mps2=0.2, vy_accel_mps2=math.inf, turn_accel_radps2=math.inf)
    controller = amlip_qp.WalkingController(robot, tracker, command_shaping=shaping)
    model, data = robot.mj_model, robot.new_mj_data("stand")
    loop = amlip_qp.MujocoLoop(robot, controller, model, data)
    stand, walk = loop.command(vx_mps=0.0), loop.command(vx_mps=0.8)  # the planner sees the shaped ramp
    torso = data.body(robot.base_body)
    x_last, z_stand, ticks_per_s = float(torso.xpos[0]), float(torso.xpos[2]), round(1.0 / controller.dt_s)
    for k in range(1, round(args.duration / controller.dt_s) + 1):
        loop.step(stand if data.time < 1.0 else walk)
        mujoco.mj_step(model, data, nstep=loop.substeps)
        if k % ticks_per_s == 0:
            print(f"t = {data.time:4.1f} s  speed {torso.xpos[0] - x_last:5.2f} m/s  height {torso.xpos[2]:.2f} m")
            x_last = float(torso.xpos[0])
        if torso.xpos[2] < 0.5 * z_stand:  # the torso at half its standing height: fallen
            print(f"Rabbit fell at t = {data.time:.2f} s")
            return 1
    print(f"Rabbit walked {torso.xpos[0]:.2f} m in {data.time:.1f} s, {len(controller.steps)} steps ({args.tracker})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
