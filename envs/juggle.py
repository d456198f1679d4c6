"""The juggling environment: a UR5e with a cone cup throws and catches one ball, or ``balls``.

Gymnasium id ``JuggleRL/Juggle-v0`` (registered by ``import jugglerl`` or ``import jugglerl_envs``).
Its defaults are the paper preset (gravity -2 m/s², the authors' code); see ``configs/env/``.

## Action
``Box(-1, 1, (3,), float32)``: setpoints of the position servos of ``shoulder_pan_joint``,
``shoulder_lift_joint`` and ``elbow_joint``, mapped linearly onto the actuators' control ranges
(radians): pan [-π/2, π/2], lift [-π, 0], elbow [0, π]. Action 0 puts the upper arm vertical and
the forearm level. The wrist joints are held at ``wrist_angles`` by their own servos.

With ``wrist_1_actuated=True`` (off by default: the paper's three actuators) ``wrist_1_joint`` is
a fourth: ``Box(-1, 1, (4,))``, its setpoint over [-2π, 2π], starting at ``wrist_angles[0]``;
it turns the cup in the arm's plane, so the cup's tilt no longer follows the lift and elbow.
The speed limit and servo gain apply to it too. An action of the wrong length is refused.

## Observation
``Box(-inf, inf, (18,), float64)``:

| index | what | unit |
| --- | --- | --- |
| 0-2 | angles of pan, lift and elbow | rad |
| 3-5 | their velocities | rad/s |
| 6-8 | ball position | m |
| 9-11 | ball velocity | m/s |
| 12-14 | cup position (site ``cup``, the cone's throat) | m |
| 15-17 | cup velocity | m/s |
| 18-19 | ``wrist_1_actuated`` only: its angle (rad) and velocity (rad/s) | |

| 18-23 (20-25), ... | ``balls`` > 1: each further ball's position and velocity | m, m/s |

The fourth joint's values come after the 18, and the further balls' after those, so every index
above means the same in every env (the further balls start at 20 with ``wrist_1_actuated``);
indices 6-11 are always the first ball.

Cup position and velocity come from the kinematics of the last physics step (MuJoCo computes them
before integrating), 2 ms older than the joint and ball states at the default timestep.

## Reward (kwarg ``reward``; one module each in ``jugglerl_envs.rewards``, documented there)
``throws`` (1 per throw over ``threshold`` in free flight, ``jugglerl_envs.events``: the paper's
reward 1, the DPS objective), ``distance`` (``min(1, 0.05 m / cup-ball distance)``, reward 2),
``contacts`` (ball-arm contacts, reward 3), ``juggle`` (ours: throws plus a small centring term).

## Start state
Arm at ``home`` (pan, lift, elbow) with the wrist at ``wrist_angles``, at rest; the ball at rest
``drop_height`` above the cup, offset horizontally by up to ``reset_noise`` metres (uniform).
With ``balls`` > 1 ball ``k`` starts ``k · ball_spacing`` higher still, offset the same way: the
balls drop into the cup one after the other (``ball_spacing`` 2 m at g = -2: 0.9 s apart), so a
pattern begins as the one-ball pattern does, with the next ball on its way. Balls pass through
each other (``jugglerl_envs.scene``).

## Episode end
Terminated when a ball falls below 0.1 m (dropped) or the physics goes bad (NaN, or any MuJoCo
warning: ``info["physics_error"]`` says which; the env never raises). Truncated after
``duration`` seconds of simulated time.

## Info
``throws``, ``catches`` (episode totals over the balls), ``throws_per_ball`` (a tuple),
``max_consecutive_catches`` (the longest streak of one ball), ``ball_height`` (m, the first
ball), ``ball_heights`` (every ball), ``in_cup`` (bool, the first ball), episode maxima
sampled every env step: ``max_cup_height`` (the cup's throat, m; a counted throw rose at least
``threshold`` minus this above the cup), ``peak_joint_speed`` (each actuated joint, rad/s;
3 or 4 values) and ``max_balls_in_cup`` (the most balls inside the cone at once: balls pass
through each other, so two can share the cup, which no real cup allows); ``time`` (s),
``kicks`` (so far), ``physics_error`` ("" if fine).

## Perturbations (for robustness tests; off by default, see ``jugglerl_envs.perturbations``)
``reset_noise`` (ball start offset), ``ball_mass``, ``ball_radius``, ``servo_gain`` (scales the
arm servos' kp), ``kick_rate`` and ``kick_speed`` (random horizontal velocity kicks of the
ball in free flight, per second and in m/s; each ball its own); imprecision: ``action_noise``
(std of Gaussian noise on every action, normalised units) with ``action_noise_correlation``
(s; 0 = white), ``ball_noise`` (m, std of the observed ball position's noise; the observed
ball velocity is then the difference of noisy positions over a step) and ``ball_latency`` (env
steps the ball's observation arrives late; each ball tracked alike). Throws and catches always
count the true balls.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from gymnasium import spaces
from gymnasium.envs.mujoco.mujoco_env import MujocoEnv

from jugglerl_envs import actions, scene
from jugglerl_envs.events import JuggleEvents
from jugglerl_envs.measurements import SceneMeasurements
from jugglerl_envs.perturbations import ActionNoise, BallKicks, BallTracker, scale_servo_gains
from jugglerl_envs.rewards import REWARDS
from jugglerl_envs.validation import check_choice, check_number, check_vector

DROP_HEIGHT = 0.1  # m: below this the ball counts as dropped
MAX_RESET_NOISE = 0.05  # m: largest start offset of the ball (it must start above the cup)
PAPER_HOME = (0.0, -1.5708, 2.15)  # rad: the paper preset (configs/env/paper.yaml)
PAPER_WRIST = (-2.0, 1.5708, 0.0)
#: Observation length with the paper's three actuators and one ball (two more with
#: ``wrist_1_actuated``, ``BALL_SIZE`` more per further ball).
OBSERVATION_SIZE = 18
#: Observed values of a ball: its position and velocity.
BALL_SIZE = 6


class JuggleEnv(SceneMeasurements, MujocoEnv):
    """UR5e juggling env; see the module docstring for spaces, rewards and episode end."""

    metadata = {"render_modes": ["human", "rgb_array", "depth_array"]}

    def __init__(
        self,
        gravity: float = -2.0,
        duration: float = 120.0,
        threshold: float = 1.0,
        reward: str = "throws",
        frame_skip: int = 10,
        timestep: float = 0.002,
        ball_radius: float = 0.035,
        ball_mass: float = 0.1,
        reset_noise: float = 0.0,
        joint_speed_limit: float | None = None,
        servo_gain: float = 1.0,
        kick_rate: float = 0.0,
        kick_speed: float = 0.0,
        action_noise: float = 0.0,
        action_noise_correlation: float = 0.0,
        ball_noise: float = 0.0,
        ball_latency: int = 0,
        drop_height: float = 0.5,
        balls: int = 1,
        ball_spacing: float = 2.0,
        home: tuple[float, float, float] = PAPER_HOME,
        wrist_angles: tuple[float, float, float] = PAPER_WRIST,
        wrist_1_actuated: bool = False,
        render_mode: str | None = None,
        width: int = 640,
        height: int = 480,
        camera_name: str | None = "side",
    ):
        self.gravity = check_number("gravity", gravity, -50.0, 0.0)
        self.duration = check_number("duration", duration, 0.0, 1e6, low_open=True)
        self.threshold = check_number("threshold", threshold, 0.0, 10.0, low_open=True)
        self.reward_kind = reward
        self._reward = REWARDS.get(reward)
        frame_skip = check_number("frame_skip", frame_skip, 1, 1000, integer=True)
        self.timestep = check_number("timestep", timestep, 0.0, 0.01, low_open=True)
        self.ball_radius = check_number("ball_radius", ball_radius, 0.01, 0.09)
        self.ball_mass = check_number("ball_mass", ball_mass, 0.0, 10.0, low_open=True)
        self.reset_noise = check_number("reset_noise", reset_noise, 0.0, MAX_RESET_NOISE)
        self.joint_speed_limit = (
            None
            if joint_speed_limit is None
            else check_number("joint_speed_limit", joint_speed_limit, 0.0, 100.0, low_open=True)
        )
        self.servo_gain = check_number("servo_gain", servo_gain, 0.0, 10.0, low_open=True)
        self.kick_rate = check_number("kick_rate", kick_rate, 0.0, 100.0)
        self.kick_speed = check_number("kick_speed", kick_speed, 0.0, 10.0)
        self._kicks = BallKicks(self.kick_rate, self.kick_speed)
        self.action_noise = check_number("action_noise", action_noise, 0.0, 1.0)
        self.action_noise_correlation = check_number(
            "action_noise_correlation", action_noise_correlation, 0.0, 100.0
        )
        self.ball_noise = check_number("ball_noise", ball_noise, 0.0, 0.1)
        self.ball_latency = check_number("ball_latency", ball_latency, 0, 50, integer=True)
        self.drop_height = check_number("drop_height", drop_height, 0.0, 2.0)
        self.balls = check_number("balls", balls, 1, scene.MAX_BALLS, integer=True)
        self.ball_spacing = check_number("ball_spacing", ball_spacing, 0.0, 10.0)
        self.home = np.array(check_vector("home", home, 3, -2 * math.pi, 2 * math.pi))
        self.wrist_angles = np.array(
            check_vector("wrist_angles", wrist_angles, 3, -2 * math.pi, 2 * math.pi)
        )
        if not isinstance(wrist_1_actuated, bool):
            raise ValueError(f"wrist_1_actuated={wrist_1_actuated!r} is not valid: expected a bool")
        self.wrist_1_actuated = wrist_1_actuated
        self.actuated_joints = (
            scene.ACTUATED_JOINTS_WITH_WRIST_1 if wrist_1_actuated else scene.ACTUATED_JOINTS
        )
        if render_mode is not None:
            check_choice("render_mode", render_mode, self.metadata["render_modes"])

        self.metadata = {**self.metadata, "render_fps": round(1.0 / (timestep * frame_skip))}
        size = OBSERVATION_SIZE + 2 * wrist_1_actuated + BALL_SIZE * (self.balls - 1)
        observation_space = spaces.Box(-np.inf, np.inf, shape=(size,), dtype=np.float64)
        super().__init__(
            scene.scene_path(),
            frame_skip,
            observation_space,
            render_mode=render_mode,
            width=width,
            height=height,
            camera_name=camera_name,
        )
        self._cache_ids()
        self._servos = len(self.actuated_joints)
        self._action_noise = ActionNoise(
            self.action_noise, self.action_noise_correlation, self.dt, self._servos
        )
        self._trackers = [
            BallTracker(self.ball_noise, self.ball_latency, self.dt) for _ in range(self.balls)
        ]
        self._events = [JuggleEvents(self.threshold) for _ in range(self.balls)]
        self._steps = 0
        self._max_steps = max(1, round(self.duration / self.dt))

    # --- set-up -----------------------------------------------------------------------------
    def _initialize_simulation(self):
        model = scene.load_model(
            self.gravity, self.timestep, self.ball_radius, self.ball_mass, self.balls
        )
        scale_servo_gains(model, slice(0, len(self.actuated_joints)), self.servo_gain)
        model.vis.global_.offwidth = max(model.vis.global_.offwidth, self.width)
        model.vis.global_.offheight = max(model.vis.global_.offheight, self.height)
        return model, mujoco.MjData(model)

    def _set_action_space(self):
        shape = (len(self.actuated_joints),)
        self.action_space = spaces.Box(-1.0, 1.0, shape=shape, dtype=np.float32)
        return self.action_space

    # --- action mapping ---------------------------------------------------------------------
    @staticmethod
    def action_to_ctrl(action: np.ndarray) -> np.ndarray:
        """Servo setpoints (rad) for a normalised action in [-1, 1] (``jugglerl_envs.actions``)."""
        return actions.action_to_ctrl(action)

    @staticmethod
    def ctrl_to_action(ctrl: np.ndarray) -> np.ndarray:
        """Normalised action for servo setpoints in radians (inverse of ``action_to_ctrl``)."""
        return actions.ctrl_to_action(ctrl)

    # --- episode ----------------------------------------------------------------------------
    def reset_model(self) -> np.ndarray:
        qpos = self.init_qpos.copy()
        qpos[self._arm_qpos] = np.concatenate([self.home, self.wrist_angles])
        self.data.qpos[:] = qpos
        self.data.qvel[:] = 0.0
        self.data.ctrl[:] = qpos[self._arm_qpos]
        mujoco.mj_forward(self.model, self.data)
        cup = self.data.site_xpos[self._cup_site].copy()
        for ball, address in enumerate(self._balls_qpos):
            offset = self.np_random.uniform(-self.reset_noise, self.reset_noise, size=2)
            height = self.drop_height + ball * self.ball_spacing
            self.data.qpos[address : address + 3] = cup + np.array([*offset, height])
            self.data.qpos[address + 3 : address + 7] = (1.0, 0.0, 0.0, 0.0)
        mujoco.mj_forward(self.model, self.data)

        self._steps = 0
        self._kick_count = 0
        self._setpoint = self.data.ctrl[: self._servos].copy()
        self._peak_joint_speed = np.zeros(self._servos)
        self._max_cup_height = float(self.cup_position()[2])
        self._measure_balls()
        self._max_balls_in_cup = sum(self._in_cup)
        for ball, events in enumerate(self._events):
            events.reset(self._heights[ball], self._clear_of_cup[ball])
        self._physics_error = ""
        self._action_noise.reset(self.np_random)
        return self._get_obs(reset=True)

    def _get_reset_info(self) -> dict:
        return self._info()

    def step(self, action):
        action = np.asarray(action, dtype=np.float64)
        if action.shape != (self._servos,):
            raise ValueError(
                f"an action of shape {action.shape}: this env drives {self._servos} servos"
                f" (wrist_1_actuated={self.wrist_1_actuated})"
            )
        if self._action_noise.active:
            action = action + self._action_noise.draw(self.np_random)
        target = self.action_to_ctrl(action)
        self._simulate(target)
        self._steps += 1
        self._kick_ball()
        self._physics_error = self._check_physics()

        self._measure_balls()
        cup_height = self.data.site_xpos[self._cup_site, 2]
        throws = 0
        for ball, events in enumerate(self._events):
            height = self._heights[ball]
            throws += events.update(
                height,
                self._ball_in_flight(ball),
                self._in_cup[ball],
                self._clear_of_cup[ball],
                height < cup_height,
            )
        speeds = np.abs(self.data.qvel[self._arm_qvel])
        self._peak_joint_speed = np.maximum(self._peak_joint_speed, speeds)
        self._max_cup_height = max(self._max_cup_height, float(self.cup_position()[2]))
        self._max_balls_in_cup = max(self._max_balls_in_cup, sum(self._in_cup))

        obs = self._get_obs()
        reward = self._reward(self, throws)
        terminated = bool(self._physics_error) or min(self._heights) < DROP_HEIGHT
        truncated = self._steps >= self._max_steps and not terminated
        if self.render_mode == "human":
            self.render()
        return obs, reward, terminated, truncated, self._info()

    def _simulate(self, target: np.ndarray) -> None:
        """Advance ``frame_skip`` physics steps towards the servo ``target`` (rad)."""
        servos = self._servos
        if self.joint_speed_limit is None:
            self.data.ctrl[:servos] = target
            mujoco.mj_step(self.model, self.data, nstep=self.frame_skip)
            return
        max_change = self.joint_speed_limit * self.model.opt.timestep
        for _ in range(self.frame_skip):
            self._setpoint += np.clip(target - self._setpoint, -max_change, max_change)
            self.data.ctrl[:servos] = self._setpoint
            mujoco.mj_step(self.model, self.data)

    @property
    def kicks_ball(self) -> bool:
        """Whether this env kicks the ball in flight (``kick_rate`` and ``kick_speed`` > 0)."""
        return self._kicks.active

    def _kick_ball(self) -> None:
        """Maybe kick each ball in free flight (``kick_rate``, ``kick_speed``)."""
        if not self._kicks.active:
            return
        for ball in range(self.balls):
            if not self._ball_in_flight(ball):
                continue
            kick = self._kicks.draw(self.np_random, self.dt)
            if kick is not None:
                self.ball_velocity(ball)[:] += kick
                self._kick_count += 1

    def _get_obs(self, reset: bool = False) -> np.ndarray:
        observation = self._true_obs()
        if not self._trackers[0].active:  # the policy sees tracked balls; events the true ones
            return observation
        for ball, tracker in enumerate(self._trackers):
            seen = self.ball_slice(ball)
            track = tracker.reset if reset else tracker.observe
            observation[seen] = track(observation[seen][:3], observation[seen][3:], self.np_random)
        return observation

    def ball_slice(self, ball: int) -> slice:
        """Where ball ``ball``'s position and velocity sit in the observation."""
        if ball == 0:
            return slice(6, 12)
        start = OBSERVATION_SIZE + 2 * self.wrist_1_actuated + BALL_SIZE * (ball - 1)
        return slice(start, start + BALL_SIZE)

    def _true_obs(self) -> np.ndarray:
        d = self.data
        parts = [
            d.qpos[self._arm_qpos[:3]],
            d.qvel[self._arm_qvel[:3]],
            self.ball_position(),
            self.ball_velocity(),
            d.site_xpos[self._cup_site],
            self._cup_velocity(),
        ]
        if self.wrist_1_actuated:  # appended, so the indices above keep their meaning
            parts += [d.qpos[self._arm_qpos[3:4]], d.qvel[self._arm_qvel[3:4]]]
        for ball in range(1, self.balls):  # and after those, the further balls
            parts += [self.ball_position(ball), self.ball_velocity(ball)]
        return np.concatenate(parts)

    def _info(self) -> dict:
        return {
            "throws": sum(events.throws for events in self._events),
            "throws_per_ball": tuple(events.throws for events in self._events),
            "catches": sum(events.catches for events in self._events),
            "max_consecutive_catches": max(events.max_streak for events in self._events),
            "ball_height": self._heights[0],
            "ball_heights": tuple(self._heights),
            "in_cup": self._in_cup[0],
            "peak_joint_speed": self._peak_joint_speed.copy(),
            "max_cup_height": self._max_cup_height,
            "max_balls_in_cup": self._max_balls_in_cup,
            "time": float(self.data.time),
            "kicks": self._kick_count,
            "physics_error": self._physics_error,
        }
