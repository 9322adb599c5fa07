"""The parsing machinery of ``amlip-qp``: its parser class, lazy handlers, and the options' value types.

Every value type refuses a bad value with a one-line message (argparse then
exits 2 through :class:`Parser`).
"""

from __future__ import annotations

import argparse
import importlib
import math
import re
import sys
from collections.abc import Callable
from typing import NoReturn

from amlip_qp.sim.reports.gl import prefer_offscreen_gl

#: An argument argparse should read as a value, not an option: anything that starts like a
#: negative number. Argparse's own pattern knows only ``-1`` and ``-1.5``; this one also takes
#: exponents (``-1e-1``, ``-5E0``), ``-inf``/``-nan`` and a push at a negative time
#: (``-1:0,0,0:1``), which the value checks then refuse with a clear message. No option of
#: ``amlip-qp`` starts with ``-`` and a digit.
NEGATIVE_NUMBER = re.compile(r"^-(?:\.?\d|inf|nan)", re.IGNORECASE)


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line and exit with status 2, and that reads ``-1e-1`` as a number."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        # argparse consults this (private) matcher to tell negative numbers from options.
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message: str) -> NoReturn:
        sys.stderr.write(f"{self.prog}: error: {message} (see '{self.prog} --help')\n")
        raise SystemExit(2)


def handler(path: str, offscreen_gl: bool = False) -> Callable[[argparse.Namespace], int]:
    """Return a lazily-imported handler ``"module:function"``.

    ``offscreen_gl``: before importing the handler (and with it MuJoCo), choose
    EGL rendering on a machine without a display
    (:func:`~amlip_qp.sim.reports.gl.prefer_offscreen_gl`), for a handler that
    may render off-screen.
    """

    def run(args: argparse.Namespace) -> int:
        if offscreen_gl:
            prefer_offscreen_gl()
        module_name, func_name = path.split(":")
        return getattr(importlib.import_module(module_name), func_name)(args)

    return run


def parse_push_spec(text: str) -> tuple[float, tuple[float, float, float], float]:
    """Parse ``T:FX,FY,FZ:DUR`` (s : N,N,N : s) into ``(t_s, (fx, fy, fz), duration_s)``."""
    usage = f"expected T:FX,FY,FZ:DUR (s:N,N,N:s), e.g. 6:100,0,0:0.2, got {text!r}"
    parts = text.split(":")
    if len(parts) != 3:
        raise argparse.ArgumentTypeError(usage)
    try:
        t = float(parts[0])
        force = tuple(float(x) for x in parts[1].split(","))
        dur = float(parts[2])
    except ValueError:
        raise argparse.ArgumentTypeError(usage) from None
    if len(force) != 3 or not all(math.isfinite(x) for x in (t, dur, *force)):
        raise argparse.ArgumentTypeError(usage)
    if t < 0 or dur <= 0:
        raise argparse.ArgumentTypeError(f"a push needs T >= 0 s and DUR > 0 s, got {text!r}")
    return t, force, dur


def finite_float(text: str) -> float:
    """Argparse type: a finite number."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def positive_float(text: str) -> float:
    """Argparse type: a finite number > 0."""
    value = finite_float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def non_negative_float(text: str) -> float:
    """Argparse type: a finite number >= 0."""
    value = finite_float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value


def float_in(low: float, high: float, unit: str, *, low_open: bool = True):
    """Argparse type: a finite number in ``(low, high]`` (``[low, high]`` with ``low_open=False``), in ``unit``.

    The error names the interval and the unit, e.g. ``expected a number in (0, 240] frames/s, got '1e9'``.
    """
    interval = f"{'(' if low_open else '['}{low:g}, {high:g}] {unit}".rstrip()

    def parse(text: str) -> float:
        value = finite_float(text)
        if not ((value > low if low_open else value >= low) and value <= high):
            raise argparse.ArgumentTypeError(f"expected a number in {interval}, got {text!r}")
        return value

    return parse


def int_in(low: int, high: int, what: str = "whole number"):
    """Argparse type: an integer in ``[low, high]`` (``what`` names it in the error)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a {what} in [{low}, {high}], got {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected a {what} in [{low}, {high}], got {value}")
        return value

    return parse


def name_list(allowed: tuple[str, ...]):
    """Argparse type: a comma-separated list of names from ``allowed`` (order kept, duplicates dropped)."""

    def parse(text: str) -> list[str]:
        names = list(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))
        bad = [n for n in names if n not in allowed]
        if not names or bad:
            raise argparse.ArgumentTypeError(f"expected a comma-separated list from {', '.join(allowed)}, got {text!r}")
        return names

    return parse


def int_at_least(minimum: int, what: str):
    """Argparse type: an integer >= ``minimum`` (``what`` names it in the error)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a {what}, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"expected a {what}, got {value}")
        return value

    return parse


positive_int = int_at_least(1, "positive integer")
non_negative_int = int_at_least(0, "non-negative integer")
