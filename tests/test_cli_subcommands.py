"""Tests of amlip_qp.cli.subcommands: the walk, compare and sweep options."""

from __future__ import annotations

from amlip_qp.cli import build_parser
from amlip_qp.cli import subcommands as S


def test_the_light_name_lists_match_the_heavy_modules():
    from amlip_qp.control import registry
    from amlip_qp.control.walking import planners
    from amlip_qp.sim.scenarios import factory
    from amlip_qp.sim.scenarios import options as O
    from amlip_qp.sim.sensing import sensors

    assert S.SENSORS == O.SENSORS == sensors.SENSOR_MODELS
    assert S.ESTIMATORS == O.ESTIMATORS == factory.ESTIMATORS
    assert set(S.TRACKERS) == set(O.TRACKERS) == set(registry.TRACKER_MODULES)
    assert S.PLANNERS == O.PLANNERS == planners.PLANNERS


def test_walk_and_compare_take_the_plant_options():
    parser = build_parser()
    plant = ["--plant", "cassie-closed-chain", "--terrain", "slope:5", "--friction", "0.6", "--actuator-delay", "2"]
    for command in (["walk"], ["compare"]):
        args = parser.parse_args([*command, *plant])
        assert (args.plant, args.terrain, args.friction, args.actuator_delay) == (
            "cassie-closed-chain",
            "slope:5",
            0.6,
            2,
        )
    sweep = parser.parse_args(["sweep", "--grid", "vx=0.5,1", "--out", "d"])
    assert sweep.grid == ["vx=0.5,1"] and sweep.workers is None and sweep.ray is None
