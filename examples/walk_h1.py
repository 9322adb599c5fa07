"""Unitree H1 walks forward with the whole-body QP tracker on a MuJoCo model and data the script steps.

Usage: ``python examples/walk_h1.py [--duration S] [--vx M/S]``

The README's quickstart loop (:class:`amlip_qp.MujocoLoop`) on the H1 profile's model
(``amlip_qp/models/h1.toml``: Unitree's MJCF from MuJoCo Menagerie, with the profile's
load-time edits). Prints how far the pelvis went; exit status 0 if H1 is upright at the
end, 1 if it fell, 2 with one line on bad input.
"""

from __future__ import annotations

import mujoco

import amlip_qp
from amlip_qp.cli.parsing import Parser, finite_float, float_in


def main(argv=None) -> int:
    ap = Parser(description=__doc__.splitlines()[0])  # one-line errors, exit status 2
    ap.add_argument("--duration", type=float_in(0.0, 600.0, "s"), default=6.0, help="simulated time, s (default 6)")
    ap.add_argument("--vx", type=finite_float, default=0.5, help="forward speed command, m/s (default 0.5)")
    args = ap.parse_args(argv)

    robot = amlip_qp.load_robot("h1")
    model, data = robot.mj_model, robot.new_mj_data("stand")
    loop = amlip_qp.MujocoLoop(robot, amlip_qp.QPTracker(robot), model, data)
    command = loop.command(vx_mps=args.vx)
    pelvis = data.body(robot.base_body)  # a view into data: it follows the simulation
    start = pelvis.xpos.copy()
    for _ in range(round(args.duration / loop.controller.dt_s)):
        loop.step(command)
        mujoco.mj_step(model, data, nstep=loop.substeps)
    dx, dy, _ = pelvis.xpos - start
    upright = pelvis.xpos[2] > 0.7 * start[2]
    state = "upright" if upright else "fallen"
    print(f"H1 walked {dx:.2f} m forward ({dy:+.2f} m sideways) in {data.time:.1f} s, {state}")
    return 0 if upright else 1


if __name__ == "__main__":
    raise SystemExit(main())
