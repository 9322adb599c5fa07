"""``--robot NAME|PATH`` and ``--robots R1,R2``: a bundled robot or a robot profile file, checked at parse time.

A bundled robot's name (``amlip_qp/models/NAME.toml``) or the path of a robot
profile file (``.toml``); the profile is read and checked key by key before
anything runs, so a bad one exits 2 with one line naming the key.
"""

from __future__ import annotations

import argparse

import amlip_qp.option_values as V
from amlip_qp.cli.parsing import value_type
from amlip_qp.profiles import bundled_names

#: Argparse type: a bundled robot's name, or a robot profile's path (returned resolved).
robot_name_or_path = value_type(V.robot_name_or_path)


def robot_list(text: str) -> list[str]:
    """Argparse type: a comma-separated list of :func:`robot_name_or_path` (order kept, duplicates dropped)."""
    names = list(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))
    if not names:
        raise argparse.ArgumentTypeError(
            f"expected a comma-separated list of robots ({', '.join(bundled_names())}, or profile paths), got {text!r}"
        )
    return [robot_name_or_path(n) for n in names]
