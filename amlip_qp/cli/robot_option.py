"""``--robot NAME|PATH`` and ``--robots R1,R2``: a bundled robot or a robot profile file, checked at parse time.

A bundled robot's name (``amlip_qp/models/NAME.toml``) or the path of a robot
profile file (``.toml``); the profile is read and checked key by key before
anything runs, so a bad one exits 2 with one line naming the key.
"""

from __future__ import annotations

import argparse

from amlip_qp.exceptions import InputError, UnknownRobotError
from amlip_qp.profiles import bundled_names, get_profile, looks_like_profile_path


def robot_name_or_path(text: str) -> str:
    """Argparse type: a bundled robot's name, or a robot profile's path (returned resolved)."""
    name = text.strip()
    try:
        profile = get_profile(name if looks_like_profile_path(name) else name.lower())
    except UnknownRobotError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    except InputError as exc:  # a profile file that is missing or invalid
        raise argparse.ArgumentTypeError(str(exc)) from None
    return str(profile.source) if looks_like_profile_path(name) else profile.name


def robot_list(text: str) -> list[str]:
    """Argparse type: a comma-separated list of :func:`robot_name_or_path` (order kept, duplicates dropped)."""
    names = list(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))
    if not names:
        raise argparse.ArgumentTypeError(
            f"expected a comma-separated list of robots ({', '.join(bundled_names())}, or profile paths), got {text!r}"
        )
    return [robot_name_or_path(n) for n in names]
