"""How much friction a walk asks of the ground, by the slope under the foot. Run walks, print a table.

Each walk is one ``amlip-qp walk`` (the Wave Field crossing by default:
``--scenario cassie-waves-60cm-valley-cc-ekf --terrain waves:0.6:2.25``, 8 s),
once per floor friction given (``--friction 1,3``: the friction coefficient of
the floor and the terrain). After every control tick the script reads MuJoCo's
force at each contact between a foot and the ground (``mujoco.mj_contactForce``,
in the contact's frame) and, for contacts carrying more than 20 N, the ratio of
the tangential to the normal force. A ratio at the floor's friction
coefficient means the contact slides. The ratio a foot needs to stand still on
a slope of angle ``a`` under a vertical force alone is ``tan(a)``: 0.73 at 36°,
0.84 at 40°.

The table has one row per friction and band of slope angle (the angle of the
contact normal from the vertical): the contacts, the median and 90th
percentile of the ratio, and the share of contacts at 99 % of the floor's
friction coefficient or more (sliding)::

    python examples/friction_demand.py
    python examples/friction_demand.py --friction 1,2,3 --duration 6 --walk vx=0.45

``--walk KEY=VALUE`` sets any further option of the walk (the names of
``amlip_qp.sim.scenarios.options.WalkOptions``, repeatable). The contacts of
the last 0.2 s before a fall are left out (the robot's body hitting the
ground). About 15 s of compute per 8-s walk on one core.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

import mujoco
import numpy as np

from amlip_qp.exceptions import InputError
from amlip_qp.sim.scenarios import factory
from amlip_qp.sim.scenarios.from_options import scenario_from_options
from amlip_qp.sim.scenarios.options import WalkOptions

DEFAULT_WALK = {"scenario": "cassie-waves-60cm-valley-cc-ekf", "terrain": "waves:0.6:2.25"}
#: Bands of the slope under the contact, degrees from the horizontal.
BANDS_DEG = ((0.0, 5.0), (5.0, 20.0), (20.0, 30.0), (30.0, 36.0), (36.0, 42.0), (42.0, 90.0))
MIN_NORMAL_N = 20.0
BEFORE_FALL_S = 0.2


def contact_rows(params: dict[str, Any]) -> tuple[np.ndarray, float | None]:
    """Per foot-ground contact and tick: (time s, slope deg, normal N, tangential N); and the fall time or None."""
    options = WalkOptions.from_mapping(params)
    scenario = scenario_from_options(options)
    sim = factory.build_simulation(scenario, options.tracker, seed=options.seed, planner=options.planner)
    model = sim.plant.model
    feet = set(sim.plant.foot_body_ids.values())
    force = np.zeros(6)
    rows: list[tuple[float, float, float, float]] = []

    def on_tick(t_s: float, data: mujoco.MjData) -> None:
        for i in range(data.ncon):
            c = data.contact[i]
            bodies = {int(model.geom_bodyid[c.geom1]), int(model.geom_bodyid[c.geom2])}
            if not bodies & feet or bodies - feet != {0}:
                continue  # not between a foot and the ground (the world body's geoms)
            mujoco.mj_contactForce(model, data, i, force)
            slope = float(np.degrees(np.arccos(min(1.0, abs(c.frame[2])))))
            rows.append((t_s, slope, float(force[0]), float(np.hypot(force[1], force[2]))))

    result = sim.run(scenario.duration_s, on_tick=on_tick, log="summary")
    return np.array(rows, dtype=float).reshape(-1, 4), (float(result.fall_time_s) if result.fell else None)


def table_rows(friction: float, rows: np.ndarray, fall_s: float | None) -> list[str]:
    """The Markdown rows of one walk."""
    keep = rows[:, 2] > MIN_NORMAL_N
    if fall_s is not None:
        keep &= rows[:, 0] < fall_s - BEFORE_FALL_S
    ratio = rows[keep, 3] / rows[keep, 2]
    slope = rows[keep, 1]
    end = "walked" if fall_s is None else f"fell at {fall_s:.2f} s"
    out = []
    for lo, hi in BANDS_DEG:
        sel = (slope >= lo) & (slope < hi)
        if not sel.any():
            continue
        r = ratio[sel]
        out.append(
            f"| {friction:g} ({end}) | {lo:g}–{hi:g}° | {int(sel.sum())} | {np.median(r):.2f} | "
            f"{np.percentile(r, 90):.2f} | {np.mean(r >= 0.99 * friction):.0%} |"
        )
    return out


def _frictions(text: str) -> list[float]:
    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected friction coefficients like 1,3, got {text!r}") from None
    if not values or not all(0.05 <= v <= 10.0 for v in values):
        raise argparse.ArgumentTypeError(f"each friction coefficient must be in [0.05, 10], got {text!r}")
    return values


def _walk_option(text: str) -> tuple[str, Any]:
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    try:
        return key, json.loads(value)
    except json.JSONDecodeError:
        return key, value


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--friction", type=_frictions, default=[1.0, 3.0], help="floor friction coefficients (1,3)")
    parser.add_argument("--duration", type=float, default=8.0, help="seconds per walk (8)")
    parser.add_argument("--walk", type=_walk_option, action="append", default=[], help="KEY=VALUE walk option")
    args = parser.parse_args(argv)
    base = {**DEFAULT_WALK, "duration": args.duration, **dict(args.walk)}
    try:  # every walk's options checked before the first one runs
        for mu in args.friction:
            scenario_from_options(WalkOptions.from_mapping({**base, "friction": mu}))
    except InputError as exc:
        parser.error(str(exc))
    print("| floor friction (walk) | slope under the foot | contacts | median ratio | 90th percentile | sliding |")
    print("|---|---|---:|---:|---:|---:|")
    for mu in args.friction:
        rows, fall_s = contact_rows({**base, "friction": mu})
        print("\n".join(table_rows(mu, rows, fall_s)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
