"""Rabbit (planar) walks at 0.5 m/s (scenario ``rabbit-0.5mps``, 20 s): summary, figure and video.

Usage: ``python examples/walk_rabbit.py [--out DIR] [--tracker qp|pbc] [--no-video]``
Writes ``DIR/walk_rabbit.json``, ``DIR/walk_rabbit.png`` and ``DIR/walk_rabbit.mp4``
(default DIR: ./out). A thin wrapper over ``amlip-qp walk``; exit status as the CLI's
(0 walked, 1 fell).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from amlip_qp.sim.video import prefer_offscreen_gl

prefer_offscreen_gl()

from amlip_qp import cli  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out", help="output folder (default ./out)")
    ap.add_argument("--tracker", choices=["qp", "pbc"], default="qp")
    ap.add_argument("--no-video", action="store_true", help="skip the MP4")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cmd = ["walk", "--scenario", "rabbit-0.5mps", "--tracker", args.tracker]
    cmd += ["--json", str(out / "walk_rabbit.json"), "--plot", str(out / "walk_rabbit.png")]
    if not args.no_video:
        cmd += ["--video", str(out / "walk_rabbit.mp4")]
    return cli.main(cmd)


if __name__ == "__main__":
    raise SystemExit(main())
