"""Which OpenGL MuJoCo renders with: EGL (off-screen) on a machine without a display.

MuJoCo reads ``MUJOCO_GL`` once, when ``mujoco`` is first imported, so
:func:`prefer_offscreen_gl` must run before that: the ``walk`` command calls
it before its handler is imported, a script first thing. A leaf module (the
standard library only), so the command line may import it.
"""

from __future__ import annotations

import os


def prefer_offscreen_gl() -> None:
    """Choose EGL for MuJoCo when ``MUJOCO_GL`` is unset and there is no display (call before importing mujoco)."""
    if "MUJOCO_GL" not in os.environ and not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        os.environ["MUJOCO_GL"] = "egl"
