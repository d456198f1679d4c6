"""``JuggleBatch``: N juggling envs stepped together, the physics in C on every core.

The task's rules live here once: ``JuggleEnv`` (``jugglerl_envs.juggle``) is a batch of one.
Each env keeps its own ``MjData`` (so the solver's warm start is kept, and env ``i`` of a batch
plays bit for bit as a lone ``JuggleEnv`` reset with the same seed), envs with the same physical
arguments share one ``MjModel``, and one step of the batch

1. adds each env's action noise (its own random generator) and maps the actions to setpoints;
2. advances every env ``frame_skip`` physics steps from a pool of ``threads`` threads (MuJoCo's
   bindings release the GIL inside ``mj_step``), kicks the balls in flight and copies each
   env's state into the batch's arrays, env by env in the same thread;
3. computes the balls' events, the rewards, the ends of episodes and the observations for all
   envs at once in NumPy, the tracked balls from each env's own generator.

Gymnasium's vector-env conventions: ``reset(seed=S)`` seeds env ``i`` with ``S + i`` (or takes one
seed per env) and returns ``(observations[N, obs], info)``; ``step(actions[N, act])`` returns
``(observations, rewards[N], terminated[N], truncated[N], info)``, ``info`` holding one array
per entry of ``JuggleEnv``'s info (``throws``, ``catches``, ``time``, ...). With ``autoreset``
(Gymnasium's NEXT_STEP mode) an env that ended is reset by the next ``step``, which ignores its
action and returns its first observation with reward 0; without it, an env that ended stays as it
ended (its action ignored, its last observation and info, reward 0, ``terminated`` or
``truncated`` still set, no physics spent on it) until ``reset(options={"reset_mask": mask})``
resets the envs of ``mask`` and leaves the others as they are.

Any argument of ``JuggleEnv`` may be a sequence of one value per env (``EnvSettings``), so one
batch holds nominal and perturbed envs side by side. ``state_dict()`` holds the whole batch
(physics, generators, perturbations, event counts): a batch restored from it continues bit for bit.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding

from jugglerl_envs import actions as action_map
from jugglerl_envs import scene
from jugglerl_envs.events import JuggleEvents
from jugglerl_envs.perturbations import (
    ActionNoise,
    BallTracker,
    draw_kick,
    kick_probability,
    scale_servo_gains,
)
from jugglerl_envs.rewards import REWARDS
from jugglerl_envs.settings import EnvSettings
from jugglerl_envs.validation import check_number

DROP_HEIGHT = 0.1  # m: below this a ball counts as dropped
#: Observation length with the paper's three actuators and one ball (two more with
#: ``wrist_1_actuated``, ``BALL_SIZE`` more per further ball).
OBSERVATION_SIZE = 18
#: Observed values of a ball: its position and velocity.
BALL_SIZE = 6
#: The physics state a saved batch restores: everything ``mj_step`` reads, warm start included.
PHYSICS_STATE = mujoco.mjtState.mjSTATE_INTEGRATION
MAX_ENVS = 1 << 16


def usable_cores() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


def ball_slice(ball: int, wrist_1_actuated: bool) -> slice:
    """Where ball ``ball``'s position and velocity sit in the observation."""
    if ball == 0:
        return slice(6, 12)
    start = OBSERVATION_SIZE + 2 * wrist_1_actuated + BALL_SIZE * (ball - 1)
    return slice(start, start + BALL_SIZE)


class JuggleBatch(gym.vector.VectorEnv):
    """``num_envs`` juggling envs of ``JuggleEnv``'s ``arguments`` (see the module docstring),
    stepped by ``threads`` threads (default: one per usable core)."""

    metadata = {"autoreset_mode": gym.vector.AutoresetMode.NEXT_STEP}

    def __init__(
        self, num_envs: int, *, threads: int | None = None, autoreset: bool = True, **arguments
    ):
        self.num_envs = check_number("num_envs", num_envs, 1, MAX_ENVS, integer=True)
        threads = usable_cores() if threads is None else threads
        self.threads = check_number("threads", threads, 1, 1024, integer=True)
        self.autoreset = bool(autoreset)
        self.settings = settings = EnvSettings(self.num_envs, **arguments)
        self._reward = REWARDS.get(settings.reward)
        self.balls = settings.balls
        self.frame_skip = settings.frame_skip
        self.wrist_1_actuated = settings.wrist_1_actuated
        self.actuated_joints = (
            scene.ACTUATED_JOINTS_WITH_WRIST_1
            if settings.wrist_1_actuated
            else scene.ACTUATED_JOINTS
        )
        self.servos = len(self.actuated_joints)
        self._build_physics()
        self._build_spaces()
        self._build_rules()
        self.rngs = [seeding.np_random()[0] for _ in range(self.num_envs)]
        self._pool = ThreadPoolExecutor(self.threads) if self.threads > 1 else None
        self.closed = False

    # --- set-up -----------------------------------------------------------------------------
    def _build_physics(self) -> None:
        """One model per distinct physical setting, one ``MjData`` per env, and the ids and
        views the steps read."""
        settings, models = self.settings, {}
        for env in range(self.num_envs):
            key = settings.model_key(env)
            if key not in models:
                models[key] = self._compile(env)
        self.models = [models[settings.model_key(env)] for env in range(self.num_envs)]
        self.datas = [mujoco.MjData(model) for model in self.models]
        #: s per env step: the control period
        self.dt = np.array([m.opt.timestep * self.frame_skip for m in self.models])
        self._max_steps = np.array(
            [max(1, round(d / dt)) for d, dt in zip(settings.duration, self.dt, strict=True)]
        )
        m = self.models[0]  # every model has the same bodies, joints and sensors
        self._arm_qpos = np.array([m.jnt_qposadr[m.joint(j).id] for j in scene.ARM_JOINTS])
        self._arm_qvel = np.array([m.jnt_dofadr[m.joint(j).id] for j in self.actuated_joints])
        joints = [m.body(scene.ball_name(ball)).jntadr[0] for ball in range(self.balls)]
        self._balls_qpos = np.array([int(m.jnt_qposadr[joint]) for joint in joints])
        self._balls_qvel = np.array([int(m.jnt_dofadr[joint]) for joint in joints])
        self._cup_site = m.site(scene.CUP_SITE).id
        self._ball_geom = m.geom(scene.BALL_GEOM).id
        self._contact_sensors = np.array(
            [m.sensor_adr[m.sensor(scene.ball_contact_sensor(b)).id] for b in range(self.balls)]
        )
        arm_root = m.body(scene.ARM_ROOT_BODY).id
        arm_bodies = [b for b in range(m.nbody) if _has_ancestor(m, b, arm_root)]
        self._arm_geoms = np.flatnonzero(np.isin(m.geom_bodyid, arm_bodies))
        self._ball_qpos_columns = self._balls_qpos[:, None] + np.arange(3)
        self._ball_qvel_columns = self._balls_qvel[:, None] + np.arange(3)
        margin = self.settings.ball_radius[:, None]  # a ball clear of the cup is this far out
        self._clear_depth = scene.CUP_DEPTH + margin
        self._clear_radius = scene.CUP_TOP_RADIUS + margin
        self._all_envs = np.arange(self.num_envs)
        # views into each env's MjData, so that a step copies without looking anything up
        self._views = [_DataViews(data, self._cup_site) for data in self.datas]
        n = self.num_envs
        self.qpos = np.zeros((n, m.nq))
        self.qvel = np.zeros((n, m.nv))
        self.cup_position = np.zeros((n, 3))  # the cup's throat (site ``cup``), world frame
        self._cup_rotation = np.zeros((n, 9))
        self._cup_twist = np.zeros((n, 6))  # rotational, then linear velocity of the site
        self._sensors = np.zeros((n, m.nsensordata))
        self._warnings = np.zeros((n, len(self.datas[0].warning)), dtype=np.int64)
        self.time = np.zeros(n)

    def _compile(self, env: int) -> mujoco.MjModel:
        arguments = self.settings.env(env)
        model = scene.load_model(
            arguments["gravity"],
            arguments["timestep"],
            arguments["ball_radius"],
            arguments["ball_mass"],
            self.balls,
        )
        scale_servo_gains(model, slice(0, self.servos), arguments["servo_gain"])
        return model

    def _build_spaces(self) -> None:
        size = OBSERVATION_SIZE + 2 * self.wrist_1_actuated + BALL_SIZE * (self.balls - 1)
        self.single_observation_space = spaces.Box(-np.inf, np.inf, (size,), np.float64)
        self.single_action_space = spaces.Box(-1.0, 1.0, (self.servos,), np.float32)
        self.observation_space = spaces.Box(-np.inf, np.inf, (self.num_envs, size), np.float64)
        self.action_space = spaces.Box(-1.0, 1.0, (self.num_envs, self.servos), np.float32)
        # the observation's columns read from qpos and from qvel, in order
        qpos_columns, qvel_columns = [0, 1, 2], [3, 4, 5]
        qpos_sources, qvel_sources = list(self._arm_qpos[:3]), list(self._arm_qvel[:3])
        for ball in range(self.balls):
            where = ball_slice(ball, self.wrist_1_actuated).start
            qpos_columns += range(where, where + 3)
            qvel_columns += range(where + 3, where + 6)
            qpos_sources += range(self._balls_qpos[ball], self._balls_qpos[ball] + 3)
            qvel_sources += range(self._balls_qvel[ball], self._balls_qvel[ball] + 3)
        if self.wrist_1_actuated:
            qpos_columns.append(OBSERVATION_SIZE)
            qvel_columns.append(OBSERVATION_SIZE + 1)
            qpos_sources.append(self._arm_qpos[3])
            qvel_sources.append(self._arm_qvel[3])
        self._observed = [np.array(x) for x in (qpos_columns, qpos_sources)]
        self._observed_velocity = [np.array(x) for x in (qvel_columns, qvel_sources)]
        slices = [ball_slice(ball, self.wrist_1_actuated) for ball in range(self.balls)]
        self._ball_columns = np.array([np.arange(cut.start, cut.stop) for cut in slices])

    def _build_rules(self) -> None:
        """Perturbations, events and the per-episode records."""
        s, n = self.settings, self.num_envs
        self.action_noise = ActionNoise(
            s.action_noise, s.action_noise_correlation, self.dt, self.servos
        )
        self.tracker = BallTracker(s.ball_noise, s.ball_latency, self.dt, self.balls)
        self._kick_probability = [
            kick_probability(rate, dt) if rate > 0 and speed > 0 else 0.0
            for rate, speed, dt in zip(s.kick_rate, s.kick_speed, self.dt, strict=True)
        ]
        self._kick_speed = [float(speed) for speed in s.kick_speed]
        self._speed_limited = np.array([limit is not None for limit in s.joint_speed_limit])
        self._max_change = np.array(
            [
                0.0 if lim is None else lim * m.opt.timestep
                for lim, m in zip(s.joint_speed_limit, self.models, strict=True)
            ]
        )
        self.events = JuggleEvents(s.threshold, self.balls)
        self.steps = np.zeros(n, dtype=np.int64)
        self.kicks = np.zeros(n, dtype=np.int64)
        self.setpoint = np.zeros((n, self.servos))  # rate-limited servo targets (speed limit)
        self.peak_joint_speed = np.zeros((n, self.servos))
        self.max_cup_height = np.zeros(n)
        self.max_balls_in_cup = np.zeros(n, dtype=np.int64)
        self.physics_error = np.full(n, "", dtype=object)
        #: how each env's episode ended (a drop, bad physics; the time limit), until it restarts
        self.terminated = np.zeros(n, dtype=bool)
        self.truncated = np.zeros(n, dtype=bool)
        self.needs_reset = np.ones(n, dtype=bool)
        self._started = False
        self._healthy = True
        self._observations = np.zeros(self.observation_space.shape)

    # --- the API ----------------------------------------------------------------------------
    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict | None = None
    ) -> tuple[np.ndarray, dict]:
        """Reset every env, or those of ``options["reset_mask"]``; ``seed`` (an int: env ``i``
        gets ``seed + i``; or one seed per env, ``None`` keeping that env's generator) seeds
        the envs reset. Returns every env's observation and the info."""
        envs = np.arange(self.num_envs)
        if options and options.get("reset_mask") is not None:
            mask = np.asarray(options["reset_mask"], dtype=bool).reshape(-1)
            if mask.shape != (self.num_envs,):
                raise ValueError(f"reset_mask of shape {mask.shape}: expected ({self.num_envs},)")
            envs = np.flatnonzero(mask)
        self.seed(seed, envs)
        self._restart(envs)
        return self._observations.copy(), self._info()

    def seed(self, seed: int | list[int | None] | None, envs: np.ndarray | None = None) -> None:
        """Seed the generators of ``envs`` (default: all): see ``reset``."""
        envs = np.arange(self.num_envs) if envs is None else envs
        if seed is None:
            return
        if isinstance(seed, (int, np.integer)):
            seeds = [int(seed) + int(env) for env in envs]
        else:
            seeds = list(seed)
            if len(seeds) == self.num_envs and len(envs) != self.num_envs:
                seeds = [seeds[env] for env in envs]
            if len(seeds) != len(envs):
                raise ValueError(f"{len(seeds)} seeds for {len(envs)} envs to reset")
        for env, value in zip(envs, seeds, strict=True):
            if value is not None:
                self.rngs[env] = seeding.np_random(value)[0]

    def step(self, actions) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        """One control step of every env (see the module docstring)."""
        return (*self.step_without_info(actions), self._info())

    def step_without_info(self, actions) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``step`` without building the info dict (``env_info`` gives one env's)."""
        actions = np.asarray(actions, dtype=np.float64)
        if actions.shape != self.action_space.shape:
            raise ValueError(
                f"actions of shape {actions.shape}: this batch takes {self.action_space.shape}"
                f" ({self.num_envs} envs of {self.servos} servos)"
            )
        if not self._started:
            raise RuntimeError("reset the batch before its first step")
        rewards = np.zeros(self.num_envs)
        if not self.needs_reset.any():  # the common case: every env steps (rows: a view)
            self._advance(self._all_envs, actions)
            self._conclude(slice(None), rewards)
        else:
            stepping = np.flatnonzero(~self.needs_reset)
            restarting = np.flatnonzero(self.needs_reset & self.autoreset)
            if len(stepping):
                self._advance(stepping, actions[stepping])
            if len(restarting):
                self._restart(restarting)
            if len(stepping):
                self._conclude(stepping, rewards)
        terminated, truncated = self.terminated.copy(), self.truncated.copy()
        return self._observations.copy(), rewards, terminated, truncated

    def _conclude(self, rows: slice | np.ndarray, rewards: np.ndarray) -> None:
        """After the physics of the envs of ``rows``: their records, rewards and ends."""
        throws = self._record(rows)
        rewards[rows] = self._reward(self, throws)[rows]
        dropped = self.ball_heights[rows].min(axis=1) < DROP_HEIGHT
        terminated = dropped if self._healthy else (self.physics_error[rows] != "") | dropped
        truncated = (self.steps[rows] >= self._max_steps[rows]) & ~terminated
        self.terminated[rows], self.truncated[rows] = terminated, truncated
        self.needs_reset[rows] = terminated | truncated

    def close_extras(self, **kwargs) -> None:
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None

    # --- stepping ---------------------------------------------------------------------------
    def _advance(self, envs: np.ndarray, actions: np.ndarray) -> None:
        """The physics of one env step of ``envs`` under ``actions``, read into the arrays."""
        noisy = actions + self.action_noise.draw(envs, self.rngs)
        self._targets = np.zeros((self.num_envs, self.servos))
        self._targets[envs] = action_map.action_to_ctrl(noisy)
        limited = envs[self._speed_limited[envs]]
        if len(limited):  # the setpoints of each physics step, rate-limited toward the target
            plan = np.zeros((len(limited), self.frame_skip, self.servos))
            setpoint, target = self.setpoint[limited], self._targets[limited]
            change = self._max_change[limited, None]
            for step in range(self.frame_skip):
                setpoint = setpoint + np.clip(target - setpoint, -change, change)
                plan[:, step] = setpoint
            self.setpoint[limited] = setpoint
            self._plans = dict(zip(limited.tolist(), plan, strict=True))
        if self._pool is None or len(envs) == 1:
            self._physics(envs)
            return
        chunks = [c for c in np.array_split(envs, self.threads) if len(c)]
        for future in [self._pool.submit(self._physics, chunk) for chunk in chunks]:
            future.result()

    def _physics(self, envs: np.ndarray) -> None:
        """Env by env (one thread's share): ``frame_skip`` physics steps, kicks, read back."""
        servos, frame_skip = self.servos, self.frame_skip
        for env in envs.tolist():
            model, data, views = self.models[env], self.datas[env], self._views[env]
            if self._speed_limited[env]:
                for setpoint in self._plans[env]:
                    views.ctrl[:servos] = setpoint
                    mujoco.mj_step(model, data)
            else:
                views.ctrl[:servos] = self._targets[env]
                mujoco.mj_step(model, data, nstep=frame_skip)
            if self._kick_probability[env] > 0:
                self._kick(env)
            self._read(env)

    def _kick(self, env: int) -> None:
        """Maybe kick each ball of ``env`` in free flight (``kick_rate``, ``kick_speed``)."""
        views, rng = self._views[env], self.rngs[env]
        for ball in range(self.balls):
            if views.sensors[self._contact_sensors[ball]] != 0:
                continue
            kick = draw_kick(rng, self._kick_probability[env], self._kick_speed[env])
            if kick is not None:
                start = self._balls_qvel[ball]
                views.qvel[start : start + 3] += kick
                self.kicks[env] += 1

    def _read(self, env: int) -> None:
        """Copy env ``env``'s state into the batch's arrays."""
        views = self._views[env]
        self.qpos[env] = views.qpos
        self.qvel[env] = views.qvel
        self.cup_position[env] = views.cup_position
        self._cup_rotation[env] = views.cup_rotation
        self._sensors[env] = views.sensors
        self._warnings[env] = views.warnings
        self.time[env] = self.datas[env].time
        mujoco.mj_objectVelocity(
            self.models[env],
            self.datas[env],
            mujoco.mjtObj.mjOBJ_SITE,
            self._cup_site,
            self._cup_twist[env],
            0,
        )

    def _restart(self, envs: np.ndarray) -> None:
        """Start new episodes in ``envs``: the arm at home, the balls dropped over the cup."""
        for env in envs.tolist():
            self._place(env)
            self._read(env)
        self.steps[envs] = 0
        self.kicks[envs] = 0
        self.setpoint[envs] = self.qpos[envs][:, self._arm_qpos[: self.servos]]
        self.peak_joint_speed[envs] = 0.0
        self.max_cup_height[envs] = self.cup_position[envs, 2]
        self._measure()
        self.max_balls_in_cup[envs] = self.in_cup[envs].sum(axis=1)
        self.events.reset(envs, self.ball_heights[envs], self._clear_of_cup[envs])
        self.physics_error[envs] = ""
        self.action_noise.reset(envs, self.rngs)
        self._observe(envs, first=True)
        self.terminated[envs] = self.truncated[envs] = self.needs_reset[envs] = False
        self._started = True

    def _place(self, env: int) -> None:
        model, data, settings = self.models[env], self.datas[env], self.settings
        mujoco.mj_resetData(model, data)
        qpos = model.qpos0.copy()
        qpos[self._arm_qpos] = np.concatenate([settings.home[env], settings.wrist_angles[env]])
        data.qpos[:] = qpos
        data.qvel[:] = 0.0
        data.ctrl[:] = qpos[self._arm_qpos]
        mujoco.mj_forward(model, data)
        cup = data.site_xpos[self._cup_site].copy()
        noise, drop = float(settings.reset_noise[env]), float(settings.drop_height[env])
        spacing = float(settings.ball_spacing[env])
        for ball, address in enumerate(self._balls_qpos.tolist()):
            offset = self.rngs[env].uniform(-noise, noise, size=2)
            data.qpos[address : address + 3] = cup + np.array([*offset, drop + ball * spacing])
            data.qpos[address + 3 : address + 7] = (1.0, 0.0, 0.0, 0.0)
        mujoco.mj_forward(model, data)

    def _record(self, rows: slice | np.ndarray) -> np.ndarray:
        """After a physics step of the envs of ``rows`` (a slice or indices): their events,
        records and observations; the throws each env's step completed (``[num_envs]``)."""
        self.steps[rows] += 1
        self._check_physics(rows)
        self._measure()
        heights = self.ball_heights[rows]
        below_cup = heights < self.cup_position[rows, 2:3]
        in_cup = self.in_cup[rows]
        clear = self._clear_of_cup[rows]
        new_throws = self.events.update(
            rows, heights, self.in_flight[rows], in_cup, clear, below_cup
        )
        speeds = np.abs(self.qvel[rows][:, self._arm_qvel])
        np.maximum(self.peak_joint_speed[rows], speeds, out=speeds)
        self.peak_joint_speed[rows] = speeds
        self.max_cup_height[rows] = np.fmax(self.max_cup_height[rows], self.cup_position[rows, 2])
        held = in_cup.sum(axis=1)
        self.max_balls_in_cup[rows] = np.maximum(self.max_balls_in_cup[rows], held)
        self._observe(rows, first=False)
        throws = np.zeros(self.num_envs, dtype=np.int64)
        throws[rows] = new_throws.sum(axis=1)
        return throws

    def _check_physics(self, rows: slice | np.ndarray) -> None:
        """``physics_error`` of the envs of ``rows``: the episode's first MuJoCo warning, or a
        NaN state. ``_healthy``: no env has either (the check costs one sum then)."""
        self._healthy = not self._warnings.any() and np.isfinite(self.qpos.sum() + self.qvel.sum())
        self.physics_error[rows] = ""
        if self._healthy:
            return
        warned = self._warnings[rows].any(axis=1)
        finite = np.isfinite(self.qpos[rows].sum(axis=1) + self.qvel[rows].sum(axis=1))
        for env in self._all_envs[rows][warned | ~finite].tolist():
            time = f"t={self.time[env]:.3f}s"
            if self._warnings[env].any():
                first = mujoco.mjtWarning(np.flatnonzero(self._warnings[env])[0]).name
                self.physics_error[env] = f"{first} at {time}"
            else:
                self.physics_error[env] = f"non-finite state at {time}"

    # --- what the envs measure --------------------------------------------------------------
    def _measure(self) -> None:
        """Per env and ball: ``ball_positions``, ``ball_velocities``, ``ball_heights``,
        ``in_flight`` (no contact), the ball in the cup's frame (``radial``: off the cone's axis,
        ``height_in_cup``: above the throat; m), ``in_cup`` (inside the cone, below the rim) and
        ``_clear_of_cup`` (more than a ball radius outside the cone: a ball sloshing up to the
        rim is neither caught again nor counted as lost)."""
        self.ball_positions = self.qpos[:, self._ball_qpos_columns]  # [N, balls, 3]
        self.ball_velocities = self.qvel[:, self._ball_qvel_columns]
        self.ball_heights = self.ball_positions[:, :, 2]
        self.in_flight = self._sensors[:, self._contact_sensors] == 0
        offset = self.ball_positions - self.cup_position[:, None, :]
        # the offset in the cup's frame: its rotation matrix (row-major) transposed, times it
        local = np.matmul(offset, self._cup_rotation.reshape(-1, 3, 3))
        self.radial = np.hypot(local[..., 0], local[..., 1])
        self.height_in_cup = local[..., 2]
        self.in_cup = (
            (self.height_in_cup >= 0.0)
            & (self.height_in_cup <= scene.CUP_DEPTH)
            & (self.radial <= scene.CUP_TOP_RADIUS)
        )
        self._clear_of_cup = (self.height_in_cup > self._clear_depth) | (
            self.radial > self._clear_radius
        )

    @property
    def cup_velocity(self) -> np.ndarray:
        """``[N, 3]``: the cup's throat's linear velocity (m/s, world frame)."""
        return self._cup_twist[:, 3:]

    def ball_arm_contacts(self) -> np.ndarray:
        """``[N]``: contacts between the first ball and the arm (links and cup plates)."""
        counts = np.zeros(self.num_envs, dtype=np.int64)
        for env, data in enumerate(self.datas):
            contacts = data.contact
            geoms = np.stack([contacts.geom1, contacts.geom2], axis=1)
            with_ball = (geoms == self._ball_geom).any(axis=1)
            other = np.where(geoms[:, 0] == self._ball_geom, geoms[:, 1], geoms[:, 0])
            counts[env] = np.isin(other[with_ball], self._arm_geoms).sum()
        return counts

    def _observe(self, rows: slice | np.ndarray, first: bool) -> None:
        """The observations of the envs of ``rows`` into ``_observations``: the true state, the
        balls as their trackers see them where ``ball_noise`` or ``ball_latency`` is on."""
        qpos, qvel = self.qpos[rows], self.qvel[rows]
        observations = np.empty((len(qpos), self.single_observation_space.shape[0]))
        columns, sources = self._observed
        observations[:, columns] = qpos[:, sources]
        columns, sources = self._observed_velocity
        observations[:, columns] = qvel[:, sources]
        observations[:, 12:15] = self.cup_position[rows]
        observations[:, 15:18] = self._cup_twist[rows, 3:]
        tracked = self.tracker.active[rows]
        if tracked.any():
            envs = self._all_envs[rows][tracked]
            track = self.tracker.reset if first else self.tracker.observe
            seen = track(envs, self.ball_positions[envs], self.ball_velocities[envs], self.rngs)
            observations[np.flatnonzero(tracked)[:, None, None], self._ball_columns] = seen
        self._observations[rows] = observations

    def env_info(self, env: int) -> dict:
        """Env ``env``'s info as plain Python values (what ``JuggleEnv`` returns)."""
        events = self.events
        throws = events.throws[env].tolist()
        return {
            "throws": sum(throws),
            "throws_per_ball": tuple(throws),
            "catches": int(events.catches[env].sum()),
            "max_consecutive_catches": int(events.max_streak[env].max()),
            "ball_height": float(self.ball_heights[env, 0]),
            "ball_heights": tuple(self.ball_heights[env].tolist()),
            "in_cup": bool(self.in_cup[env, 0]),
            "peak_joint_speed": self.peak_joint_speed[env].copy(),
            "max_cup_height": float(self.max_cup_height[env]),
            "max_balls_in_cup": int(self.max_balls_in_cup[env]),
            "time": float(self.time[env]),
            "kicks": int(self.kicks[env]),
            "physics_error": self.physics_error[env],
        }

    def _info(self) -> dict[str, np.ndarray]:
        events = self.events
        return {
            "throws": events.throws.sum(axis=1),
            "throws_per_ball": events.throws.copy(),
            "catches": events.catches.sum(axis=1),
            "max_consecutive_catches": events.max_streak.max(axis=1),
            "ball_height": self.ball_heights[:, 0].copy(),
            "ball_heights": self.ball_heights.copy(),
            "in_cup": self.in_cup[:, 0].copy(),
            "peak_joint_speed": self.peak_joint_speed.copy(),
            "max_cup_height": self.max_cup_height.copy(),
            "max_balls_in_cup": self.max_balls_in_cup.copy(),
            "time": self.time.copy(),
            "kicks": self.kicks.copy(),
            "physics_error": self.physics_error.copy(),
        }

    # --- saving -----------------------------------------------------------------------------
    def state_dict(self) -> dict[str, Any]:
        """Everything a step reads: a batch that loads it continues bit for bit."""
        size = mujoco.mj_stateSize(self.models[0], PHYSICS_STATE)
        physics = np.zeros((self.num_envs, size))
        for env, (model, data) in enumerate(zip(self.models, self.datas, strict=True)):
            mujoco.mj_getState(model, data, physics[env], PHYSICS_STATE)
        warnings = np.array([views.warnings for views in self._views])
        records = ("steps", "kicks", "setpoint", "peak_joint_speed", "max_cup_height")
        return {
            "physics": physics,
            "warnings": warnings,
            "generators": [rng.bit_generator.state for rng in self.rngs],
            **{name: getattr(self, name).copy() for name in records},
            "max_balls_in_cup": self.max_balls_in_cup.copy(),
            "physics_error": self.physics_error.tolist(),
            "needs_reset": self.needs_reset.copy(),
            "terminated": self.terminated.copy(),
            "truncated": self.truncated.copy(),
            "observations": self._observations.copy(),
            "events": self.events.state_dict(),
            "action_noise": self.action_noise.state_dict(),
            "tracker": self.tracker.state_dict(),
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Continue from ``state_dict()`` of a batch of the same arguments."""
        if len(state["physics"]) != self.num_envs:
            raise ValueError(
                f"a saved batch of {len(state['physics'])} envs cannot load into {self.num_envs}"
            )
        for env, (model, data) in enumerate(zip(self.models, self.datas, strict=True)):
            mujoco.mj_setState(model, data, state["physics"][env], PHYSICS_STATE)
            self._views[env].warnings[:] = state["warnings"][env]
            mujoco.mj_forward(model, data)
            self._read(env)
            self.rngs[env].bit_generator.state = state["generators"][env]
        for name in ("steps", "kicks", "setpoint", "peak_joint_speed", "max_cup_height"):
            getattr(self, name)[:] = state[name]
        self.max_balls_in_cup[:] = state["max_balls_in_cup"]
        self.physics_error[:] = state["physics_error"]
        self.needs_reset[:] = state["needs_reset"]
        self.terminated[:] = state["terminated"]
        self.truncated[:] = state["truncated"]
        self._started = True
        self._observations[:] = state["observations"]
        self.events.load_state_dict(state["events"])
        self.action_noise.load_state_dict(state["action_noise"])
        self.tracker.load_state_dict(state["tracker"])
        self._measure()


class _DataViews:
    """The arrays of one ``MjData`` a step reads and writes, looked up once."""

    def __init__(self, data: mujoco.MjData, cup_site: int):
        self.ctrl = data.ctrl
        self.qpos = data.qpos
        self.qvel = data.qvel
        self.sensors = data.sensordata
        self.warnings = data.warning.number
        self.cup_position = data.site_xpos[cup_site]
        self.cup_rotation = data.site_xmat[cup_site]


def _has_ancestor(model: mujoco.MjModel, body: int, ancestor: int) -> bool:
    while body != ancestor and body != 0:
        body = model.body_parentid[body]
    return body == ancestor
