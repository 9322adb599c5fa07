"""Which MJCF file a plant name or path means: ``--plant``'s names and paths.

A robot's profile names its plants (its ``[plants]`` table, and its own model
under the robot's name); a robot without a profile has one,
its own model file. Anything else that looks like a path (a ``.xml`` name, a
path separator, a :class:`os.PathLike`) is read as a user's MJCF file.
"""

from __future__ import annotations

import os
from pathlib import Path

from amlip_qp.exceptions import InputError, ModelFileError
from amlip_qp.robots.robot import Robot


def plant_files(robot: Robot) -> dict[str, Path]:
    """The named plants of ``robot``: its profile's ``plants``, or its own file for a robot without a profile.

    The robot's own plant is the file its controller model was loaded from (the profile's model
    with its edits, :func:`amlip_qp.robots.model_edits.prepared_model_path`).
    """
    if robot.profile is None:
        return {robot.name: Path(robot.path)}
    plants = dict(robot.profile.plants)
    plants[robot.profile.name] = Path(robot.path)
    return plants


def resolve_plant_source(source: str | os.PathLike, robot: Robot) -> tuple[str, Path]:
    """``(name, path)`` of a plant name of ``robot`` or an MJCF path (the path resolved).

    A name of :func:`plant_files` is named so; a path is named by the path as given (``~`` expanded).

    Raises:
        InputError: Neither a plant name of the robot nor something that looks like a path.
        ModelFileError: The file does not exist.
    """
    named = plant_files(robot)
    text = os.fspath(source)
    if isinstance(source, str) and text in named:
        name, path = text, named[text]
    else:
        looks_like_path = not isinstance(source, str) or text.lower().endswith(".xml") or os.sep in text
        if not looks_like_path:
            raise InputError(
                f"unknown plant {text!r} for {robot.name}: known plants are {', '.join(named)}; "
                "a path to an MJCF .xml file also works"
            )
        path = Path(text).expanduser()
        name = str(path)
    if not path.is_file():
        raise ModelFileError(f"plant model file not found: {path}")
    return name, path.resolve()
