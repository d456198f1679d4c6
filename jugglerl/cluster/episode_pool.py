"""``EpisodePool``: episodes of policies on a cluster's workers, results in order.

A task names the env (keyword arguments of ``JuggleEnv``), the policy (a ``Policy`` object,
pickled to the worker, or a ``policy=`` spec that each worker loads once and keeps) and the reset
seed. Consecutive tasks of the same policy run together as one ``JuggleBatch`` of up to
``batch_size`` envs (``jugglerl.batch.episodes``: a network acts on all its envs in one forward
pass), one batch per worker at a time: processes of this machine, or Ray tasks
(``jugglerl.cluster``). Which tasks share a batch depends on the tasks alone, not on the workers,
so a run gives the same episodes wherever it runs. Users: the closed-loop searches' roll-outs and
the robustness benchmark.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from omegaconf import DictConfig

from jugglerl.batch.episodes import batch_policy, per_env_arguments, run_episodes
from jugglerl.cluster import open_cluster
from jugglerl.policies import Policy
from jugglerl.policies.episodes import EpisodeMetrics
from jugglerl_envs import JuggleBatch, JuggleEnv

#: Most episodes run as one batch.
BATCH_SIZE = 32


@dataclass(frozen=True)
class EpisodeTask:
    """One episode: ``JuggleEnv(**env)``, ``policy`` (an object or a spec) and the reset seed."""

    env: dict
    policy: Policy | str
    seed: int


_worker_policies: dict[str, Policy] = {}


def run_batch(tasks: list[EpisodeTask]) -> list[EpisodeMetrics]:
    """Tasks of one policy as one batch, here (what a worker does); one thread, as the workers
    are the parallelism."""
    from jugglerl.policies.loading import load_policy

    policy = tasks[0].policy
    if isinstance(policy, str):  # perturbations leave what a policy reads of the env unchanged
        if policy not in _worker_policies:
            template = JuggleEnv(**tasks[0].env)
            _worker_policies[policy] = load_policy(policy, template)
            template.close()
        policy = _worker_policies[policy]
    arguments = per_env_arguments([task.env for task in tasks])
    batch = JuggleBatch(len(tasks), threads=1, autoreset=False, **arguments)
    metrics = run_episodes(batch, batch_policy(policy, len(tasks)), [t.seed for t in tasks])
    batch.close()
    return metrics


def run_batches(batches: list[list[EpisodeTask]]) -> list[list[EpisodeMetrics]]:
    """Batches one after the other (what a cluster's worker is handed)."""
    return [run_batch(tasks) for tasks in batches]


def batches(tasks: Sequence[EpisodeTask], size: int) -> list[list[EpisodeTask]]:
    """``tasks`` cut into runs of the same policy (an equal spec, or the same object), each of
    at most ``size``."""
    found: list[list[EpisodeTask]] = []
    for task in tasks:
        last = found[-1] if found else None
        if last and len(last) < size and _same(last[0].policy, task.policy):
            last.append(task)
        else:
            found.append([task])
    return found


def _same(a: Policy | str, b: Policy | str) -> bool:
    return a == b if isinstance(a, str) and isinstance(b, str) else a is b


class EpisodePool:
    """Runs ``EpisodeTask``s on the cluster of ``cluster`` (``None``: this machine) with
    ``workers`` local processes (0: one per core), ``batch_size`` episodes per batch."""

    def __init__(
        self, workers: int = 0, cluster: DictConfig | None = None, batch_size: int = BATCH_SIZE
    ):
        self._cluster = open_cluster(cluster, workers)
        self.batch_size = batch_size

    def run(
        self,
        tasks: Sequence[EpisodeTask],
        on_episode: Callable[[EpisodeMetrics], None] | None = None,
    ) -> list[EpisodeMetrics]:
        """The tasks' metrics in the order of ``tasks``; ``on_episode`` sees each as its batch
        ends."""
        results = []
        for batch in self._cluster.map(run_batches, batches(tasks, self.batch_size)):
            for metrics in batch:
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
