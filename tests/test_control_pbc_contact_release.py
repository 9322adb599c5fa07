"""The PBC's release of a stance contact that would pull the foot (``PBCGains.release_pulling_contact``)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from amlip_qp.control.pbc.contact_release import solve_released
from amlip_qp.control.pbc.gains import PBCGains, default_gains, gains_from_table
from amlip_qp.control.pbc.tracker import PBCTracker
from amlip_qp.exceptions import InputError
from amlip_qp.robots import load_robot
from amlip_qp.robots.kinematics import RobotKinematics
from amlip_qp.sim.scenarios.factory import build_simulation
from amlip_qp.sim.scenarios.named import get_scenario
from amlip_qp.sweep.run_cell import walk_run


def _tracker(robot, release: bool) -> PBCTracker:
    return PBCTracker(robot, dataclasses.replace(default_gains(robot), release_pulling_contact=release))


@pytest.mark.parametrize("name", ["cassie", "rabbit"])
def test_the_released_solve_is_the_dynamics_with_the_foot_free_and_the_springs_held(name):
    """Without the contact rows: M vdot + h - tau_pas = B tau + J_s^T lambda_s (Pinocchio's RNEA, the
    contact's lambda zero), J_s vdot = 0 for the rigid springs, and the controlled joints' commanded
    accelerations; the contact foot then accelerates (it is free)."""
    robot = load_robot(name)
    rng = np.random.default_rng(3)
    q = robot.q_stand.copy()
    q[robot.actuated.pin_q_idx] += rng.normal(0.0, 0.02, robot.nu)
    v = rng.normal(0.0, 0.3, robot.nv)
    kin = RobotKinematics(robot)
    kin.update(q, v)
    tracker = _tracker(robot, True)
    stance = "left"
    lay = tracker.layout(stance)
    vdot_cmd = rng.normal(0.0, 5.0, len(lay.ctrl_v))
    held = tracker.solve_dynamics(kin, stance, vdot_cmd)  # fills the system of this tick
    vdot, tau_c, lam = solve_released(lay.K, lay.rhs, robot.nv, len(lay.ctrl_v), lay.n_contact)
    assert lam.shape == held[2].shape and np.all(lam[: lay.n_contact] == 0.0)
    Jc, jdv = tracker.constraints(kin, stance)  # contact rows, then the springs'
    tau_full = np.zeros(robot.nv)
    tau_full[lay.ctrl_v] = tau_c
    rnea = pin.rnea(robot.pin_model, robot.pin_model.createData(), q, v, vdot)
    residual = rnea - kin.passive_forces() - tau_full - Jc.T @ lam
    assert np.max(np.abs(residual)) < 1e-8 * max(1.0, np.max(np.abs(rnea)))
    springs = slice(lay.n_contact, None)
    np.testing.assert_allclose(Jc[springs] @ vdot + jdv[springs], 0.0, atol=1e-9)
    np.testing.assert_allclose(vdot[lay.ctrl_v], vdot_cmd, atol=1e-9)
    # the held solve keeps the foot still; the released one lets it move
    assert np.max(np.abs(Jc[: lay.n_contact] @ held[0] + jdv[: lay.n_contact])) < 1e-9
    assert np.max(np.abs(Jc[: lay.n_contact] @ vdot + jdv[: lay.n_contact])) > 1e-3


def _walk_normal_forces(release: bool, duration_s: float = 1.0):
    """Cassie's PBC at 1 m/s: the commanded normal force of every tick, whether it was released, the count."""
    sc = get_scenario("cassie-1mps").with_(duration_s=duration_s)
    tracker = _tracker(load_robot("cassie"), release)
    forces, released = [], []
    compute = tracker.compute

    def recording(kin, target):
        result = compute(kin, target)
        forces.append(result.info["contact_force_z_N"])
        released.append(result.info.get("contact_released", 0.0) == 1.0)
        return result

    tracker.compute = recording  # type: ignore[method-assign]
    result = build_simulation(sc, tracker).run(duration_s, log="summary")
    assert not result.fell
    return np.array(forces), np.array(released), tracker.contact_releases


def test_with_the_release_the_pbc_never_commands_a_pulling_contact_force():
    """The paper's PBC (the default) commands a negative normal force in some ticks of a nominal walk;
    with the release, every such tick is solved again with the contact force zero."""
    forces, released, count = _walk_normal_forces(False)
    assert forces.min() < -1.0 and count == 0 and not released.any()
    forces, released, count = _walk_normal_forces(True)
    assert count == released.sum() > 0
    assert np.all(forces[released] == 0.0) and forces[~released].min() >= 0.0


def test_the_release_saves_the_pbcs_weakest_push_map_cell():
    """The push map's weakest PBC cell with the step-timing MPC: 28.1 N s forward-left (45 deg) at phase
    0.8 of a step after 3 s, Cassie at 1 m/s (the walk as the map runs it). The paper's PBC falls; with
    the release it stands at the end of the map's 5.5 s."""
    params = {
        "robot": "cassie", "vx": 1.0, "duration": 5.5, "tracker": "pbc", "planner": "mpc", "push_time_s": 3.0,
        "push_duration_s": 0.2, "push_direction_deg": 45.0, "push_phase": 0.8, "push_impulse_Ns": 28.125,
    }  # fmt: skip
    run = walk_run(params, seed=0)
    fell = {}
    for release in (False, True):
        sim = build_simulation(run.scenario, _tracker(load_robot("cassie"), release), planner=run.planner)
        fell[release] = sim.run(run.scenario.duration_s, log="summary").fell
    assert fell == {False: True, True: False}


def test_the_release_is_a_profile_flag():
    assert PBCGains().release_pulling_contact is False
    assert all(not default_gains(load_robot(n)).release_pulling_contact for n in ("cassie", "rabbit", "h1"))
    assert gains_from_table({"release_pulling_contact": True}).release_pulling_contact is True
    with pytest.raises(InputError, match="release_pulling_contact must be true or false"):
        gains_from_table({"release_pulling_contact": 1})
    with pytest.raises(InputError, match="release_pulling_contact must be True or False"):
        PBCGains(release_pulling_contact="yes")  # type: ignore[arg-type]
