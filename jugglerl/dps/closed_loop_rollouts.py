"""``ClosedLoopRollouts``: the candidates of a closed-loop search, rolled out as policies.

A closed-loop candidate (a feedback policy's command and gains, a throw-and-catch policy's
parameters) needs Python every env step, so each is built into a ``Policy`` by the search space
and run as episodes on an ``EpisodePool`` (worker processes, or Ray tasks): once under each of
``conditions`` (env overrides: nominal, perturbed). Its return is its throws summed over the
conditions, so the search prefers candidates that juggle in all of them.

``limits`` keeps the throws honest: an episode in which the cup's throat rose above
``max_cup_height`` (m), a joint turned faster than ``max_joint_speed`` (rad/s) or more than
``max_balls_in_cup`` balls sat in the cup at once scores no throws, so a search cannot buy
throws by lifting the cup, by outrunning the arm or, the balls passing through each other in
the scene, by juggling two as one.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import gymnasium as gym
import numpy as np
from omegaconf import DictConfig, OmegaConf

from jugglerl.cluster.episode_pool import EpisodePool, EpisodeTask
from jugglerl.config.envs import make_juggle_env
from jugglerl.dps.rollouts import RolloutResults
from jugglerl.policies import Policy
from jugglerl.policies.episodes import EpisodeMetrics

LIMIT_KEYS = ("max_cup_height", "max_joint_speed", "max_balls_in_cup")


def within_limits(metrics: EpisodeMetrics, limits: Mapping[str, float | None]) -> bool:
    """Whether an episode kept the cup, the joints and the balls in the cup within ``limits``
    (``None``: no limit)."""
    cup, speed, shared = (limits.get(key) for key in LIMIT_KEYS)
    if cup is not None and metrics.max_cup_height > cup:
        return False
    if shared is not None and metrics.max_balls_in_cup > shared:
        return False
    return speed is None or max(metrics.peak_joint_speed, default=0.0) <= speed


class ClosedLoopRollouts:
    """Rolls closed-loop candidates out under each of ``conditions``.

    ``build(candidate, env)`` makes the policy of one candidate for envs like ``env``.
    ``evaluate(candidates, seeds)`` gives, per candidate, the throws summed over the conditions
    (none from an episode outside ``limits``) and the earliest drop (NaN when none dropped);
    episode ``k`` of candidate ``i`` uses reset seed ``seeds[i] + k``.
    """

    def __init__(
        self,
        env_cfg: DictConfig,
        conditions: list[dict],
        workers: int,
        build: Callable[[object, gym.Env], Policy],
        cluster: DictConfig | None = None,
        limits: Mapping[str, float | None] | None = None,
    ):
        base = OmegaConf.to_container(env_cfg, resolve=True)
        self.envs = [{**base, **condition} for condition in conditions]
        self.templates = [make_juggle_env(OmegaConf.create(env)) for env in self.envs]
        self.build = build
        self.limits = dict(limits or {})
        unknown = set(self.limits) - set(LIMIT_KEYS)
        if unknown:
            raise ValueError(f"limits: unknown {sorted(unknown)}; use {', '.join(LIMIT_KEYS)}")
        self._pool = EpisodePool(workers, cluster)

    def evaluate(self, candidates: list, seeds: list[int]) -> RolloutResults:
        tasks = [
            EpisodeTask(env, self.build(candidate, template), seed + k)
            for candidate, seed in zip(candidates, seeds, strict=True)
            for k, (env, template) in enumerate(zip(self.envs, self.templates, strict=True))
        ]
        episodes = self._pool.run(tasks)
        throws = np.array(
            [m.throws if within_limits(m, self.limits) else 0 for m in episodes]
        ).reshape(len(candidates), len(self.envs))
        drops = np.array(
            [np.nan if m.time_to_drop is None else m.time_to_drop for m in episodes]
        ).reshape(throws.shape)
        return RolloutResults(throws.sum(axis=1), np.fmin.reduce(drops, axis=1))

    def close(self) -> None:
        self._pool.close()
        for env in self.templates:
            env.close()

    def __enter__(self) -> ClosedLoopRollouts:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()
