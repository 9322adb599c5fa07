"""The walking controller's foot-placement planner, by name (the one-step law or the step-timing MPC),
and how it plans each tick, on flat ground or off it (:func:`plan_tick`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

from amlip_qp.alip.clock import StepClock
from amlip_qp.alip.mpc_planner import MPCPlanner, MPCSettings
from amlip_qp.alip.planner import Planner
from amlip_qp.alip.step_timing import StepTiming
from amlip_qp.control.walking.ground import GroundPredictor
from amlip_qp.exceptions import InputError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from amlip_qp.control.walking.estimator import Estimate
    from amlip_qp.messages import Command, PlannerOutput, StateEstimate

#: The planners (``WalkingController(planner=...)``, ``amlip-qp walk --planner``).
PLANNERS = ("one-step", "mpc")
#: The one-step planner's step time when the terrain-aware mode moves its target onto a tread
#: (:mod:`amlip_qp.alip.step_timing`): 1.0 to 1.4 times the command's (lengthened, never shortened:
#: docs/TUNING.md, "Terrain"). In that mode the step-timing MPC's shortest step is the same
#: (:func:`make_planner`): a short step leaves the swing foot too little time to climb a riser.
FOOTHOLD_TIMING = StepTiming(step_time_min=1.0)


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
    shortest_step_s: float = 0.0,
    aware: bool = False,
) -> Planner:
    """The planner ``name`` (:data:`PLANNERS`) on ``clock``, its kernels the generated C (``backend="c"``)
    or the numpy references (``"numpy"``): ``"one-step"``, the paper's
    :class:`~amlip_qp.alip.planner.Planner`; ``"mpc"``, the step-timing
    :class:`~amlip_qp.alip.mpc_planner.MPCPlanner` (:func:`amlip_qp.control.mpc.make_mpc_planner`),
    its ``step_time_min_s`` raised to ``shortest_step_s`` (the tracker's shortest step, s;
    :attr:`~amlip_qp.control.tracker.Tracker.shortest_step_s`) and, for the terrain-aware mode
    (``aware``), its ``step_time_min`` to that of :data:`FOOTHOLD_TIMING`: no step shorter than the
    command's ``T``, as the one-step planner's there.

    Raises:
        InputError: An unknown planner, MPC settings for another planner, or (``aware``) an MPC
            ``step_time_max`` below 1.0."""
    check_planner(name, mpc_settings)
    if name == "mpc":
        from amlip_qp.control.mpc import make_mpc_planner

        base = mpc_settings or MPCSettings()
        if shortest_step_s > base.step_time_min_s:
            base = replace(base, step_time_min_s=float(shortest_step_s))
        if aware and FOOTHOLD_TIMING.step_time_min > base.step_time_min:
            if base.step_time_max < FOOTHOLD_TIMING.step_time_min:
                raise InputError(
                    "terrain-aware, the MPC plans no step shorter than T: MPCSettings.step_time_max must be"
                    f" >= {FOOTHOLD_TIMING.step_time_min}, got {base.step_time_max!r}"
                )
            base = replace(base, step_time_min=FOOTHOLD_TIMING.step_time_min)
        mpc_settings = base

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


def extra(planner: Planner, ground: GroundPredictor) -> dict:
    """The keywords of a planner's update off flat ground beyond the foothold hook: the MPC's regions
    (:func:`mpc_regions`); for the one-step planner in the ``"aware"`` mode the step timing of a moved
    foothold (:data:`FOOTHOLD_TIMING`)."""
    if isinstance(planner, MPCPlanner):
        return mpc_regions(planner, ground)
    return {"timing": FOOTHOLD_TIMING} if ground.foothold() is not None else {}


def plan_tick(
    planner: Planner,
    ground: GroundPredictor,
    state: StateEstimate,
    command: Command,
    est: Estimate,
    new_step: bool,
    last_plan: PlannerOutput | None,
) -> PlannerOutput:
    """The planner's update of one control tick. On flat ground (``ground`` inactive): for ``state`` and
    ``command``. Off it: with the ground predicted at the swing target (``last_plan``'s; before any
    plan the swing foot's contact, ``est.swing_contact_m``) and the command fit to it; at a new step
    (``new_step``: the first step or a touchdown) the ground first takes the new stance foothold
    (``est.stance_contact_m``), and the planner plans once to find the new step's swing target."""
    if not ground.active:
        return planner.update(state, command)
    if new_step:
        ground.touchdown(est.stance_contact_m, planner.heading_rad)
        # the swing target of the new step is not known yet: plan once for it
        first = ground.predict(est.stance_contact_m, planner.heading_rad)
        plan = planner.update(state, ground.fit(first, command), first, ground.foothold(), **extra(planner, ground))
        target_xy = plan.swing_target_world_m
    else:
        target_xy = last_plan.swing_target_world_m if last_plan is not None else est.swing_contact_m
    prediction = ground.predict(target_xy, planner.heading_rad)
    return planner.update(
        state, ground.fit(prediction, command), prediction, ground.foothold(), **extra(planner, ground)
    )
