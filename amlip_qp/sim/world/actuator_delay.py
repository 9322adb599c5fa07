"""The actuator delay: a FIFO of whole controller ticks between the controller's command and the plant.

One of the plant modifiers (``--actuator-delay TICKS``,
:attr:`~amlip_qp.sim.world.plant_modifiers.PlantModifiers.actuator_delay_ticks`),
the one that is not an edit of the plant's ``MjSpec``: the harness puts it
between the controller and ``data.ctrl``. ``ActuatorDelay(0, nu)`` hands back
the very array it is given.
"""

from __future__ import annotations

import numbers

import numpy as np

from amlip_qp.exceptions import InputError
from amlip_qp.sim.world.plant_modifiers import PlantModifiers


class ActuatorDelay:
    """A FIFO of ``n_ticks`` controller ticks between the command and the actuators.

    ``push(ctrl)`` returns the control vector pushed ``n_ticks`` pushes
    earlier. Before that many pushes, it returns the first pushed vector: the
    plant starts as if the controller had held its first command before the
    run began (zeros would drop a standing robot for the first ticks).
    ``n_ticks = 0`` is a pass-through that returns the very array it is given.

    Args:
        n_ticks: Delay, whole ticks, in [0, 100].
        nu: Length of the control vector.
    """

    n_ticks: int
    nu: int
    _buffer: np.ndarray
    _next: int
    _started: bool

    def __init__(self, n_ticks: int, nu: int):
        PlantModifiers(actuator_delay_ticks=n_ticks)
        if not isinstance(nu, numbers.Integral) or isinstance(nu, bool) or nu < 1:
            raise InputError(f"ActuatorDelay needs the control vector length nu >= 1, got {nu!r}")
        self.n_ticks = int(n_ticks)
        self.nu = int(nu)
        self._buffer = np.zeros((self.n_ticks, self.nu))
        self._next = 0
        self._started = False

    def push(self, ctrl: np.ndarray) -> np.ndarray:
        """Queue this tick's command; return the one to apply now (``n_ticks`` ticks old)."""
        ctrl = np.asarray(ctrl)
        if ctrl.shape != (self.nu,):
            raise InputError(f"ActuatorDelay takes a control vector of shape ({self.nu},), got shape {ctrl.shape}")
        if self.n_ticks == 0:
            return ctrl
        if not self._started:
            self._buffer[:] = ctrl
            self._started = True
        out = self._buffer[self._next].copy()
        self._buffer[self._next] = ctrl
        self._next = (self._next + 1) % self.n_ticks
        return out

    def reset(self) -> None:
        """Forget every queued command (the next push starts afresh)."""
        self._buffer[:] = 0.0
        self._next = 0
        self._started = False
