"""``VideoRecorder``: renders episodes of the juggling env into a video file, in real time.

Frames come from MuJoCo's offscreen renderer (headless through EGL, or OSMesa with
``MUJOCO_GL=osmesa``) and are encoded by PyAV as they are rendered, so memory stays bounded
however long the episode. The file's suffix picks the format: ``.mp4`` (H.264, for players and
sharing), ``.webp`` (an animated image that loops, for a README) or ``.gif``.
"""

from __future__ import annotations

import math
import os
from contextlib import contextmanager
from fractions import Fraction
from pathlib import Path

import av
import gymnasium as gym
import mujoco
import numpy as np

from jugglerl.runs.files import RunFileError, failure

#: suffix -> (codec, pixel format); H.264 needs even frame sizes (checked in ``VideoRecorder``).
FORMATS = {
    ".mp4": ("libx264", "yuv420p"),
    ".webp": ("libwebp_anim", "yuv420p"),
    ".gif": ("gif", "pal8"),
}


class VideoError(ValueError):
    """A video that cannot be made here: no OpenGL for the renderer, a bad size or file name."""


class VideoOptionError(VideoError):
    """A bad option, its message starting with the option's ``render`` key: ``fps=0 must ...``."""


class VideoRecorder(gym.Wrapper):
    """Renders every step of the wrapped ``JuggleEnv`` that falls on a grid of ``1 / fps``
    simulated seconds into ``path``, from the scene's camera ``camera``.

    The recorder never changes the episode: it renders a copy of the state (the env's own
    ``data`` keeps the poses of the previous physics step until its next one).
    """

    def __init__(
        self,
        env: gym.Env,
        path: str | Path,
        fps: float = 30.0,
        width: int = 640,
        height: int = 480,
        camera: str = "side",
    ):
        super().__init__(env)
        self.path = Path(path)
        if self.path.suffix not in FORMATS:
            raise VideoOptionError(
                f"file={self.path.name}: the suffix must be one of {', '.join(FORMATS)}"
            )
        juggle = env.unwrapped
        step_rate = 1.0 / juggle.dt
        if not 0 < fps <= step_rate:
            raise VideoOptionError(f"fps={fps} must be in (0, {step_rate:g}] (the env's steps)")
        if width <= 0 or height <= 0 or width % 2 or height % 2:
            raise VideoOptionError(
                f"width={width}, height={height}: the size must be even and positive"
            )
        self._model = juggle.model
        self._data = juggle.data
        try:
            self._camera = self._model.camera(camera).id
        except KeyError:
            cameras = [self._model.camera(i).name for i in range(self._model.ncam)]
            raise VideoOptionError(
                f"camera={camera} is not in the scene; cameras: {', '.join(cameras)}"
            ) from None
        self._model.vis.global_.offwidth = max(self._model.vis.global_.offwidth, width)
        self._model.vis.global_.offheight = max(self._model.vis.global_.offheight, height)
        self._scratch = mujoco.MjData(self._model)
        try:
            self._renderer = mujoco.Renderer(self._model, height, width)
        except Exception as error:  # MuJoCo raises whatever its GL backend raised
            cause = str(error).splitlines()[0] if str(error) else type(error).__name__
            raise VideoError(
                f"video needs OpenGL for MuJoCo's offscreen renderer (MUJOCO_GL={mujoco_gl()}):"
                f" {cause}; on Debian/Ubuntu: apt-get install libegl1 libgl1-mesa-dri"
            ) from None
        self.frame_period = 1.0 / fps
        self.frames = 0
        self._fps = Fraction(fps).limit_denominator(1000)
        self._container = None
        self._stream = None
        self._failed: RunFileError | None = None  # the write that failed; no frame after it
        self._next_frame = math.inf

    def reset(self, **kwargs):
        observation, info = self.env.reset(**kwargs)
        self._next_frame = 0.0
        self._frame(info["time"])
        return observation, info

    def step(self, action):
        observation, reward, terminated, truncated, info = self.env.step(action)
        self._frame(info["time"])
        return observation, reward, terminated, truncated, info

    def close(self):
        """Flush the encoder and close the file (a video with its frames so far), then the env.
        A file that cannot be written raises ``RunFileError`` naming it; the encoder is then
        left alone (libav may crash when a failed file is flushed or closed again)."""
        container, self._container = self._container, None
        try:
            if container is not None:
                with self._writing():
                    container.mux(self._stream.encode())
                    container.close()
            self._renderer.close()
        finally:
            super().close()

    @contextmanager
    def _writing(self):
        """A failed write of the video as ``RunFileError``; the encoder is not used again."""
        try:
            yield
        except OSError as error:
            self._container = None
            self._failed = failure(self.path, "write the video", error)
            raise self._failed from None

    def _frame(self, time: float) -> None:
        if time < self._next_frame - 1e-9:
            return
        self._next_frame = (math.floor(time / self.frame_period + 1e-9) + 1) * self.frame_period
        self._encode(self._render())

    def _render(self) -> np.ndarray:
        self._scratch.qpos[:] = self._data.qpos
        mujoco.mj_kinematics(self._model, self._scratch)
        mujoco.mj_camlight(self._model, self._scratch)
        self._renderer.update_scene(self._scratch, camera=self._camera)
        return self._renderer.render()

    def _encode(self, pixels: np.ndarray) -> None:
        if self._failed is not None:
            raise self._failed
        if self._container is None:
            self._open(pixels.shape[1], pixels.shape[0])
        frame = av.VideoFrame.from_ndarray(pixels, format="rgb24")
        frame.pts = self.frames
        with self._writing():
            self._container.mux(self._stream.encode(frame))
        self.frames += 1

    def _open(self, width: int, height: int) -> None:
        codec, pixel_format = FORMATS[self.path.suffix]
        self.path.parent.mkdir(parents=True, exist_ok=True)
        options = {"loop": "0"} if self.path.suffix in (".webp", ".gif") else {}
        self._container = av.open(str(self.path), mode="w", options=options)
        self._stream = self._container.add_stream(codec, rate=self._fps)
        self._stream.width = width
        self._stream.height = height
        self._stream.pix_fmt = pixel_format
        self._stream.codec_context.time_base = 1 / self._fps


def render_options(render_cfg) -> dict:
    """``VideoRecorder``'s keyword arguments from a ``render`` config block (its ``file`` aside)."""
    return {key: render_cfg[key] for key in ("fps", "width", "height", "camera")}


def mujoco_gl() -> str:
    """The OpenGL backend MuJoCo was asked for (``MUJOCO_GL``; GLFW when unset)."""
    return os.environ.get("MUJOCO_GL", "glfw")
