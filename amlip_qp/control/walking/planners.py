"""The walking controller's foot-placement planner, by name: the one-step law or the step-timing MPC."""

from __future__ import annotations

from collections.abc import Sequence

from amlip_qp.alip.clock import StepClock
from amlip_qp.alip.mpc_planner import MPCPlanner, MPCSettings
from amlip_qp.alip.planner import Planner
from amlip_qp.control.walking.ground import GroundPredictor
from amlip_qp.exceptions import InputError

#: The planners (``WalkingController(planner=...)``, ``amlip-qp walk --planner``).
PLANNERS = ("one-step", "mpc")


def check_planner(name: str, mpc_settings: MPCSettings | None) -> None:
    """Raise InputError for an unknown planner, or MPC settings given to another planner."""
    if name not in PLANNERS:
        raise InputError(f"planner must be one of {PLANNERS}, got {name!r}")
    if mpc_settings is not None and name != "mpc":
        raise InputError("mpc_settings are the step-timing MPC's: pass planner='mpc' with them")
    if mpc_settings is not None and not isinstance(mpc_settings, MPCSettings):
        raise InputError(f"mpc_settings must be MPCSettings, got {type(mpc_settings).__name__}")


def make_planner(
    name: str,
    outputs: Sequence[str],
    mass_kg: float,
    clock: StepClock,
    backend: str,
    late_descent: str | None,
    mpc_settings: MPCSettings | None = None,
) -> Planner:
    """The planner ``name`` (:data:`PLANNERS`) on ``clock``, its kernels the generated C (``backend="c"``)
    or the numpy references (``"numpy"``): ``"one-step"``, the paper's
    :class:`~amlip_qp.alip.planner.Planner`; ``"mpc"``, the step-timing
    :class:`~amlip_qp.alip.mpc_planner.MPCPlanner` (:func:`amlip_qp.control.mpc.make_mpc_planner`)."""
    check_planner(name, mpc_settings)
    if name == "mpc":
        from amlip_qp.control.mpc import make_mpc_planner

        return make_mpc_planner(
            outputs, mass_kg, backend=backend, settings=mpc_settings, clock=clock, late_descent=late_descent
        )
    plan_fn = reference_fn = None
    if backend == "c":
        from amlip_qp.codegen import load_kernels

        kernels = load_kernels()
        plan_fn, reference_fn = kernels.alip_plan, kernels.swing_reference
    return Planner(outputs, mass_kg, plan_fn=plan_fn, reference_fn=reference_fn, clock=clock, late_descent=late_descent)


def mpc_regions(planner: Planner, ground: GroundPredictor) -> dict:
    """The keywords of the MPC planner's update with its foothold regions: from the terrain around the
    last tick's planned footholds (:meth:`GroundPredictor.regions
    <amlip_qp.control.walking.ground.GroundPredictor.regions>`, the ``"aware"`` mode); ``{}`` for the
    one-step planner, the other modes and the first tick of a step."""
    if not isinstance(planner, MPCPlanner) or planner.last_plan is None or not planner.last_plan.solved:
        return {}
    regions = ground.regions(planner.last_plan.footholds_m, planner.heading_next_rad)
    return {} if regions is None else {"regions": regions}
