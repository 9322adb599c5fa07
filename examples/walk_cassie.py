"""Cassie walks at 1 m/s, takes a push, and keeps walking, on a MuJoCo model and data the script steps.

Usage: ``python examples/walk_cassie.py [--out DIR] [--duration S] [--tracker qp|pbc] [--no-video]``

The README's quickstart loop (:class:`amlip_qp.MujocoLoop`) with what a loop of your own
can add around it: a 100 N forward shove on the pelvis for 0.2 s at t = 6 s, written into
``data.xfrc_applied`` between the controller's tick and MuJoCo's step, and a video of the
model's ``track`` camera (``DIR/walk_cassie.mp4``, default DIR: ./out; ``MUJOCO_GL=egl``
without a display). The speed command is 1 m/s from the start; the profile's rate limit
ramps it up in 2 s. Prints the distance walked and the speed of the last second; exit
status 0 if Cassie walked, 1 if it fell, 2 with one line on bad input. With the harness's
log, summary and plot instead, from the shell:
``amlip-qp walk --scenario cassie-1mps --push 6:100,0,0:0.2 --json - --plot out/walk_cassie.png``.
"""

from __future__ import annotations

from pathlib import Path

from amlip_qp.sim.reports.gl import prefer_offscreen_gl

prefer_offscreen_gl()  # headless rendering, before mujoco is imported

import mujoco  # noqa: E402

import amlip_qp  # noqa: E402
from amlip_qp.cli.parsing import Parser, float_in  # noqa: E402
from amlip_qp.sim.reports.video import VideoRecorder  # noqa: E402

PUSH_N, PUSH_START_S, PUSH_END_S = (100.0, 0.0, 0.0), 6.0, 6.2


def main(argv=None) -> int:
    ap = Parser(description=__doc__.splitlines()[0])  # one-line errors, exit status 2
    ap.add_argument("--out", default="out", help="output folder (default ./out)")
    ap.add_argument("--duration", type=float_in(0.0, 600.0, "s"), default=10.0, help="simulated time, s (default 10)")
    ap.add_argument("--tracker", choices=["qp", "pbc"], default="qp")
    ap.add_argument("--no-video", action="store_true", help="skip the MP4")
    args = ap.parse_args(argv)

    robot = amlip_qp.load_robot("cassie")
    model, data = robot.mj_model, robot.new_mj_data("stand")
    tracker = amlip_qp.QPTracker(robot) if args.tracker == "qp" else amlip_qp.PBCTracker(robot)
    loop = amlip_qp.MujocoLoop(robot, tracker, model, data)
    command = loop.command(vx_mps=1.0)
    pelvis = data.body(robot.base_body)
    recorder = None
    if not args.no_video:
        Path(args.out).mkdir(parents=True, exist_ok=True)
        recorder = VideoRecorder(model, Path(args.out) / "walk_cassie.mp4")
    ticks, per_s = round(args.duration / loop.controller.dt_s), round(1.0 / loop.controller.dt_s)
    z_stand, x_before = float(pelvis.xpos[2]), float(pelvis.xpos[0])  # then: the x one second before the end
    try:
        for k in range(ticks):
            if k == ticks - per_s:
                x_before = float(pelvis.xpos[0])
            loop.step(command)
            pushed = PUSH_START_S <= data.time < PUSH_END_S
            pelvis.xfrc_applied[:3] = PUSH_N if pushed else (0.0, 0.0, 0.0)
            mujoco.mj_step(model, data, nstep=loop.substeps)
            if recorder is not None:
                recorder(data.time, data)
            if pelvis.xpos[2] < 0.5 * z_stand:
                print(f"Cassie fell at t = {data.time:.2f} s ({args.tracker})")
                return 1
    finally:
        if recorder is not None:
            recorder.close()
    speed = (pelvis.xpos[0] - x_before) / min(1.0, data.time)
    print(
        f"Cassie walked {pelvis.xpos[0]:.2f} m in {data.time:.1f} s ({args.tracker}), "
        f"{speed:.2f} m/s over the last {min(1.0, data.time):g} s, {len(loop.controller.steps)} steps"
        + ("" if recorder is None else f"  ->  {args.out}/walk_cassie.mp4")
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
