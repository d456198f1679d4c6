"""``ClusterCommandRollouts``: ``CommandRollouts`` spread over a distributed cluster's tasks.

On ``cluster=ray`` the open-loop roll-outs of DPS go out one command per item (chunked by
``cluster.chunk``); each worker process builds the env and its ``CommandRollouts`` once per env
configuration and keeps them, with one ``mujoco.rollout`` thread per CPU its task holds. A
roll-out depends only on its command, its env and its seed, and the results come back in the
order asked, so a seeded search gives the same commands, to the last bit, as on one machine.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from functools import partial

import numpy as np

from jugglerl.cluster import Cluster
from jugglerl.commands import ViaPointCommand
from jugglerl.dps.rollouts import CommandRollouts, RolloutResults, seeds_per_command
from jugglerl_envs import JuggleEnv

_worker_rollouts: dict[str, CommandRollouts] = {}


def roll_out(env: dict, items: list[tuple[ViaPointCommand, int | None]]) -> list[tuple]:
    """(throws, time to drop) of each ``(command, reset seed)`` on ``JuggleEnv(**env)`` (what a
    worker does): the chunk in one batch, on the CPUs the task was given (Ray sets
    ``OMP_NUM_THREADS`` to them)."""
    key = repr(sorted(env.items()))
    if key not in _worker_rollouts:
        threads = int(os.environ.get("OMP_NUM_THREADS", "1"))
        _worker_rollouts[key] = CommandRollouts(JuggleEnv(**env), threads)
    commands, seeds = zip(*items, strict=True)
    batch = _worker_rollouts[key].evaluate(list(commands), list(seeds))
    return [(int(t), float(d)) for t, d in zip(batch.throws, batch.time_to_drop, strict=True)]


class ClusterCommandRollouts:
    """``evaluate(commands, seeds)`` as ``CommandRollouts`` gives it, on ``cluster``'s tasks;
    ``env`` is the keyword arguments of the roll-outs' ``JuggleEnv``."""

    def __init__(self, env: dict, cluster: Cluster):
        self.env = env
        self.cluster = cluster

    def evaluate(
        self, commands: Sequence[ViaPointCommand], seeds: Sequence[int | None] | int | None = 0
    ) -> RolloutResults:
        items = list(zip(commands, seeds_per_command(seeds, len(commands)), strict=True))
        results = list(self.cluster.map(partial(roll_out, self.env), items))
        throws = np.array([throws for throws, _ in results], dtype=int)
        return RolloutResults(throws, np.array([drop for _, drop in results]))

    def close(self) -> None:
        self.cluster.close()

    def __enter__(self) -> ClusterCommandRollouts:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()
