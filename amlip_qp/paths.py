"""Where the repository's data folders (``models/``, ``codegen/``) are."""

from __future__ import annotations

from pathlib import Path

#: The repository root (the folder holding ``pyproject.toml``).
REPO_ROOT = Path(__file__).resolve().parent.parent

#: MJCF robot models shared by MuJoCo and Pinocchio.
MODELS_DIR = REPO_ROOT / "models"

#: Committed CasADi-generated C sources and headers.
CODEGEN_DIR = REPO_ROOT / "codegen"
