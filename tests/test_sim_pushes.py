"""The push schedule: a push at its time, or at a phase of the step after its time."""

from __future__ import annotations

import numpy as np

from amlip_qp.sim.loop.pushes import PushSchedule
from amlip_qp.sim.loop.run_types import Push


def test_a_timed_push_acts_on_its_window_whatever_the_phase():
    sched = PushSchedule([Push(0.010, (50.0, -20.0, 5.0), 0.020)])
    assert np.allclose(sched.force(0.0099, 0.3), 0.0)
    assert np.allclose(sched.force(0.010, 0.9), [50.0, -20.0, 5.0])
    assert np.allclose(sched.force(0.0299), [50.0, -20.0, 5.0])
    assert np.allclose(sched.force(0.030), 0.0)


def test_a_phase_push_starts_when_the_step_phase_reaches_it():
    """After its time, a phase push waits for the phase to cross its value (or a new step at or past it)."""
    sched = PushSchedule([Push(0.010, (7.0, 0.0, 0.0), 0.002, phase=0.5)])
    ticks = [(0.000, 0.40), (0.005, 0.52), (0.010, 0.60), (0.0105, 0.90), (0.011, 0.10), (0.0115, 0.49)]
    for t, s in ticks:  # 0.52 is crossed before 10 ms; at 10 ms the phase is already past 0.5: wait
        assert np.allclose(sched.force(t, s), 0.0)
    assert np.allclose(sched.force(0.012, 0.51), [7.0, 0.0, 0.0])  # crossed: starts here for 2 ms
    assert np.allclose(sched.force(0.0135, 0.8), [7.0, 0.0, 0.0])
    assert np.allclose(sched.force(0.014, 0.9), 0.0)  # 0.012 + 0.002: over, and never again
    assert np.allclose(sched.force(0.020, 0.1), 0.0) and np.allclose(sched.force(0.021, 0.6), 0.0)
    sched.reset()  # a new run: it waits again
    assert np.allclose(sched.force(0.0, 0.4), 0.0) and np.allclose(sched.force(0.0125, 0.55), [7.0, 0.0, 0.0])


def test_phase_zero_is_the_first_tick_of_a_step_and_no_phase_starts_nothing():
    at_step = PushSchedule([Push(0.005, (1.0, 0.0, 0.0), 0.01, phase=0.0)])
    assert np.allclose(at_step.force(0.0, 0.0), 0.0) and np.allclose(at_step.force(0.005, 0.3), 0.0)
    assert np.allclose(at_step.force(0.006, 0.0), [1.0, 0.0, 0.0])  # the next step's first tick
    safe = PushSchedule([Push(0.0, (1.0, 0.0, 0.0), 0.01, phase=0.2)])
    assert np.allclose(safe.force(0.0, float("nan")), 0.0)  # no phase (the controller's safe mode): no start
    assert np.allclose(safe.force(0.001, 0.25), [1.0, 0.0, 0.0])  # no phase before (a run's start): reached


def test_overlapping_pushes_sum():
    sched = PushSchedule([Push(0.0, (10.0, 0.0, 0.0), 0.02), Push(0.01, (5.0, 0.0, 1.0), 0.02, phase=0.0)])
    sched.force(0.0, 0.9)
    assert np.allclose(sched.force(0.015, 0.0), [15.0, 0.0, 1.0])
