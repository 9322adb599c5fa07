"""The plain data of a run: push validation and impulse, the noisy-orientation quaternion product."""

from __future__ import annotations

import math

import numpy as np
import pytest

from amlip_qp.exceptions import InputError
from amlip_qp.sim.loop.run_types import Push
from amlip_qp.sim.sensing.sensors import quat_mul_small_rotation


@pytest.mark.parametrize(
    "bad",
    [dict(t_s=-1.0), dict(duration_s=0.0), dict(force_N=(float("nan"), 0.0, 0.0)), dict(phase=1.0), dict(phase=-0.1)],
)
def test_push_validation(bad):
    kw = dict(t_s=0.0, force_N=(1.0, 0.0, 0.0), duration_s=0.1)
    kw.update(bad)
    with pytest.raises(InputError):
        Push(**kw)


def test_push_impulse_is_force_norm_times_duration():
    assert Push(1.0, (30.0, -40.0, 0.0), 0.2).impulse_Ns == pytest.approx(10.0)


def test_small_rotation_about_z_turns_the_yaw():
    angle = 0.1
    q = quat_mul_small_rotation(np.array([0.0, 0.0, 0.0, 1.0]), np.array([0.0, 0.0, angle]))
    assert np.allclose(q, [0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2)])
    # the rotation is in the body frame: after a 90 deg yaw, a body-x rotation turns about world y
    yaw90 = np.array([0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)])
    q = quat_mul_small_rotation(yaw90, np.array([angle, 0.0, 0.0]))
    assert np.linalg.norm(q) == pytest.approx(1.0)
    x, y, z, w = q
    R = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    # R = Rz(90 deg) Rx(angle): the body z axis tilts toward world +x by sin(angle)
    assert np.allclose(R[:, 2], [math.sin(angle), 0.0, math.cos(angle)])
    zero = np.array([0.1, 0.2, 0.3, 0.9])
    assert quat_mul_small_rotation(zero, np.zeros(3)) is zero
