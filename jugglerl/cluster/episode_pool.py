"""``EpisodePool``: episodes of closed-loop policies on a cluster's workers, results in order.

A closed-loop episode steps Python every env step, so batches of them (the feedback search's
roll-outs, the robustness benchmark) run one per worker: processes of this machine, or Ray tasks
(``jugglerl.cluster``). A task names the env (keyword arguments of ``JuggleEnv``), the policy (a
``Policy`` object, pickled to the worker, or a ``policy=`` spec that each worker loads once and
keeps) and the reset seed.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from omegaconf import DictConfig

from jugglerl.cluster import open_cluster
from jugglerl.evaluation import EpisodeMetrics, run_episode
from jugglerl.policies import Policy
from jugglerl_envs import JuggleEnv


@dataclass(frozen=True)
class EpisodeTask:
    """One episode: ``JuggleEnv(**env)``, ``policy`` (an object or a spec) and the reset seed."""

    env: dict
    policy: Policy | str
    seed: int


_worker_policies: dict[str, Policy] = {}


def run_task(task: EpisodeTask) -> EpisodeMetrics:
    """Run one task here (what a worker does)."""
    from jugglerl.policies.loading import load_policy

    env = JuggleEnv(**task.env)
    policy = task.policy
    if isinstance(policy, str):  # perturbations leave what a policy reads of the env unchanged
        if policy not in _worker_policies:
            _worker_policies[policy] = load_policy(policy, env)
        policy = _worker_policies[policy]
    metrics = run_episode(env, policy, seed=task.seed)
    env.close()
    return metrics


def run_tasks(tasks: list[EpisodeTask]) -> list[EpisodeMetrics]:
    """A chunk of tasks, one after the other (what a cluster's worker is handed)."""
    return [run_task(task) for task in tasks]


class EpisodePool:
    """Runs ``EpisodeTask``s on the cluster of ``cluster`` (``None``: this machine) with
    ``workers`` local processes (0: one per core)."""

    def __init__(self, workers: int = 0, cluster: DictConfig | None = None):
        self._cluster = open_cluster(cluster, workers)

    def run(
        self,
        tasks: Sequence[EpisodeTask],
        on_episode: Callable[[EpisodeMetrics], None] | None = None,
    ) -> list[EpisodeMetrics]:
        """The tasks' metrics in the order of ``tasks``; ``on_episode`` sees each as it ends."""
        results = []
        for metrics in self._cluster.map(run_tasks, tasks):
            results.append(metrics)
            if on_episode is not None:
                on_episode(metrics)
        return results

    def close(self) -> None:
        self._cluster.close()

    def __enter__(self) -> EpisodePool:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()
