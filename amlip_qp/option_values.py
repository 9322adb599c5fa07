"""Checks of option values, given as text (a command line) or typed (a sweep spec, a library call).

Each check returns the value in its type or raises :class:`~amlip_qp.exceptions.InputError`
with one line saying what was expected and what was given. The command line's
value types (:mod:`amlip_qp.cli.parsing`) are these checks, their error made
argparse's; the walk options (:class:`amlip_qp.sim.scenarios.options.WalkOptions`)
check every value with them. A number given as text is read with Python's
``float``/``int``; a typed number is taken as it is (a ``bool`` is not a number).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from typing import Any

from amlip_qp.exceptions import InputError, UnknownRobotError
from amlip_qp.profiles import get_profile, looks_like_profile_path

#: A check: a value (text or typed) -> the value in its type; :class:`InputError` otherwise.
Check = Callable[[Any], Any]


def _is_real(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def number(value: Any) -> float:
    """A number (``nan`` and ``inf`` included: the option's own bounds refuse them)."""
    if _is_real(value):
        return float(value)
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            pass
    raise InputError(f"expected a number, got {value!r}")


def finite_float(value: Any) -> float:
    """A finite number."""
    x = number(value)
    if not math.isfinite(x):
        raise InputError(f"expected a finite number, got {value!r}")
    return x


def positive_float(value: Any) -> float:
    """A finite number > 0."""
    x = finite_float(value)
    if x <= 0:
        raise InputError(f"expected a positive number, got {value!r}")
    return x


def non_negative_float(value: Any) -> float:
    """A finite number >= 0."""
    x = finite_float(value)
    if x < 0:
        raise InputError(f"expected a number >= 0, got {value!r}")
    return x


def float_in(low: float, high: float, unit: str, *, low_open: bool = True) -> Check:
    """A finite number in ``(low, high]`` (``[low, high]`` with ``low_open=False``), in ``unit``.

    The error names the interval and the unit, e.g. ``expected a number in (0, 240] frames/s, got '1e9'``.
    """
    interval = f"{'(' if low_open else '['}{low:g}, {high:g}] {unit}".rstrip()

    def check(value: Any) -> float:
        x = finite_float(value)
        if not ((x > low if low_open else x >= low) and x <= high):
            raise InputError(f"expected a number in {interval}, got {value!r}")
        return x

    return check


def whole_number(value: Any, what: str = "whole number") -> int:
    """An integer (text in Python's ``int`` syntax, or a typed integer; ``what`` names it in the error)."""
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        return int(value)
    if isinstance(value, str):
        try:
            return int(value)
        except ValueError:
            pass
    raise InputError(f"expected a {what}, got {value!r}")


def int_in(low: int, high: int, what: str = "whole number") -> Check:
    """An integer in ``[low, high]`` (``what`` names it in the error)."""

    def check(value: Any) -> int:
        try:
            x = whole_number(value)
        except InputError:
            raise InputError(f"expected a {what} in [{low}, {high}], got {value!r}") from None
        if not low <= x <= high:
            raise InputError(f"expected a {what} in [{low}, {high}], got {x}")
        return x

    return check


def int_at_least(minimum: int, what: str) -> Check:
    """An integer >= ``minimum`` (``what`` names it in the error)."""

    def check(value: Any) -> int:
        x = whole_number(value, what)
        if x < minimum:
            raise InputError(f"expected a {what}, got {x}")
        return x

    return check


def one_of(allowed: tuple[str, ...]) -> Check:
    """One of the names ``allowed``."""

    def check(value: Any) -> str:
        if not isinstance(value, str) or value not in allowed:
            raise InputError(f"expected one of {', '.join(allowed)}, got {value!r}")
        return value

    return check


def name_list(allowed: tuple[str, ...]) -> Check:
    """A comma-separated list of names from ``allowed`` (order kept, duplicates dropped)."""

    def check(value: Any) -> list[str]:
        text = value if isinstance(value, str) else ""
        names = list(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))
        bad = [n for n in names if n not in allowed]
        if not names or bad:
            raise InputError(f"expected a comma-separated list from {', '.join(allowed)}, got {value!r}")
        return names

    return check


def flag(value: Any) -> bool:
    """``True`` or ``False`` (an on/off option)."""
    if not isinstance(value, bool):
        raise InputError(f"expected true or false, got {value!r}")
    return value


def text(value: Any) -> str:
    """A text value (a name, a path or a spec); a number is taken as its text, as on a command line."""
    if isinstance(value, str):
        return value
    if _is_real(value):
        return str(value)
    raise InputError(f"expected a text value, got {value!r}")


#: A push: ``(t_s, (fx_N, fy_N, fz_N), duration_s)``.
PushSpec = tuple[float, tuple[float, float, float], float]


def push_spec(value: Any) -> PushSpec:
    """``T:FX,FY,FZ:DUR`` (s : N,N,N : s), or the tuple ``(t_s, (fx, fy, fz), duration_s)`` it stands for."""
    usage = f"expected T:FX,FY,FZ:DUR (s:N,N,N:s), e.g. 6:100,0,0:0.2, got {value!r}"
    try:
        if isinstance(value, str):
            parts = value.split(":")
            if len(parts) != 3:
                raise InputError(usage)
            t, force, dur = float(parts[0]), tuple(float(x) for x in parts[1].split(",")), float(parts[2])
        elif isinstance(value, (tuple, list)) and len(value) == 3 and isinstance(value[1], (tuple, list)):
            if not all(_is_real(x) for x in (value[0], value[2], *value[1])):
                raise InputError(usage)
            t, force, dur = float(value[0]), tuple(float(x) for x in value[1]), float(value[2])
        else:
            raise InputError(usage)
    except ValueError:  # float() of a malformed field
        raise InputError(usage) from None
    if len(force) != 3 or not all(math.isfinite(x) for x in (t, dur, *force)):
        raise InputError(usage)
    if t < 0 or dur <= 0:
        raise InputError(f"a push needs T >= 0 s and DUR > 0 s, got {value!r}")
    return t, (force[0], force[1], force[2]), dur


def robot_name_or_path(value: Any) -> str:
    """A bundled robot's name, or a robot profile's path (returned resolved); the profile is read and checked."""
    if not isinstance(value, str):
        raise InputError(f"expected a robot name or a profile path, got {value!r}")
    name = value.strip()
    try:
        profile = get_profile(name if looks_like_profile_path(name) else name.lower())
    except UnknownRobotError as exc:
        raise InputError(str(exc)) from None
    return str(profile.source) if looks_like_profile_path(name) else profile.name
