"""Evaluate batches of open-loop commands at raw physics speed, counting throws as the env does.

An open-loop command needs no Python per physics step: its servo setpoints are a function of time
alone. So the whole control sequence of an episode is computed up front, exactly as ``JuggleEnv``
would apply it (the same float32 action round trip, the same setpoint-rate limit, the same
accumulated ``data.time``), and ``mujoco.rollout`` steps the batch in C on several threads.

The ball is then sampled every ``frame_skip`` physics steps, as the env samples it, and throws
are counted with the env's own definition (``jugglerl_envs.events.count_throws``) up to the first
sample below the drop height, where the env would terminate. Same start state, same controls,
same solver warm start: the counts equal the env's (tested). Not replicated: the env's stop on a
MuJoCo warning (a roll-out stops counting only on a non-finite state).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from mujoco import rollout

from jugglerl.commands import ViaPointCommand
from jugglerl_envs import scene
from jugglerl_envs.events import count_throws
from jugglerl_envs.juggle import DROP_HEIGHT, JuggleEnv

STATE_SPEC = mujoco.mjtState.mjSTATE_FULLPHYSICS
#: Roll-outs per ``mujoco.rollout`` call: bounds the state buffer (a 120 s roll-out's states
#: take 12.5 MB) while giving every thread several trajectories.
MAX_BATCH = 16


@dataclass
class RolloutResults:
    """Per command: ``throws`` (int array) and ``time_to_drop`` (s; NaN when never dropped)."""

    throws: np.ndarray
    time_to_drop: np.ndarray


def seeds_per_command(seeds: Sequence[int | None] | int | None, count: int) -> list[int | None]:
    """One reset seed per command: ``seeds`` as given, or one seed (or ``None``) for all."""
    if not isinstance(seeds, Sequence):
        return [seeds] * count
    if len(seeds) != count:
        raise ValueError(f"{len(seeds)} seeds for {count} commands")
    return list(seeds)


class CommandRollouts:
    """Rolls out open-loop commands on the scene of ``env`` (its model, start state and limits).

    ``env`` is a ``JuggleEnv`` (unwrapped or not); its ``duration`` sets the roll-out length.
    ``nthread``: worker threads of ``mujoco.rollout`` (default: all cores). Close the pool with
    ``close()`` or use the object as a context manager.
    """

    def __init__(self, env: JuggleEnv, nthread: int | None = None):
        self.env = env.unwrapped
        if self.env.wrist_1_actuated:
            raise ValueError(
                "env.wrist_1_actuated: open-loop commands drive the three paper actuators; set"
                " it to false for DPS"
            )
        if self.env.kicks_ball:
            raise ValueError(
                "env.kick_rate/kick_speed: DPS roll-outs run open loop in C and cannot kick the"
                " ball; set them to 0 for DPS (evaluate kicks with scripts/robustness.py)"
            )
        self.nthread = nthread or os.cpu_count() or 1
        self.frame_skip = self.env.frame_skip
        self.n_env_steps = max(1, round(self.env.duration / self.env.dt))
        self._env_step_times = self._times_before_each_env_step()
        self._datas = [mujoco.MjData(self.env.model) for _ in range(self.nthread)]
        self._pool = rollout.Rollout(nthread=self.nthread)
        model = self.env.model
        ball_qpos = model.jnt_qposadr[model.body(scene.BALL_BODY).jntadr[0]]
        self._ball_z = 1 + ball_qpos + 2  # the state is (time, qpos, qvel, ...)
        self._contact = model.sensor_adr[model.sensor(scene.BALL_CONTACT_SENSOR).id]

    def _times_before_each_env_step(self) -> np.ndarray:
        """``data.time`` when each env step starts, summed physics step by physics step as MuJoCo
        does (a product ``k * dt`` differs in the last bits, and the commands are chaotic)."""
        steps = self.n_env_steps * self.frame_skip
        timestep = self.env.model.opt.timestep
        physics_times = np.concatenate([[0.0], np.cumsum(np.full(steps - 1, timestep))])
        return physics_times[:: self.frame_skip]

    # --- controls -------------------------------------------------------------------------
    def controls(self, commands: Sequence[ViaPointCommand]) -> np.ndarray:
        """The ``[command, physics step, nu]`` controls the env would apply for each command."""
        env = self.env
        # the policy hands the env a float32 action; the env maps it back to radians
        targets = np.stack(
            [
                env.action_to_ctrl(env.ctrl_to_action(command.setpoints(self._env_step_times)))
                for command in commands
            ]
        )
        targets = np.repeat(targets, self.frame_skip, axis=1)
        arm = targets if env.joint_speed_limit is None else self._rate_limited(targets)
        wrists = np.broadcast_to(env.wrist_angles, arm.shape[:2] + env.wrist_angles.shape)
        return np.concatenate([arm, wrists], axis=2)

    def _rate_limited(self, targets: np.ndarray) -> np.ndarray:
        """The env's setpoint-rate limit, physics step by physics step, from the home pose."""
        max_change = self.env.joint_speed_limit * self.env.model.opt.timestep
        setpoint = np.tile(np.asarray(self.env.home, dtype=np.float64), (len(targets), 1))
        limited = np.empty_like(targets)
        for step in range(targets.shape[1]):
            setpoint += np.clip(targets[:, step] - setpoint, -max_change, max_change)
            limited[:, step] = setpoint
        return limited

    # --- roll-outs ------------------------------------------------------------------------
    def start_state(self, seed: int | None) -> tuple[np.ndarray, np.ndarray]:
        """(full physics state, solver warm start) right after ``env.reset(seed=seed)``."""
        env = self.env
        env.reset(seed=seed)
        state = np.empty(mujoco.mj_stateSize(env.model, STATE_SPEC))
        mujoco.mj_getState(env.model, env.data, state, STATE_SPEC)
        return state, env.data.qacc_warmstart.copy()

    def evaluate(
        self, commands: Sequence[ViaPointCommand], seeds: Sequence[int | None] | int | None = 0
    ) -> RolloutResults:
        """Throws and drop times of each command, from the env's start state for its seed."""
        seeds = seeds_per_command(seeds, len(commands))
        throws = np.zeros(len(commands), dtype=int)
        time_to_drop = np.full(len(commands), np.nan)
        for first in range(0, len(commands), MAX_BATCH):
            batch = slice(first, first + MAX_BATCH)
            starts = [self.start_state(seed) for seed in seeds[batch]]
            states, sensors = self._pool.rollout(
                [self.env.model] * len(starts),
                self._datas,
                initial_state=np.stack([state for state, _ in starts]),
                control=self.controls(commands[batch]),
                initial_warmstart=np.stack([warm for _, warm in starts]),
            )
            initial_heights = np.array([state[self._ball_z] for state, _ in starts])
            throws[batch], time_to_drop[batch] = self._score(initial_heights, states, sensors)
        return RolloutResults(throws, time_to_drop)

    def _score(self, initial_heights, states, sensors) -> tuple[np.ndarray, np.ndarray]:
        """Throws and drop times from the states after each env step, as the env samples them."""
        at_env_steps = slice(self.frame_skip - 1, None, self.frame_skip)
        heights = np.concatenate(
            [initial_heights[:, None], states[:, at_env_steps, self._ball_z]], axis=1
        )
        in_flight = np.concatenate(
            [np.ones((len(heights), 1), bool), sensors[:, at_env_steps, self._contact] == 0], axis=1
        )
        ended = (heights < DROP_HEIGHT) | ~np.isfinite(heights)
        ended[:, 0] = False
        dropped = ended.any(axis=1)
        last = np.where(dropped, ended.argmax(axis=1), heights.shape[1] - 1)
        counted = np.arange(heights.shape[1]) <= last[:, None]
        # a crossing completes at its later sample: masking that sample's flag drops it
        throws = count_throws(heights, in_flight & counted, self.env.threshold)
        time_to_drop = np.where(dropped, last * self.env.dt, np.nan)
        return throws, time_to_drop

    def close(self) -> None:
        self._pool.close()

    def __enter__(self) -> CommandRollouts:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()
