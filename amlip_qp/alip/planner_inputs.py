"""The ALIP planner's inputs checked: its settings, each tick's estimate and command, the terrain prediction.

:class:`~amlip_qp.alip.planner.Planner` calls :func:`check_settings` when it is
built and, every tick, :func:`check_tick` and :func:`ground_terms` (the
:class:`~amlip_qp.messages.TerrainPrediction` checked and turned into the
kernels' height differences and ground terms; ``None`` is flat ground). Each
raises :class:`~amlip_qp.exceptions.InputError` saying what to give.
"""

from __future__ import annotations

from amlip_qp.alip import _checks as C
from amlip_qp.alip import outputs as O
from amlip_qp.alip.clock import StepClock
from amlip_qp.exceptions import InputError
from amlip_qp.messages import Command, StateEstimate, TerrainPrediction

#: The meanings of ``Command.vx_mps`` / ``vy_mps`` the planner knows (see :class:`~amlip_qp.alip.planner.Planner`).
SPEED_REFERENCES = ("mean", "end_of_step")
#: The ground terms of flat ground: ``(dz_sw0, dz_sw, pitch0, pitch)`` all 0 (m, m, rad, rad).
FLAT_GROUND = (0.0, 0.0, 0.0, 0.0)


def check_settings(mass_kg, g, plan_fn, reference_fn, speed_reference, clock, late_descent) -> None:
    """The :class:`~amlip_qp.alip.planner.Planner`'s arguments (mass kg, gravity m/s^2, ...), as its doc says."""
    C.positive("mass_kg", mass_kg, "kg")
    C.positive("g (gravity magnitude)", g, "m/s^2")
    if speed_reference not in SPEED_REFERENCES:
        raise InputError(f"speed_reference must be one of {SPEED_REFERENCES}, got {speed_reference!r}")
    if plan_fn is not None and not callable(plan_fn):
        raise InputError(f"plan_fn must be callable (16 floats -> 8 floats), got {plan_fn!r}")
    if clock is not None and not isinstance(clock, StepClock):
        raise InputError(f"clock must be a StepClock, got {type(clock).__name__}")
    if reference_fn is not None and not callable(reference_fn):
        raise InputError(f"reference_fn must be callable (15 floats -> 30 floats), got {reference_fn!r}")
    if late_descent is not None and late_descent != "landing":
        if isinstance(late_descent, (bool, str)) or not isinstance(late_descent, (int, float)):
            raise InputError(f"late_descent must be None, 'landing' or a rate in m/s, got {late_descent!r}")
        C.positive("late_descent (descent rate)", late_descent, "m/s")


def check_tick(stance: str | None, estimate: StateEstimate, command: Command) -> None:
    """One tick's estimate and command, against the current step's ``stance`` (``None``: no step yet)."""
    if stance is None:
        raise InputError("Planner.update called before start_step(); call start_step at the first touchdown")
    if not isinstance(estimate, StateEstimate) or not isinstance(command, Command):
        raise InputError(
            f"update needs a StateEstimate and a Command, got {type(estimate).__name__} and {type(command).__name__}"
        )
    if estimate.stance != stance:
        raise InputError(
            f"estimate.stance={estimate.stance!r} but the current step has stance {stance!r}; "
            "call start_step at touchdown before updating with the new stance"
        )


def ground_terms(
    terrain: TerrainPrediction | None, H: float, clearance_m: float
) -> tuple[float, float, tuple[float, float, float, float]]:
    """``(dz_next, dz_sw, ground)`` of a terrain prediction (m, m, and the kernels' ground terms
    ``(dz_sw0, dz_sw, pitch0, pitch)``), checked against the CoM height ``H`` and the swing
    clearance (m); ``None`` is flat ground (all zeros)."""
    if terrain is None:
        dz_next = dz_sw = 0.0
        ground = FLAT_GROUND
    else:
        if not isinstance(terrain, TerrainPrediction):
            raise InputError(f"terrain must be a TerrainPrediction or None, got {type(terrain).__name__}")
        dz_next, dz_sw = terrain.dz_next_m, terrain.dz_sw_m
        ground = (terrain.dz_sw0_m, dz_sw, terrain.slope_pitch0_rad, terrain.slope_pitch_rad)
        if not abs(dz_next) < H:
            raise InputError(
                f"terrain.dz_next_m={dz_next!r} m must be smaller in size than H = {H!r} m (the CoM height over "
                "the stance contact); check the terrain prediction"
            )
        O.check_ground(ground, H, clearance_m)
    return dz_next, dz_sw, ground
