"""The juggling environment: a UR5e with a cone cup throws and catches one ball, or ``balls``.

Gymnasium id ``JuggleRL/Juggle-v0`` (registered by ``import jugglerl`` or ``import jugglerl_envs``).
Its defaults are the paper preset (gravity -2 m/s², the authors' code); see ``configs/env/``.
Its arguments, their defaults and checks are listed once, in ``jugglerl_envs.settings``. It is a
``JuggleBatch`` of one env (``jugglerl_envs.batch``, where the task's rules live), with MuJoCo's
renderer: env ``i`` of a batch plays exactly as this env reset with the batch's seed plus ``i``.

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
``contacts`` (ball-arm contacts, reward 3), ``juggle`` (ours: throws plus a small centring term),
``cradle`` (ours: ``juggle`` less a cost for a held ball rolled off the cone's axis), ``rise``
(ours: ``juggle`` plus the height a ball rises in free flight, up to the threshold).

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

import numpy as np
from gymnasium.envs.mujoco.mujoco_env import MujocoEnv

from jugglerl_envs import actions, scene
from jugglerl_envs.batch import DROP_HEIGHT, JuggleBatch, ball_slice
from jugglerl_envs.settings import ARGUMENTS
from jugglerl_envs.validation import check_choice

__all__ = ["DROP_HEIGHT", "JuggleEnv"]

#: The arguments a ``JuggleEnv`` lets change between episodes (properties; the others are fixed).
POSES = ("home", "wrist_angles")


class JuggleEnv(MujocoEnv):
    """UR5e juggling env; see the module docstring for spaces, rewards and episode end. The
    keyword ``arguments`` are ``jugglerl_envs.settings.ARGUMENTS`` (the paper preset by default);
    ``render_mode``, ``width``, ``height`` and ``camera_name`` set up MuJoCo's renderer."""

    metadata = {"render_modes": ["human", "rgb_array", "depth_array"]}

    def __init__(
        self,
        render_mode: str | None = None,
        width: int = 640,
        height: int = 480,
        camera_name: str | None = "side",
        **arguments,
    ):
        if render_mode is not None:
            check_choice("render_mode", render_mode, self.metadata["render_modes"])
        self.batch = JuggleBatch(1, threads=1, autoreset=False, **arguments)
        for key, value in self.batch.settings.env(0).items():
            if key not in POSES:
                setattr(self, "reward_kind" if key == "reward" else key, value)
        self.actuated_joints = self.batch.actuated_joints
        self.width, self.height = width, height  # MujocoEnv sizes the offscreen buffer with them
        dt = self.batch.dt[0]
        self.metadata = {**self.metadata, "render_fps": round(1.0 / dt)}
        super().__init__(
            scene.scene_path(),
            self.batch.frame_skip,
            self.batch.single_observation_space,
            render_mode=render_mode,
            width=width,
            height=height,
            camera_name=camera_name,
        )
        self._cup_site = self.batch._cup_site

    # --- set-up -----------------------------------------------------------------------------
    def _initialize_simulation(self):
        model = self.batch.models[0]
        model.vis.global_.offwidth = max(model.vis.global_.offwidth, self.width)
        model.vis.global_.offheight = max(model.vis.global_.offheight, self.height)
        return model, self.batch.datas[0]

    def _set_action_space(self):
        self.action_space = self.batch.single_action_space
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
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super(MujocoEnv, self).reset(seed=seed)  # seeds ``np_random``, which the batch draws from
        self.batch.rngs[0] = self.np_random
        observations, _ = self.batch.reset()
        if self.render_mode == "human":
            self.render()
        return observations[0], self.batch.env_info(0)

    def step(self, action):
        action = np.asarray(action, dtype=np.float64)
        if action.shape != (self.batch.servos,):
            raise ValueError(
                f"an action of shape {action.shape}: this env drives {self.batch.servos} servos"
                f" (wrist_1_actuated={self.wrist_1_actuated})"
            )
        observations, rewards, terminated, truncated = self.batch.step_without_info(action[None])
        if self.render_mode == "human":
            self.render()
        info = self.batch.env_info(0)
        return observations[0], float(rewards[0]), bool(terminated[0]), bool(truncated[0]), info

    @property
    def home(self) -> np.ndarray:
        """Start pose of pan, lift and elbow (rad); set it to start the next episodes elsewhere."""
        return self.batch.settings.home[0]

    @home.setter
    def home(self, pose) -> None:
        self.batch.settings.home[0] = ARGUMENTS["home"].check("home", pose)

    @property
    def wrist_angles(self) -> np.ndarray:
        """The wrist's angles (rad), held by its servos; set them for the next episodes."""
        return self.batch.settings.wrist_angles[0]

    @wrist_angles.setter
    def wrist_angles(self, angles) -> None:
        self.batch.settings.wrist_angles[0] = ARGUMENTS["wrist_angles"].check(
            "wrist_angles", angles
        )

    @property
    def kicks_ball(self) -> bool:
        """Whether this env kicks the ball in flight (``kick_rate`` and ``kick_speed`` > 0)."""
        return self.kick_rate > 0 and self.kick_speed > 0

    def ball_slice(self, ball: int) -> slice:
        """Where ball ``ball``'s position and velocity sit in the observation."""
        return ball_slice(ball, self.wrist_1_actuated)

    def true_observation(self) -> np.ndarray:
        """The observation with the true balls (what ``ball_noise`` and ``ball_latency`` hide),
        at the last step."""
        observation = self.batch._observations[0].copy()
        for ball in range(self.balls):
            seen = self.ball_slice(ball)
            observation[seen] = np.concatenate(
                [self.batch.ball_positions[0, ball], self.batch.ball_velocities[0, ball]]
            )
        return observation

    # --- the scene, read off (and writable through) MuJoCo's state -----------------------------
    def ball_position(self, ball: int = 0) -> np.ndarray:
        """The ball's centre (m, world frame), a view of ``data.qpos``."""
        start = self.batch._balls_qpos[ball]
        return self.data.qpos[start : start + 3]

    def ball_velocity(self, ball: int = 0) -> np.ndarray:
        """The ball's linear velocity (m/s, world frame), a view of ``data.qvel``."""
        start = self.batch._balls_qvel[ball]
        return self.data.qvel[start : start + 3]

    def cup_position(self) -> np.ndarray:
        """The cup's throat (site ``cup``, m, world frame), from the last physics step."""
        return self.data.site_xpos[self._cup_site]

    def ball_in_cup(self, ball: int = 0) -> bool:
        """Whether ball ``ball``'s centre sat inside the cone, below its rim, after the step."""
        return bool(self.batch.in_cup[0, ball])

    def ball_in_cup_frame(self, ball: int = 0) -> tuple[float, float]:
        """Ball centre in the cup frame (m): (distance from the cone axis, height above throat),
        after the step."""
        return float(self.batch.radial[0, ball]), float(self.batch.height_in_cup[0, ball])

    def ball_arm_contacts(self) -> int:
        """Contacts between the ball and the arm (links and cup plates) after the last step."""
        return int(self.batch.ball_arm_contacts()[0])

    def close(self):
        self.batch.close()
        super().close()
