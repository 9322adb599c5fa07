"""Offscreen video of a run: MuJoCo's renderer, the model's ``track`` camera, imageio.

A :class:`VideoRecorder` is a per-tick callback for
:meth:`amlip_qp.sim.loop.harness.Simulation.run` (``on_tick``): it renders a frame
whenever the simulated time passes the next frame time (``fps`` frames per
simulated second) and streams it to an MP4 (imageio-ffmpeg) or GIF file.

Headless machines need an offscreen OpenGL backend. :func:`amlip_qp.sim.reports.gl.prefer_offscreen_gl`
sets ``MUJOCO_GL=egl`` when no display is available; it must run before
``mujoco`` is imported. If ``mujoco`` was imported without a usable backend,
the recorder creates an EGL (then OSMesa) context itself.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np

from amlip_qp.exceptions import AmlipError, InputError

#: File suffixes the recorder writes.
VIDEO_SUFFIXES = (".mp4", ".gif")
#: Highest frame rate, frames per simulated second (the video plays in real time): 240 Hz, the refresh
#: rate of the fastest common displays. More frames are never shown but are each rendered and encoded:
#: libx264 warns past its level limits ("MB rate > level limit"), and above the control rate a frame
#: is rendered every 0.5 ms tick: ``walk --duration 0.5 --video v.mp4`` took 97 s (1,000 frames) at
#: ``--video-fps 1e9``, 21 s at 240 and 4.6 s at 30 (EGL rendering on this project's 2-core machine).
MAX_VIDEO_FPS = 240.0
#: Highest frame rate of a ``.gif``, frames per s: GIF frame delays are whole hundredths of a second.
MAX_GIF_FPS = 100.0


class RenderError(AmlipError):
    """Offscreen rendering or video encoding failed (no OpenGL backend, encoder missing...)."""


def check_video_path(path: str | os.PathLike) -> Path:
    """``path`` as a Path if its suffix is ``.mp4`` or ``.gif``; :class:`InputError` otherwise."""
    p = Path(path)
    if p.suffix.lower() not in VIDEO_SUFFIXES:
        raise InputError(f"video file must end in .mp4 or .gif, got {str(path)!r}")
    return p


def check_video_fps(fps: float, path: str | os.PathLike | None = None) -> float:
    """``fps`` as a float if ``0 < fps <= MAX_VIDEO_FPS`` (``<= MAX_GIF_FPS`` for a ``.gif`` ``path``).

    Raises:
        InputError: One line naming ``--video-fps`` and the bound.
    """
    gif = path is not None and Path(path).suffix.lower() == ".gif"
    high = MAX_GIF_FPS if gif else MAX_VIDEO_FPS
    value = float(fps) if isinstance(fps, (int, float)) and not isinstance(fps, bool) else float("nan")
    if not (np.isfinite(value) and 0.0 < value <= high):
        why = "a .gif's frame delays are whole hundredths of a second" if gif else "the fastest displays' refresh rate"
        raise InputError(f"--video-fps must be in (0, {high:g}] frames/s ({why}), got {fps!r}")
    return value


def _default_backend_usable() -> bool:
    """True if MuJoCo's import-time backend can render here (EGL/OSMesa, or a display for GLFW/GLX)."""
    from mujoco.rendering.classic import gl_context

    backend = getattr(gl_context, "_MUJOCO_GL", "")
    if backend in ("egl", "osmesa"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _make_renderer(model, height: int, width: int):
    """A ``mujoco.Renderer`` and the GL context we created for it (or ``None``).

    MuJoCo picks its OpenGL backend when it is imported. Without a display and
    without ``MUJOCO_GL=egl|osmesa`` at that time, its default (GLFW) cannot
    work, and a failed attempt leaves MuJoCo unable to render; so in that case
    an EGL (then OSMesa) context is made current first and the renderer uses it.
    """
    import mujoco

    errors = []
    if _default_backend_usable():
        try:
            return mujoco.Renderer(model, height, width), None
        except Exception as exc:  # mujoco raises FatalError/RuntimeError/ImportError depending on the backend
            raise RenderError(f"offscreen rendering failed: {exc}") from exc
    for backend in ("egl", "osmesa"):
        try:
            module = __import__(f"mujoco.{backend}", fromlist=["GLContext"])
            ctx = module.GLContext(width, height)
            ctx.make_current()
        except Exception as exc:  # try the next backend
            errors.append(f"{backend}: {exc}")
            continue
        try:
            with warnings.catch_warnings():  # GLFW complains about the missing display; our context is current
                warnings.simplefilter("ignore")
                return mujoco.Renderer(model, height, width), ctx
        except Exception as exc:
            ctx.free()
            errors.append(f"{backend}: {exc}")
    raise RenderError(
        "no offscreen OpenGL backend works (set MUJOCO_GL=egl or osmesa before starting); " + "; ".join(errors)
    )


class VideoRecorder:
    """Render the ``track`` camera at ``fps`` frames per simulated second into ``path``.

    Use as ``Simulation.run(..., on_tick=recorder)`` and call :meth:`close`
    (or use it as a context manager) when the run ends.

    Args:
        model: The ``mujoco.MjModel``.
        path: Output file, ``.mp4`` or ``.gif``.
        fps: Frames per simulated second (also the playback rate: real time), in
            ``(0, MAX_VIDEO_FPS]`` (``(0, MAX_GIF_FPS]`` for a ``.gif``, :func:`check_video_fps`).
        width, height: Frame size, pixels.
        camera: Camera name (the robots' models define ``track``).
    """

    def __init__(
        self,
        model,
        path: str | os.PathLike,
        fps: float = 30.0,
        width: int = 640,
        height: int = 480,
        camera: str = "track",
    ):
        import mujoco

        self.path = check_video_path(path)
        fps = check_video_fps(fps, self.path)
        if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera) < 0:
            raise InputError(f"the model has no camera named {camera!r}")
        width = min(int(width), int(model.vis.global_.offwidth))
        height = min(int(height), int(model.vis.global_.offheight))
        self.fps = float(fps)
        self.camera = camera
        self.frames = 0
        self._next_t = 0.0
        self._renderer, self._ctx = _make_renderer(model, height, width)
        import imageio

        self.path.parent.mkdir(parents=True, exist_ok=True)
        try:
            if self.path.suffix.lower() == ".gif":
                self._writer = imageio.get_writer(self.path, mode="I", duration=1000.0 / self.fps, loop=0)
            else:
                self._writer = imageio.get_writer(
                    self.path, fps=self.fps, codec="libx264", macro_block_size=8, quality=7
                )
        except Exception as exc:
            self._close_renderer()
            raise RenderError(f"cannot open a video writer for {self.path}: {exc}") from exc

    def __call__(self, t_s: float, data) -> None:
        """Per-tick hook: render a frame if simulated time ``t_s`` (s) reached the next frame time."""
        if t_s + 1e-12 < self._next_t:
            return
        self.capture(data)
        self._next_t += 1.0 / self.fps
        if self._next_t <= t_s:  # never fall behind by more than one frame
            self._next_t = t_s + 1.0 / self.fps

    def capture(self, data) -> None:
        """Render ``data`` from the camera and append the frame."""
        self._renderer.update_scene(data, camera=self.camera)
        self._writer.append_data(self._renderer.render())
        self.frames += 1

    def _close_renderer(self) -> None:
        with warnings.catch_warnings():  # GLFW's "not initialized" when our own context was used
            warnings.simplefilter("ignore")
            if self._renderer is not None:
                self._renderer.close()
                self._renderer = None
            if self._ctx is not None:
                self._ctx.free()
                self._ctx = None

    def close(self) -> None:
        """Finish the file and release the OpenGL context."""
        if getattr(self, "_writer", None) is not None:
            self._writer.close()
            del self._writer  # closed: the getattr above sees no writer on a second close
        self._close_renderer()

    def __enter__(self) -> VideoRecorder:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
