"""The bundled robot profiles, and profiles given by path.

A bundled robot is a profile file ``NAME.toml`` among the package's models
(:data:`amlip_qp.paths.MODELS_DIR`); a user's robot is a profile file
anywhere, given by its path. Each file is read once per process.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping
from pathlib import Path

from amlip_qp.exceptions import UnknownRobotError
from amlip_qp.paths import MODELS_DIR
from amlip_qp.profiles.profile import RobotProfile
from amlip_qp.profiles.reader import read_profile

_READ: dict[Path, RobotProfile] = {}

#: The robot a command walks when none is named: the paper's.
DEFAULT_ROBOT = "cassie"
#: The default robot's nominal walk (its ``[compare] nominal_scenario``): the default scenario of
#: ``bench qp`` and ``bench harness``.
DEFAULT_SCENARIO = "cassie-1mps"
#: The nominal walk on the default robot's closed-chain plant, with its own sensors and the EKF: the
#: default scenario of ``bench ekf``.
DEFAULT_EKF_SCENARIO = "cassie-1mps-cc-ekf"


def bundled_names() -> tuple[str, ...]:
    """Names of the bundled robots, in alphabetical order."""
    return tuple(sorted(p.stem for p in MODELS_DIR.glob("*.toml")))


def looks_like_profile_path(text: str | os.PathLike) -> bool:
    """Whether ``text`` names a profile file rather than a bundled robot (a ``.toml`` name or a path)."""
    s = os.fspath(text)
    return (
        not isinstance(text, str)
        or s.lower().endswith(".toml")
        or os.sep in s
        or (os.altsep is not None and os.altsep in s)
    )


def load_profile(path: str | os.PathLike) -> RobotProfile:
    """The profile in the file ``path`` (read once per process; :func:`~amlip_qp.profiles.reader.read_profile`).

    Raises:
        ProfileError: The file is missing or invalid (the message names the key).
    """
    resolved = Path(path).expanduser().resolve()
    if resolved not in _READ:
        _READ[resolved] = read_profile(resolved)
    return _READ[resolved]


def get_profile(name_or_path: str | os.PathLike) -> RobotProfile:
    """The profile of the bundled robot ``name_or_path``, or of the profile file at that path.

    Raises:
        UnknownRobotError: Neither a bundled robot nor something that looks like a path.
        ProfileError: The profile file is missing or invalid.
    """
    if looks_like_profile_path(name_or_path):
        return load_profile(name_or_path)
    name = str(name_or_path)
    path = MODELS_DIR / f"{name}.toml"
    if name != Path(name).name or not path.is_file():
        raise UnknownRobotError(
            f"unknown robot {name!r}; known robots: {', '.join(bundled_names())} "
            "(or give the path of a robot profile file, NAME.toml)"
        )
    return load_profile(path)


def compared_robots() -> tuple[str, ...]:
    """The bundled robots ``amlip-qp compare`` runs by default: those whose profile has a ``[compare]`` table."""
    return tuple(name for name in bundled_names() if get_profile(name).compare is not None)


class BundledProfiles(Mapping[str, RobotProfile]):
    """The bundled profiles by name, read on first use (a read-only mapping)."""

    def __getitem__(self, name: str) -> RobotProfile:
        if name not in bundled_names():
            raise KeyError(name)
        return get_profile(name)

    def __iter__(self) -> Iterator[str]:
        return iter(bundled_names())

    def __len__(self) -> int:
        return len(bundled_names())
