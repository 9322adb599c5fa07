"""Bisection of one parameter per cell: the largest value survived (e.g. a push impulse, N s)."""

from __future__ import annotations

import math
from collections.abc import Callable

from amlip_qp.exceptions import InputError


def largest_surviving(
    survives: Callable[[float], bool], low: float, high: float, iterations: int
) -> tuple[float, bool, list[tuple[float, bool]]]:
    """The largest value in ``[low, high]`` that ``survives``, by bisection.

    ``high`` is tried first: if it survives the answer is ``high`` and capped
    (at least that much). Otherwise ``iterations`` halvings keep ``lo``
    surviving and ``hi`` failing, and the answer is ``lo`` (the true edge lies
    in ``[lo, lo + (high - low) / 2**iterations)`` for a monotone outcome).
    ``survives(low)`` is assumed true and not run (for a push impulse, ``low = 0``
    is the unpushed walk).

    Returns:
        ``(value, capped, trials)`` with ``trials`` the ``(value, survived)`` pairs in the order run.

    Raises:
        InputError: ``low >= high``, a non-finite bound, or ``iterations < 0``.
    """
    if not (math.isfinite(low) and math.isfinite(high) and low < high) or iterations < 0:
        raise InputError(
            f"a bisection needs finite low < high and iterations >= 0, got {low!r}, {high!r}, {iterations!r}"
        )
    trials: list[tuple[float, bool]] = []

    def attempt(value: float) -> bool:
        ok = bool(survives(value))
        trials.append((value, ok))
        return ok

    if attempt(float(high)):
        return float(high), True, trials
    lo, hi = float(low), float(high)
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        if attempt(mid):
            lo = mid
        else:
            hi = mid
    return lo, False, trials
