"""The outputs a profile may declare: each a named primitive quantity of the robot's state.

A walking controller drives a list of outputs ``y = h_0(q)`` to references
``h_d(s)`` (docs/ARCHITECTURE.md). A profile declares its robot's list in its
``outputs`` key, by name, in the order the trackers' gain tables follow; each
name is one primitive (:class:`OutputPrimitive`):

=====================  ==================  ===================================================
name                   primitive           value (SI: rad, m)
=====================  ==================  ===================================================
``torso_pitch``        base angle          the base body's pitch (z-y-x Euler angles; a planar
                                           root's pitch about the world y axis)
``torso_roll``         base angle          the base body's roll (z-y-x Euler angles)
``stance_hip_yaw``     joint angle         the stance leg's ``hip_yaw`` joint
``swing_hip_yaw``      joint angle         the swing leg's ``hip_yaw`` joint
``com_z_over_stance``  CoM over a contact  CoM minus the stance contact point, z
``com_x_over_swing``   CoM over a contact  CoM minus the swing contact point, the step's heading x
``com_y_over_swing``   CoM over a contact  CoM minus the swing contact point, the step's heading y
``com_z_over_swing``   CoM over a contact  CoM minus the swing contact point, z
``swing_toe_pitch``    foot angle          the swing foot's pitch along the heading, from its
                                           sole line (toe minus heel: a two-point foot's
                                           points, a four-point foot's pair midpoints)
``swing_foot_roll``    foot angle          the swing foot's roll, from its contact frame's
                                           rotation (z-y-x Euler angles)
=====================  ==================  ===================================================

Every name has a reference of the planner (:mod:`amlip_qp.alip.outputs`,
whose :data:`~amlip_qp.alip.outputs.REFERENCE_OUTPUTS` are these names in the
kernels' order). A profile declares the ones its legs need: the leg's actuated
joints minus the ones passive in stance (checked when the robot is loaded,
with the output Jacobian's rank at the stand pose).

This module imports nothing but :mod:`amlip_qp.exceptions`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from amlip_qp.exceptions import InputError

#: The primitive kinds, in the order of the module doc's table.
PRIMITIVE_KINDS: tuple[str, ...] = ("base_angle", "joint", "com_over_contact", "foot_angle")


@dataclass(frozen=True)
class OutputPrimitive:
    """One output: a primitive quantity and its parameters (module doc).

    Attributes:
        name: The output's name.
        kind: One of :data:`PRIMITIVE_KINDS`.
        axis: ``"pitch"``/``"roll"`` for an angle; ``"x"``, ``"y"``, ``"z"`` for a CoM component
            (x and y in the step's heading frame, z vertical).
        side: ``"stance"`` or ``"swing"``: the leg of a joint or foot angle, the contact the CoM
            is measured from; ``""`` for a base angle.
        role: The joint role of a joint angle (``amlip_qp.profiles.JOINT_ROLES``); ``""`` otherwise.
    """

    name: str
    kind: str
    axis: str = ""
    side: str = ""
    role: str = ""

    @property
    def lateral(self) -> bool:
        """True for a quantity out of the sagittal plane (a planar robot has none)."""
        return self.axis in ("roll", "y") or self.role == "hip_yaw"


#: Every output a profile may declare, by name (module doc).
OUTPUT_PRIMITIVES: dict[str, OutputPrimitive] = {
    p.name: p
    for p in (
        OutputPrimitive("torso_pitch", "base_angle", axis="pitch"),
        OutputPrimitive("torso_roll", "base_angle", axis="roll"),
        OutputPrimitive("stance_hip_yaw", "joint", side="stance", role="hip_yaw"),
        OutputPrimitive("swing_hip_yaw", "joint", side="swing", role="hip_yaw"),
        OutputPrimitive("com_z_over_stance", "com_over_contact", axis="z", side="stance"),
        OutputPrimitive("com_x_over_swing", "com_over_contact", axis="x", side="swing"),
        OutputPrimitive("com_y_over_swing", "com_over_contact", axis="y", side="swing"),
        OutputPrimitive("com_z_over_swing", "com_over_contact", axis="z", side="swing"),
        OutputPrimitive("swing_toe_pitch", "foot_angle", axis="pitch", side="swing"),
        OutputPrimitive("swing_foot_roll", "foot_angle", axis="roll", side="swing"),
    )
}

#: The outputs every walking robot declares: the planner's foot placement acts through them.
REQUIRED_OUTPUTS: tuple[str, ...] = ("com_z_over_stance", "com_x_over_swing", "com_z_over_swing")


def output_primitives(names: Sequence[str], planar: bool = False) -> tuple[OutputPrimitive, ...]:
    """The primitives of the outputs ``names``, in order.

    Args:
        names: Output names (module doc), each once.
        planar: The robot walks in the sagittal plane only: no lateral output.

    Raises:
        InputError: A name is unknown or repeated, a required output is missing, a lateral one is
            declared for a planar robot, or a 3-D robot lacks ``com_y_over_swing``.
    """
    if isinstance(names, str) or not all(isinstance(n, str) for n in names):
        raise InputError(f"outputs must be a list of output names, got {names!r}")
    unknown = [n for n in names if n not in OUTPUT_PRIMITIVES]
    if unknown:
        raise InputError(f"unknown output {unknown[0]!r}; known: {', '.join(OUTPUT_PRIMITIVES)}")
    repeated = sorted({n for n in names if list(names).count(n) > 1})
    if repeated:
        raise InputError(f"output {repeated[0]!r} is declared more than once")
    missing = [n for n in REQUIRED_OUTPUTS if n not in names]
    if missing:
        raise InputError(f"outputs must include {', '.join(missing)} (the foot placement acts through them)")
    primitives = tuple(OUTPUT_PRIMITIVES[n] for n in names)
    lateral = [p.name for p in primitives if p.lateral]
    if planar and lateral:
        raise InputError(f"a planar robot has no lateral output: drop {', '.join(lateral)}")
    if not planar and "com_y_over_swing" not in names:
        raise InputError("a 3-D robot needs com_y_over_swing (the lateral foot placement acts through it)")
    return primitives
