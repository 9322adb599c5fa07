"""Stand-ins the tests put in place of the library's heavy parts."""

from __future__ import annotations

import numpy as np

from amlip_qp.control.tracker import Tracker
from amlip_qp.messages import TrackerResult


class ZeroTracker(Tracker):
    """A tracker that commands zero torque: a closed loop without a solver, for plumbing tests."""

    name = "zero"

    def __init__(self, robot):
        self.nu = robot.nu

    def compute(self, kin, target):
        return TrackerResult(tau_Nm=np.zeros(self.nu))
