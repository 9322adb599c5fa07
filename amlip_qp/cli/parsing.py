"""The parsing machinery of ``amlip-qp``: its parser class, lazy handlers, and the options' value types.

The value types are the library's value checks (:mod:`amlip_qp.option_values`,
shared with the walk options of a sweep cell); each refuses a bad value with a
one-line message (argparse then exits 2 through :class:`Parser`).
"""

from __future__ import annotations

import argparse
import importlib
import re
import sys
from collections.abc import Callable
from typing import Any, NoReturn

import amlip_qp.option_values as V
from amlip_qp.exceptions import InputError
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


def value_type(check: V.Check) -> Callable[[str], Any]:
    """The argparse type of a value check of :mod:`amlip_qp.option_values`: its one-line error made argparse's."""

    def parse(text: str) -> Any:
        try:
            return check(text)
        except InputError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = getattr(check, "__name__", "value")
    return parse


#: ``T:FX,FY,FZ:DUR`` (s : N,N,N : s) -> ``(t_s, (fx, fy, fz), duration_s)``.
parse_push_spec = value_type(V.push_spec)
#: A finite number.
finite_float = value_type(V.finite_float)
#: A finite number > 0.
positive_float = value_type(V.positive_float)
#: A finite number >= 0.
non_negative_float = value_type(V.non_negative_float)
positive_int = value_type(V.int_at_least(1, "positive integer"))
non_negative_int = value_type(V.int_at_least(0, "non-negative integer"))


def float_in(low: float, high: float, unit: str, *, low_open: bool = True) -> Callable[[str], Any]:
    """Argparse type: :func:`amlip_qp.option_values.float_in`."""
    return value_type(V.float_in(low, high, unit, low_open=low_open))


def int_in(low: int, high: int, what: str = "whole number") -> Callable[[str], Any]:
    """Argparse type: :func:`amlip_qp.option_values.int_in`."""
    return value_type(V.int_in(low, high, what))


def name_list(allowed: tuple[str, ...]) -> Callable[[str], Any]:
    """Argparse type: :func:`amlip_qp.option_values.name_list`."""
    return value_type(V.name_list(allowed))


def int_at_least(minimum: int, what: str) -> Callable[[str], Any]:
    """Argparse type: :func:`amlip_qp.option_values.int_at_least`."""
    return value_type(V.int_at_least(minimum, what))
