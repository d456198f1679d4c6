"""PPO on a standard Gymnasium task: the check that tells a bug in the learner from a hard task.

``GymCheck(cfg)`` trains with what the juggling trainer (``jugglerl.onpolicy.training``) learns
with, on ``collector.num_envs`` copies of the Gymnasium env ``task.id`` (e.g. ``HalfCheetah-v5``
of ``gymnasium[mujoco]``): the Gaussian policy around an actor and the critic
(``jugglerl.onpolicy.agent``), the update (``jugglerl.onpolicy.update.PPOUpdate``), the collector
that carries episodes across batches (``jugglerl.batch.collector``) and the normalisation fitted
on the untrained policy's roll-outs (``jugglerl.batch.env_stack``). What it leaves out is the
juggling env, its time features and its evaluations. Its returns are compared with those CleanRL
publishes for the same frame budget (``scripts/benchmarks/gym_check.py``,
docs/results/gym_check.md).

The env, as the juggling env's conventions have it: actions in [-1, 1], clipped there (the
Gaussian samples beyond) and rescaled to the task's bounds; the observation copied to ``state``,
cast to float32 and standardised; a fall ``terminated``, the time limit ``truncated`` (GAE
bootstraps through it); ``episode_reward`` sums each episode's rewards.
"""

from __future__ import annotations

import time
from collections import deque
from functools import partial

import gymnasium as gym
import numpy as np
import torch
from omegaconf import DictConfig
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
from tqdm import tqdm

from jugglerl.batch.collector import BatchCollector
from jugglerl.batch.env_stack import fit_normalisation_on, normalisation
from jugglerl.onpolicy.agent import make_agent, policy_sigma
from jugglerl.onpolicy.update import PPOUpdate
from jugglerl_envs.batch import usable_cores

#: Training episodes the final training return averages (CleanRL's curves: returns at the end).
RECENT_EPISODES = 20


def make_task_env(
    task_id: str, num_envs: int, loc: torch.Tensor | None = None, scale: torch.Tensor | None = None
) -> EnvBase:
    """``num_envs`` copies of the Gymnasium env ``task_id`` as one TorchRL env of
    ``batch_size=[num_envs]`` (see the module docstring); the normalisation ``loc``/``scale``
    (default: none, 0 and 1, until it is fitted)."""
    try:
        spec = gym.spec(task_id)
    except gym.error.Error as error:
        raise ValueError(f"task.id={task_id}: {error}") from None
    if not isinstance(gym.make(spec).action_space, gym.spaces.Box):
        raise ValueError(f"task.id={task_id}: the actors act on continuous (Box) action spaces")
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


class ClipToBounds(gym.ActionWrapper):
    """Clips actions to the action space, which it keeps (Gymnasium's ``ClipAction`` declares an
    unbounded one)."""

    def action(self, action):
        return np.clip(action, self.action_space.low, self.action_space.high)


def _normalised_actions(task_id: str) -> gym.Env:
    env = gym.make(task_id)
    ones = np.ones(env.action_space.shape, dtype=np.float32)
    return ClipToBounds(gym.wrappers.RescaleAction(env, -ones, ones))


class GymCheck:
    """One PPO run on ``cfg.task.id``; ``run()`` trains to ``collector.total_frames`` and
    returns its record."""

    def __init__(self, cfg: DictConfig):
        collect = cfg.collector
        batch, envs = collect.frames_per_batch, collect.num_envs
        if envs < 1 or batch % envs or not 0 < batch <= collect.total_frames:
            raise ValueError(
                f"collector.frames_per_batch={batch} must be a multiple of collector.num_envs="
                f"{envs} and at most collector.total_frames={collect.total_frames}"
            )
        self.cfg = cfg
        torch.manual_seed(cfg.seed)
        self.env = make_task_env(cfg.task.id, collect.num_envs)
        state_size = self.env.observation_spec["state"].shape[-1]
        self.agent = make_agent(cfg, state_size, self.env.action_spec.shape[-1])
        self.update = PPOUpdate(self.agent, cfg.algo, cfg.optim)
        self.env.set_seed(cfg.seed)
        fit_normalisation_on(
            self.env, self.agent.policy, cfg.norm_frames, None, ExplorationType.RANDOM
        )
        self.collector = BatchCollector(self.env)
        self.collector.restart(cfg.seed)

    def run(self, progress: bool = True) -> dict:
        """Train; the returns of the training episodes (``curve``: frames at each episode's end
        and its return), the mean of the last ``RECENT_EPISODES``, the deterministic policy's
        mean return over ``eval_episodes`` new episodes, and the wall seconds."""
        collect = self.cfg.collector
        steps = collect.frames_per_batch // collect.num_envs
        frames, curve = 0, []
        recent: deque[float] = deque(maxlen=RECENT_EPISODES)
        started = time.monotonic()
        with tqdm(total=collect.total_frames, unit="frame", disable=not progress) as bar:
            while frames + collect.frames_per_batch <= collect.total_frames:
                torch.set_num_threads(1)
                batch = self.collector.collect(self.agent.policy, steps)
                frames += batch.numel()
                ended = batch["next", "done"].squeeze(-1)
                returns = batch["next", "episode_reward"][ended].reshape(-1).tolist()
                curve += [(frames, r) for r in returns]
                recent.extend(returns)
                torch.set_num_threads(usable_cores())
                self.update(batch, (frames - batch.numel()) / collect.total_frames)
                bar.update(batch.numel())
                if recent:
                    bar.set_postfix(
                        {"return": f"{np.mean(recent):.1f}", "sigma": f"{self._sigma():.3g}"}
                    )
        wall = time.monotonic() - started
        return {
            "task": self.cfg.task.id,
            "seed": self.cfg.seed,
            "frames": frames,
            "wall_seconds": round(wall, 1),
            "train_return": float(np.mean(recent)) if recent else float("nan"),
            "eval_return": self.evaluate(self.cfg.eval_episodes),
            "curve": curve,
        }

    def _sigma(self) -> float:
        return float(policy_sigma(self.agent).mean())

    def evaluate(self, episodes: int) -> float:
        """The deterministic actor's mean return over ``episodes`` episodes of new envs (seeds
        ``10_000 + seed`` on), each to its end."""
        norm = normalisation(self.env)
        env = make_task_env(self.cfg.task.id, episodes, norm.loc, norm.scale)
        env.set_seed(10_000 + self.cfg.seed)
        limit = gym.spec(self.cfg.task.id).max_episode_steps or 1000
        try:
            with torch.no_grad(), set_exploration_type(ExplorationType.DETERMINISTIC):
                rollout = env.rollout(limit, self.agent.actor, break_when_any_done=False)
        finally:
            env.close()
        done = rollout["next", "done"].squeeze(-1)
        return float(first_episode_returns(rollout["next", "reward"].squeeze(-1), done).mean())

    def close(self) -> None:
        self.env.close()


def first_episode_returns(rewards: torch.Tensor, done: torch.Tensor) -> torch.Tensor:
    """Each env's return up to its first ``done`` (``[envs, steps]`` rewards and ends; a roll-out
    goes on into new episodes after it)."""
    before_end = (done.long().cumsum(dim=1) - done.long()) == 0
    return (rewards * before_end).sum(dim=1)
