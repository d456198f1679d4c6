"""``EpisodeTrack``: records episodes of one juggling env (of a ``JuggleEnv`` or of a batch) in
3D, with the ball-height plot; ``EpisodeRecorder``: a ``JuggleEnv`` wrapped to record with it;
``record_episode``: one recorded episode of a policy."""

from __future__ import annotations

import math

import gymnasium as gym
import mujoco
import numpy as np
import rerun as rr

from jugglerl.policies import Policy
from jugglerl.policies.episodes import EpisodeMetrics, run_episode
from jugglerl.recording.geometry import (
    body_paths,
    log_static_scene,
    moving_bodies,
    relative_poses,
)
from jugglerl.recording.names import PLOTS, SIM_TIME, WORLD, join
from jugglerl_envs.scene import CUP_SITE, ball_name

THRESHOLD_COLOUR = [40, 160, 255]
THROW_COLOUR = [255, 200, 0]
HEIGHT_COLOUR = [230, 60, 60]
#: Buffered samples are sent every this many 3D frames (60 s of simulated time at 50 Hz, well
#: under a second of wall time), so a live viewer follows the episode and memory stays bounded.
#: Each send costs ~0.5 ms an entity: sending more often shows in the episode's wall time.
FRAMES_PER_SEND = 3000


class EpisodeTrack:
    """Records episodes of one juggling env (its MuJoCo ``model`` and ``data``, the env of a
    ``JuggleEnv`` or of a ``JuggleBatch``) into a rerun stream, from its info after each step.

    Under an episode's ``root`` (``""`` for the top level):

    - ``world/...``: the static geometry once, then the moving bodies' transforms at
      ``scene_fps`` frames per simulated second (the ball at ``world/ball``), and the threshold as
      a square outline at its height;
    - ``plots/ball_height`` every env step (with several balls, ``plots/ball_1_height``, ... too,
      in each ball's colour), ``plots/threshold`` as a line, ``plots/throws`` a
      marker at the height of the ball thrown for each counted throw (the env's own count,
      ``info["throws_per_ball"]``).

    All on the ``sim_time`` timeline. Samples are buffered and sent in columns (a log call per
    sample would cost more than the physics). ``begin(root, info)`` after the env's reset,
    ``sample(info)`` after each step, ``end()`` when the episode ends (or is abandoned).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        threshold: float,
        balls: int,
        stream: rr.RecordingStream,
        scene_fps: float = 50.0,
    ):
        if scene_fps <= 0:
            raise ValueError(f"scene_fps must be > 0 frames per second, got {scene_fps}")
        self.stream = stream
        self.frame_period = 1.0 / scene_fps
        self._model = model
        self._data = data
        self._kinematics = mujoco.MjData(model)  # scratch: poses at the current state
        self._threshold = threshold
        self._balls = balls
        self._cup_site = model.site(CUP_SITE).id
        self._moving = moving_bodies(model)
        self._roots_with_scene: set[str] = set()
        self._recording = False

    @classmethod
    def of_batch_env(
        cls, batch, env: int, stream: rr.RecordingStream, scene_fps: float = 50.0
    ) -> EpisodeTrack:
        """The track of env ``env`` of a ``JuggleBatch``."""
        threshold = batch.settings.env(env)["threshold"]
        model, data = batch.models[env], batch.datas[env]
        return cls(model, data, threshold, batch.balls, stream, scene_fps)

    def begin(self, root: str, info: dict) -> None:
        """Start an episode under ``root`` from the env's state after its reset."""
        self.end()  # an episode abandoned by the caller keeps what was recorded
        self._world = join(root, WORLD)
        self._plots = join(root, PLOTS)
        self._paths = body_paths(self._model, self._world)
        if root not in self._roots_with_scene:
            self._log_static()
            self._roots_with_scene.add(root)
        self._start_buffers()
        self._recording = True
        self._next_frame = 0.0
        self._throws_per_ball = info["throws_per_ball"]
        self._sample(info)

    def sample(self, info: dict) -> None:
        """The env's state after a step of the running episode (ignored between episodes)."""
        if self._recording:
            self._sample(info)

    def end(self) -> None:
        """Send what the episode has left buffered; later samples are ignored until ``begin``."""
        self._send()
        self._recording = False

    def _log_static(self) -> None:
        log_static_scene(self.stream, self._model, self._world)
        self._log_threshold_square()
        self.stream.log(
            join(self._plots, "ball_height"),
            rr.SeriesLines(colors=[HEIGHT_COLOUR], names=["ball height (m)"]),
            static=True,
        )
        for ball in range(1, self._balls):
            colour = self._model.geom(ball_name(ball)).rgba[:3]
            self.stream.log(
                join(self._plots, _height_series(ball)),
                rr.SeriesLines(colors=[colour], names=[f"ball {ball} height (m)"]),
                static=True,
            )
        self.stream.log(
            join(self._plots, "threshold"),
            rr.SeriesLines(colors=[THRESHOLD_COLOUR], names=["threshold"]),
            static=True,
        )
        self.stream.log(
            join(self._plots, "throws"),
            rr.SeriesPoints(colors=[THROW_COLOUR], names=["throw"], markers=["diamond"]),
            static=True,
        )

    def _log_threshold_square(self, half_width: float = 0.6) -> None:
        """The threshold plane as a square outline, centred over the cup's start position."""
        centre_x, centre_y = self._data.site_xpos[self._cup_site, :2]
        corners = [[-1, -1], [1, -1], [1, 1], [-1, 1], [-1, -1]]
        outline = [
            [centre_x + half_width * x, centre_y + half_width * y, self._threshold]
            for x, y in corners
        ]
        self.stream.log(
            join(self._world, "threshold"),
            rr.LineStrips3D([outline], colors=[THRESHOLD_COLOUR], radii=[0.003]),
            static=True,
        )

    def _start_buffers(self) -> None:
        self._times: list[float] = []
        self._heights: list[float] = []
        self._throw_times: list[float] = []
        self._throw_heights: list[float] = []
        self._frame_times: list[float] = []
        self._xpos: list[np.ndarray] = []
        self._xquat: list[np.ndarray] = []

    def _sample(self, info: dict) -> None:
        time = info["time"]
        self._times.append(time)
        self._heights.append(info["ball_heights"])
        for ball, (count, before) in enumerate(
            zip(info["throws_per_ball"], self._throws_per_ball, strict=True)
        ):
            if count > before:  # a marker at the height of the ball thrown
                self._throw_times.append(time)
                self._throw_heights.append(info["ball_heights"][ball])
        self._throws_per_ball = info["throws_per_ball"]
        if time >= self._next_frame - 1e-9:  # frames on a grid of frame_period seconds
            self._next_frame = (math.floor(time / self.frame_period + 1e-9) + 1) * self.frame_period
            self._add_frame(time)
            if len(self._frame_times) >= FRAMES_PER_SEND:
                self._send()

    def _add_frame(self, time: float) -> None:
        """Body poses at the current state (``data.xpos`` lags one physics step behind qpos)."""
        self._kinematics.qpos[:] = self._data.qpos
        mujoco.mj_kinematics(self._model, self._kinematics)
        self._frame_times.append(time)
        self._xpos.append(self._kinematics.xpos.copy())
        self._xquat.append(self._kinematics.xquat.copy())

    def _send(self) -> None:
        """Send the buffered samples as columns and empty the buffers."""
        if not self._recording or not self._times:
            return
        for ball, heights in enumerate(zip(*self._heights, strict=True)):
            self._send_scalars(_height_series(ball), self._times, list(heights))
        ends = [self._times[0], self._times[-1]]
        self._send_scalars("threshold", ends, [self._threshold] * 2)
        if self._throw_times:
            self._send_scalars("throws", self._throw_times, self._throw_heights)
        if self._frame_times:
            self._send_poses()
        self._start_buffers()

    def _send_scalars(self, name: str, times: list[float], values: list[float]) -> None:
        # numpy arrays: rerun converts Python lists element by element, ~15x slower
        self.stream.send_columns(
            join(self._plots, name),
            indexes=[rr.TimeColumn(SIM_TIME, duration=np.asarray(times))],
            columns=rr.Scalars.columns(scalars=np.asarray(values)),
        )

    def _send_poses(self) -> None:
        translations, quaternions = relative_poses(
            self._model, np.stack(self._xpos), np.stack(self._xquat)
        )
        index = [rr.TimeColumn(SIM_TIME, duration=np.asarray(self._frame_times))]
        for body in self._moving:
            self.stream.send_columns(
                self._paths[body],
                indexes=index,
                columns=rr.Transform3D.columns(
                    translation=translations[:, body].astype(np.float32),
                    quaternion=quaternions[:, body].astype(np.float32),
                ),
            )


class EpisodeRecorder(gym.Wrapper):
    """Records every episode of the wrapped ``JuggleEnv`` into a rerun stream (``EpisodeTrack``
    says what and where). To record several episodes in one stream, give each its own ``root``
    (e.g. ``eval/episodes/0005``), set before its ``reset``."""

    def __init__(
        self, env: gym.Env, stream: rr.RecordingStream, root: str = "", scene_fps: float = 50.0
    ):
        super().__init__(env)
        juggle = env.unwrapped
        self.root = root
        self.track = EpisodeTrack(
            juggle.model, juggle.data, juggle.threshold, juggle.balls, stream, scene_fps
        )

    def reset(self, **kwargs):
        observation, info = self.env.reset(**kwargs)
        self.track.begin(self.root, info)  # sends what an abandoned episode left first
        return observation, info

    def step(self, action):
        observation, reward, terminated, truncated, info = self.env.step(action)
        self.track.sample(info)
        if terminated or truncated:
            self.track.end()
        return observation, reward, terminated, truncated, info

    def close(self):
        self.track.end()
        super().close()


class BatchEnvRecorder:
    """Records the episode of env ``env`` of a ``JuggleBatch`` under ``root`` as
    ``jugglerl.batch.episodes.run_episodes`` steps the batch (its ``on_step``): the episode runs
    with the others, in the same forward passes, instead of alone after them."""

    def __init__(
        self, batch, env: int, stream: rr.RecordingStream, root: str, scene_fps: float = 50.0
    ):
        self.track = EpisodeTrack.of_batch_env(batch, env, stream, scene_fps)
        self.batch, self.env, self.root = batch, env, root
        self._begun = False

    def __call__(self, moved: np.ndarray) -> None:
        if not moved[self.env]:
            return
        info = self.batch.env_info(self.env)
        if not self._begun:  # the reset
            self.track.begin(self.root, info)
            self._begun = True
        else:
            self.track.sample(info)
        if self.batch.terminated[self.env] or self.batch.truncated[self.env]:
            self.track.end()


def record_episode(
    env: gym.Env,
    policy: Policy,
    stream: rr.RecordingStream,
    root: str = "",
    seed: int | None = None,
    scene_fps: float = 50.0,
) -> EpisodeMetrics:
    """Run one episode of ``policy`` in ``env`` while recording it under ``root``; the recorder
    is closed (the episode sent) whatever happens, and ``env`` with it."""
    recorder = EpisodeRecorder(env, stream, root, scene_fps)
    try:
        return run_episode(recorder, policy, seed=seed)
    finally:
        recorder.close()


def _height_series(ball: int) -> str:
    """The plot of ball ``ball``'s height: ``ball_height`` for the first, as with one ball."""
    return "ball_height" if ball == 0 else f"{ball_name(ball)}_height"
