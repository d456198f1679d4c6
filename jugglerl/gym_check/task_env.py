"""``make_task_env``: N copies of a Gymnasium env as one TorchRL env, as the juggling env's
conventions have it, and ``evaluate_actor``, its deterministic episodes.

Actions are in [-1, 1], clipped there (a Gaussian samples beyond) and rescaled to the task's
bounds; the observation is copied to ``state``, cast to float32 and standardised (the
normalisation: 0 and 1 until a check fits it); a fall is ``terminated``, the time limit
``truncated`` (value targets bootstrap through it); ``episode_reward`` sums each episode's
rewards, ``step_count`` and ``is_init`` are as in the juggling stack.
"""

from __future__ import annotations

from functools import partial

import gymnasium as gym
import numpy as np
import torch
from torchrl.envs import (
    DoubleToFloat,
    EnvBase,
    GymWrapper,
    InitTracker,
    ObservationNorm,
    RenameTransform,
    RewardSum,
    StepCounter,
    TransformedEnv,
)
from torchrl.envs.utils import ExplorationType, set_exploration_type

from jugglerl.batch.env_stack import normalisation


class ClipToBounds(gym.ActionWrapper):
    """Clips actions to the action space, which it keeps (Gymnasium's ``ClipAction`` declares an
    unbounded one)."""

    def action(self, action):
        return np.clip(action, self.action_space.low, self.action_space.high)


def _normalised_actions(task_id: str) -> gym.Env:
    env = gym.make(task_id)
    if not isinstance(env.action_space, gym.spaces.Box):
        env.close()
        raise ValueError(f"task.id={task_id}: the actors act on continuous (Box) action spaces")
    ones = np.ones(env.action_space.shape, dtype=np.float32)
    return ClipToBounds(gym.wrappers.RescaleAction(env, -ones, ones))


def make_task_env(
    task_id: str, num_envs: int, loc: torch.Tensor | None = None, scale: torch.Tensor | None = None
) -> EnvBase:
    """``num_envs`` copies of the Gymnasium env ``task_id`` as one TorchRL env of
    ``batch_size=[num_envs]`` (see the module docstring), standardised by ``loc``/``scale``."""
    try:
        gym.spec(task_id)
    except gym.error.Error as error:
        raise ValueError(f"task.id={task_id}: {error}") from None
    makers = [partial(_normalised_actions, task_id)] * num_envs
    vector = gym.vector.SyncVectorEnv(makers, autoreset_mode=gym.vector.AutoresetMode.DISABLED)
    env = TransformedEnv(GymWrapper(vector))
    size = env.observation_spec["observation"].shape[-1]
    env.append_transform(RenameTransform(["observation"], ["state"], create_copy=True))
    env.append_transform(DoubleToFloat(in_keys=["state"]))
    for transform in (StepCounter(), InitTracker(), RewardSum()):
        env.append_transform(transform)
    loc = torch.zeros(size) if loc is None else loc
    scale = torch.ones(size) if scale is None else scale
    norm = ObservationNorm(
        loc=loc.clone(), scale=scale.clone(), in_keys=["state"], standard_normal=True
    )
    env.append_transform(norm)
    return env


def evaluate_actor(env: EnvBase, task_id: str, actor, episodes: int, seed: int) -> float:
    """The mean return of ``actor`` acting deterministically over ``episodes`` new episodes of
    ``task_id`` (env seeds ``seed`` on), each to its end, standardised as ``env`` is."""
    norm = normalisation(env)
    episodes_env = make_task_env(task_id, episodes, norm.loc, norm.scale)
    episodes_env.set_seed(seed)
    limit = gym.spec(task_id).max_episode_steps or 1000
    try:
        with torch.no_grad(), set_exploration_type(ExplorationType.DETERMINISTIC):
            rollout = episodes_env.rollout(limit, actor, break_when_any_done=False)
    finally:
        episodes_env.close()
    rewards = rollout["next", "reward"].squeeze(-1)
    return float(first_episode_returns(rewards, rollout["next", "done"].squeeze(-1)).mean())


def first_episode_returns(rewards: torch.Tensor, done: torch.Tensor) -> torch.Tensor:
    """Each env's return up to its first ``done`` (``[envs, steps]`` rewards and ends; a roll-out
    goes on into new episodes after it)."""
    before_end = (done.long().cumsum(dim=1) - done.long()) == 0
    return (rewards * before_end).sum(dim=1)
