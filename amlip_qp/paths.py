"""Where amlip_qp's package data is, and whether it runs from a source checkout.

The data ships inside the package (in a wheel as in a checkout) and is found
with :mod:`importlib.resources`:

- :data:`MODELS_DIR`: ``amlip_qp/models/``, the MJCF robot models;
- :data:`CODEGEN_DIR`: ``amlip_qp/codegen/generated/``, the committed
  CasADi-generated C sources and header.

MuJoCo and Pinocchio read the models by file path, so the package must be
installed as files on disk (any pip install is; a zip import is not).
"""

from __future__ import annotations

import os
from importlib.resources import files
from pathlib import Path

#: The project name in ``pyproject.toml`` that marks a source checkout of amlip_qp.
_PROJECT_LINE = 'name = "amlip_qp"'


def _package_dir() -> Path:
    root = files("amlip_qp")
    if not isinstance(root, Path):
        raise ImportError(
            f"amlip_qp is imported from {root}, not from files on disk; MuJoCo and Pinocchio read "
            "its robot models by path: install it with pip (not as a zip)"
        )
    return root


#: The folder of the imported ``amlip_qp`` package.
PACKAGE_DIR = _package_dir()

#: MJCF robot models shared by MuJoCo and Pinocchio (package data).
MODELS_DIR = PACKAGE_DIR / "models"

#: Committed CasADi-generated C source and header (package data).
CODEGEN_DIR = PACKAGE_DIR / "codegen" / "generated"


def checkout_root() -> Path | None:
    """The source tree this ``amlip_qp`` runs from, or ``None`` for an installed package.

    A source tree (a git checkout, an unpacked sdist; used through an editable
    install or ``PYTHONPATH``) holds the package folder next to the project's
    ``pyproject.toml``. A package installed by ``pip install .`` or from a
    wheel lives in ``site-packages``, which has no such file.
    """
    root = PACKAGE_DIR.parent
    try:
        text = (root / "pyproject.toml").read_text(encoding="utf-8")
    except OSError:
        return None
    return root if _PROJECT_LINE in text else None


#: Environment variable naming the cache folder (compiled generated C, edited robot models).
CACHE_ENV = "AMLIP_QP_CACHE_DIR"


def cache_root() -> Path:
    """The cache folder: ``$AMLIP_QP_CACHE_DIR``, else ``$XDG_CACHE_HOME/amlip_qp``, else ``~/.cache/amlip_qp``."""
    explicit = os.environ.get(CACHE_ENV)
    if explicit:
        return Path(explicit).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg else Path.home() / ".cache"
    return base / "amlip_qp"
