"""Robot profiles: one file per robot, everything about it that is not in its MJCF file.

A robot is data: a TOML profile file (``docs/NEW_ROBOT.md`` documents every
key) that names its MJCF model and the edits made to it at load, the roles of
its joints, its feet, its gait, the bounds and shaping of its commands, the
tuned configuration of each tracker and the ``compare`` ranges. The bundled
robots' files are among the package's models (``amlip_qp/models/NAME.toml``);
a user's is given by path (``--robot PATH``, ``load_robot(PATH)``).

- :mod:`~amlip_qp.profiles.profile`: :class:`RobotProfile` and its parts;
- :mod:`~amlip_qp.profiles.commands`: :class:`CommandBounds`, :class:`VerifiedEnvelope`, :class:`CommandShaping`;
- :mod:`~amlip_qp.profiles.reader`: the file, checked key by key;
- :mod:`~amlip_qp.profiles.registry`: the bundled profiles and :func:`get_profile`.

This package imports nothing but :mod:`amlip_qp.exceptions` and
:mod:`amlip_qp.paths`, so every layer may use it (``docs/ARCHITECTURE.md``).
Nothing is read at import time: ``PROFILES`` reads each bundled file on first use.
"""

from __future__ import annotations

from typing import Any

from amlip_qp.profiles.commands import NO_SHAPING, CommandBounds, CommandShaping, VerifiedEnvelope
from amlip_qp.profiles.profile import (
    FORCE_POINT_COUNTS,
    FORCE_SITE_SUFFIXES,
    JOINT_ROLES,
    CompareRanges,
    FootSpec,
    GaitSettings,
    ImuMount,
    ModelSpec,
    RobotProfile,
    StandPose,
    sole_line_points,
    sole_rectangle_corners,
)
from amlip_qp.profiles.reader import read_profile
from amlip_qp.profiles.registry import (
    DEFAULT_EKF_SCENARIO,
    DEFAULT_ROBOT,
    DEFAULT_SCENARIO,
    BundledProfiles,
    bundled_names,
    compared_robots,
    get_profile,
    load_profile,
    looks_like_profile_path,
)

#: The bundled robots' profiles by name (each file read on first use).
PROFILES = BundledProfiles()

__all__ = [
    "FORCE_POINT_COUNTS",
    "FORCE_SITE_SUFFIXES",
    "sole_line_points",
    "sole_rectangle_corners",
    "DEFAULT_EKF_SCENARIO",
    "DEFAULT_ROBOT",
    "DEFAULT_SCENARIO",
    "JOINT_ROLES",
    "NO_SHAPING",
    "PROFILES",
    "ROBOT_NAMES",
    "BundledProfiles",
    "CommandBounds",
    "CommandShaping",
    "CompareRanges",
    "FootSpec",
    "GaitSettings",
    "ImuMount",
    "ModelSpec",
    "RobotProfile",
    "StandPose",
    "VerifiedEnvelope",
    "bundled_names",
    "compared_robots",
    "get_profile",
    "load_profile",
    "looks_like_profile_path",
    "read_profile",
]


def __getattr__(name: str) -> Any:
    """``ROBOT_NAMES``: the bundled robots' names, listed when first asked for."""
    if name == "ROBOT_NAMES":
        return bundled_names()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
