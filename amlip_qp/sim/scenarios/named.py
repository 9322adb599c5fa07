"""The named scenarios: every bundled robot's, built from its profile's tables on first use.

:data:`SCENARIOS` holds each bundled profile's ``[scenarios]``, ``[settings]``
and ``[mismatches]`` scenarios (:mod:`~amlip_qp.sim.scenarios.scenario_tables`)
by name ``ROBOT-KEY``; the CLI, the examples, the comparison and the tests
take them from here.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping

from amlip_qp.exceptions import InputError
from amlip_qp.profiles import bundled_names, get_profile
from amlip_qp.sim.loop.run_types import PlantSetting
from amlip_qp.sim.scenarios.scenario_tables import profile_scenarios
from amlip_qp.sim.scenarios.scenarios import Scenario


class _Scenarios(Mapping[str, "Scenario"]):
    """Named scenarios by name, built from the bundled profiles' tables on first use (read-only).

    ``only`` keeps those a predicate accepts (the terrain scenarios)."""

    def __init__(self, only: Callable[[Scenario], bool] | None = None):
        self._only = only
        self._items: dict[str, Scenario] | None = None

    def _all(self) -> dict[str, Scenario]:
        if self._items is None:
            items = {s.name: s for name in bundled_names() for s in profile_scenarios(get_profile(name))}
            self._items = {k: v for k, v in items.items() if self._only is None or self._only(v)}
        return self._items

    def __getitem__(self, name: str) -> Scenario:
        return self._all()[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._all())

    def __len__(self) -> int:
        return len(self._all())


#: The named scenarios of every bundled robot (each profile's ``[scenarios]``, ``[settings]`` and
#: ``[mismatches]`` tables, :mod:`amlip_qp.sim.scenarios.scenario_tables`), by name ``ROBOT-KEY``.
SCENARIOS: Mapping[str, Scenario] = _Scenarios()

#: The named scenarios with a terrain (slopes, stairs, rough ground, waves).
TERRAIN_SCENARIOS: Mapping[str, Scenario] = _Scenarios(lambda s: s.setting.terrain != "flat")


def ideal_scenarios() -> list[str]:
    """The names of the scenarios on each robot's own model with ideal sensors and the true base state."""
    return [name for name, s in SCENARIOS.items() if s.setting == PlantSetting()]


def get_scenario(name: str) -> Scenario:
    """The named scenario; :class:`InputError` listing the names otherwise."""
    try:
        return SCENARIOS[name]
    except KeyError:
        raise InputError(f"unknown scenario {name!r}; known: {', '.join(SCENARIOS)}") from None
