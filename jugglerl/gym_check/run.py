"""``TaskRun``: the loop the checks share: a batch of every env's steps under the exploring
policy, the learner's updates on it, the returns of the episodes that ended, a progress bar; at
the end the deterministic actor's episodes."""

from __future__ import annotations

import time
from collections import deque

import numpy as np
import torch
from omegaconf import DictConfig
from tensordict import TensorDict
from tqdm import tqdm

from jugglerl.batch.collector import BatchCollector
from jugglerl.batch.env_stack import check_batches
from jugglerl.gym_check.task_env import evaluate_actor, make_task_env

#: Training episodes the final training return averages (CleanRL's curves: returns at the end).
RECENT_EPISODES = 20
#: The evaluation episodes' env seeds start here plus the run's seed.
EVAL_SEEDS = 10_000


class TaskRun:
    """One run on ``cfg.task.id``; a subclass builds ``actor`` (what is evaluated) and says how
    it collects (``collect``) and learns (``learn``). ``run()`` trains to
    ``collector.total_frames`` and returns the run's record."""

    actor = None

    def __init__(self, cfg: DictConfig):
        check_batches(cfg.collector)
        self.cfg = cfg
        torch.manual_seed(cfg.seed)
        self.env = make_task_env(cfg.task.id, cfg.collector.num_envs)
        self.env.set_seed(cfg.seed)
        self.collector = BatchCollector(self.env)
        self.frames = 0

    @property
    def state_size(self) -> int:
        return self.env.observation_spec["state"].shape[-1]

    @property
    def action_size(self) -> int:
        return self.env.action_spec.shape[-1]

    def collect(self, steps: int) -> TensorDict:
        """``steps`` steps of every env under the exploring policy."""
        raise NotImplementedError

    def learn(self, batch: TensorDict) -> dict[str, float]:
        """The updates after ``batch``; what the progress bar shows of them."""
        raise NotImplementedError

    def run(self, progress: bool = True) -> dict:
        """Train; the returns of the training episodes (``curve``: frames at each episode's end
        and its return), the mean of the last ``RECENT_EPISODES``, the deterministic actor's
        mean return over ``eval_episodes`` new episodes, and the wall seconds."""
        collect = self.cfg.collector
        steps = collect.frames_per_batch // collect.num_envs
        curve: list[tuple[int, float]] = []
        recent: deque[float] = deque(maxlen=RECENT_EPISODES)
        self.collector.restart(self.cfg.seed)
        started = time.monotonic()
        with tqdm(total=collect.total_frames, unit="frame", disable=not progress) as bar:
            while self.frames + collect.frames_per_batch <= collect.total_frames:
                batch = self.collect(steps)
                self.frames += batch.numel()
                ended = batch["next", "done"].squeeze(-1)
                returns = batch["next", "episode_reward"][ended].reshape(-1).tolist()
                curve += [(self.frames, r) for r in returns]
                recent.extend(returns)
                shown = self.learn(batch)
                bar.update(batch.numel())
                if recent:
                    bar.set_postfix({"return": f"{np.mean(recent):.1f}", **shown})
        wall = time.monotonic() - started
        seed = EVAL_SEEDS + self.cfg.seed
        return {
            "task": self.cfg.task.id,
            "algo": self.cfg.algo.get("loss", self.cfg.algo.name),
            "seed": self.cfg.seed,
            "frames": self.frames,
            "wall_seconds": round(wall, 1),
            "train_return": float(np.mean(recent)) if recent else float("nan"),
            "eval_return": evaluate_actor(
                self.env, self.cfg.task.id, self.actor, self.cfg.eval_episodes, seed
            ),
            "curve": curve,
        }

    def close(self) -> None:
        self.env.close()
