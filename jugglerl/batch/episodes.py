"""``run_episodes``: one episode in each env of a ``JuggleBatch``, all stepped together.

A policy acts on the whole batch at once when it can (``acts_on_batches``: a network, one
forward pass per step for every env); any other ``Policy`` (a command, ``FeedbackPolicy``,
``ThrowCatchPolicy``) acts env by env, a copy of it on each row (``RowPolicies``). An env whose
episode ended waits for the others (``JuggleBatch`` spends no physics on it), its actor no more
asked. Each episode is the same as alone in a ``JuggleEnv`` reset with its seed, bit for bit for
the per-row policies; a network's actions can differ in the last bits with the number of rows it
is run on (matrix products of other shapes round differently), so compare networks on batches of
the same composition.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Sequence
from typing import Protocol

import numpy as np

from jugglerl.policies import Policy
from jugglerl.policies.episodes import EpisodeMetrics, episode_metrics
from jugglerl_envs import JuggleBatch
from jugglerl_envs.settings import ARGUMENTS


class BatchPolicy(Protocol):
    """Acts for every env of a batch: ``act(observations [N, obs], times [N], running [N])``
    gives ``[N, act]`` (the rows of envs not ``running`` are ignored)."""

    def reset(self) -> None: ...

    def act(self, observations: np.ndarray, times: np.ndarray, running: np.ndarray): ...


class RowPolicies:
    """One copy of a single-env ``policy`` per env, each acting on its own row."""

    def __init__(self, policies: Sequence[Policy]):
        self.policies = list(policies)

    def reset(self) -> None:
        for policy in self.policies:
            policy.reset()

    def act(self, observations: np.ndarray, times: np.ndarray, running: np.ndarray) -> np.ndarray:
        actions = None
        for env in np.flatnonzero(running).tolist():
            action = self.policies[env].act(observations[env], float(times[env]))
            if actions is None:
                actions = np.zeros((len(observations), len(action)))
            actions[env] = action
        return actions


def batch_policy(policy: Policy, num_envs: int) -> BatchPolicy:
    """``policy`` acting on a batch of ``num_envs``: itself if it ``acts_on_batches``, else a
    copy of it per env."""
    if getattr(policy, "acts_on_batches", False):
        return policy
    return RowPolicies([copy.deepcopy(policy) for _ in range(num_envs)])


def per_env_arguments(envs: Sequence[dict]) -> dict[str, list]:
    """``JuggleBatch`` arguments from one ``JuggleEnv`` argument dict per env."""
    keys = dict.fromkeys(key for env in envs for key in env)
    return {key: [env.get(key, ARGUMENTS[key].default) for env in envs] for key in keys}


def run_episodes(
    batch: JuggleBatch,
    policy: BatchPolicy,
    seeds: Sequence[int],
    on_step: Callable[[np.ndarray], None] | None = None,
) -> list[EpisodeMetrics]:
    """One episode per env of ``batch`` (made with ``autoreset=False``), env ``i`` reset with
    ``seeds[i]``; their metrics in env order. ``on_step(moved)``, if given, runs after the reset
    and after each step, ``moved`` saying which envs it moved (a recorder follows an env with
    it: ``jugglerl.recording.episode.BatchEnvRecorder``)."""
    observations, info = batch.reset(seed=list(seeds))
    policy.reset()
    running = np.ones(batch.num_envs, dtype=bool)
    metrics: list[EpisodeMetrics | None] = [None] * batch.num_envs
    if on_step is not None:
        on_step(running.copy())
    while running.any():
        actions = policy.act(observations, info["time"], running)
        observations, _, terminated, truncated, info = batch.step(actions)
        if on_step is not None:
            on_step(running.copy())
        for env in np.flatnonzero(running & (terminated | truncated)).tolist():
            metrics[env] = episode_metrics(batch.env_info(env), terminated[env], seeds[env])
            running[env] = False
    return metrics
