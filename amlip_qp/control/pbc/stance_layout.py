"""The PBC's bookkeeping for one stance side: the controlled joints, their gains and the system's buffers.

:class:`~amlip_qp.control.pbc.tracker.PBCTracker` makes one per side; its system (1)-(3) is written
into ``K`` and ``rhs`` (by :mod:`~amlip_qp.control.pbc.dynamics_compiled` or
:meth:`PBCTracker.assemble_dynamics <amlip_qp.control.pbc.tracker.PBCTracker.assemble_dynamics>`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class StanceLayout:
    """Index bookkeeping and gains for one stance side (read-only; see
    :meth:`PBCTracker.layout <amlip_qp.control.pbc.tracker.PBCTracker.layout>`)."""

    ctrl: np.ndarray  # indices into the actuator list of the controlled joints
    ctrl_v: np.ndarray  # their Pinocchio v indices
    ctrl_q: np.ndarray  # their Pinocchio q indices
    kp: np.ndarray = field(default_factory=lambda: np.zeros(0))
    kd: np.ndarray = field(default_factory=lambda: np.zeros(0))
    swing_mask: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    swing_pos: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))  # positions of swing_mask's
    swing_v: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))  # ... and their v indices
    K: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # KKT matrix, constant entries preset
    rhs: np.ndarray = field(default_factory=lambda: np.zeros(0))
    n_contact: int = 0  # contact rows (the spring rows follow)
