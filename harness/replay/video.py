"""Render a replay to mp4 with MuJoCo's offscreen renderer.

Headless machines render through EGL (`MUJOCO_GL=egl`, read when mujoco is
first imported). Frames are encoded by the ffmpeg binary that the `imageio-ffmpeg` wheel
ships. A video the user asked for (`replay --video`) that cannot be made is an error
(`rendering_problem` is asked before anything is simulated or written); the bench's videos
are optional: where no GL context can be made they are skipped with a warning and
`render_video` returns False. The measurement never depends on them.
"""

from __future__ import annotations

import sys
from pathlib import Path

import mujoco
import numpy as np

from harness.errors import UserError
from harness.io import atomic_write
from harness.replay.simulate import ReplayTrace

CAMERA = "overview"
# What making a GL context raises where rendering does not work: MuJoCo's own error (no
# display for GLFW), PyOpenGL's (a platform library missing or half-loaded).
RENDER_ERRORS = (mujoco.FatalError, RuntimeError, ImportError, AttributeError, OSError)
FPS = 30  # frames per second of simulated time


def _make_renderer(model: mujoco.MjModel) -> mujoco.Renderer:
    width = min(640, model.vis.global_.offwidth)
    height = min(480, model.vis.global_.offheight)
    return mujoco.Renderer(model, height=height - height % 2, width=width - width % 2)


def rendering_problem(model: mujoco.MjModel) -> str | None:
    """Why a video of model cannot be rendered here, or None if it can."""
    try:
        import imageio_ffmpeg  # noqa: F401
    except ImportError:
        return "imageio-ffmpeg is not installed"
    try:
        _make_renderer(model).close()
    except RENDER_ERRORS as exc:
        return f"no OpenGL rendering available ({type(exc).__name__}: {' '.join(str(exc).split())})"
    return None


def _renderer(model: mujoco.MjModel) -> mujoco.Renderer | None:
    try:
        return _make_renderer(model)
    except RENDER_ERRORS as exc:  # no display, no EGL/OSMesa: the video is skipped, said so
        warn(f"video skipped, no OpenGL rendering available ({type(exc).__name__}: {exc})")
        return None


def warn(message: str) -> None:
    print(f"torquebench: warning: {message}", file=sys.stderr)


def frames(model: mujoco.MjModel, trace: ReplayTrace, renderer: mujoco.Renderer):
    """Yield RGB frames (h, w, 3) uint8 at FPS from the recorded trace."""
    data = mujoco.MjData(model)
    camera = CAMERA if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, CAMERA) >= 0 else -1
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "obstacle")
    mocap = int(model.body_mocapid[body]) if body >= 0 else -1
    times = np.arange(trace.t[0], trace.t[-1] + 1e-9, 1.0 / FPS)
    for k in np.searchsorted(trace.t, times).clip(0, len(trace.t) - 1):
        data.qpos[:] = trace.q[k]
        if mocap >= 0:
            data.mocap_pos[mocap] = trace.obstacle[k]
        mujoco.mj_forward(model, data)
        renderer.update_scene(data, camera=camera)
        yield renderer.render()


def render_video(model: mujoco.MjModel, trace: ReplayTrace, path: str | Path,
                 required: bool = False) -> bool:
    """Write the replay as an mp4 at path; False (with a warning) if it cannot render, or,
    required, a UserError naming why (nothing written)."""
    if required:
        problem = rendering_problem(model)
        if problem:
            raise UserError(f"cannot render the video {path}: {problem}")
    try:
        import imageio_ffmpeg
    except ImportError:
        warn("video skipped, imageio-ffmpeg is not installed")
        return False
    renderer = _renderer(model)
    if renderer is None:
        return False

    def write(tmp: str) -> None:
        writer = imageio_ffmpeg.write_frames(
            tmp, (renderer.width, renderer.height), fps=FPS, quality=7,
            output_params=["-f", "mp4"],
        )
        writer.send(None)  # start the ffmpeg process
        for frame in frames(model, trace, renderer):
            writer.send(np.ascontiguousarray(frame))
        writer.close()

    try:
        atomic_write(path, write, suffix=".mp4")
    except (*RENDER_ERRORS, BrokenPipeError) as exc:  # the encoder or the GL context failed
        if required:
            raise UserError(f"cannot render the video {path}: {type(exc).__name__}: "
                            f"{' '.join(str(exc).split())}") from None
        warn(f"video {path} skipped: {type(exc).__name__}: {exc}")
        return False
    finally:
        renderer.close()
    return True
