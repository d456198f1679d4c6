"""``cluster=local`` (the default): worker processes of this machine, one item per call."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import torch
from omegaconf import DictConfig

from jugglerl.cluster import CLUSTERS


def _start_worker() -> None:
    torch.set_num_threads(1)  # one thread per worker: the workers are the parallelism


@CLUSTERS.register("local")
class LocalCluster:
    """``workers`` processes (0: one per core)."""

    distributed = False

    def __init__(self, cfg: DictConfig | None, workers: int = 0):
        self.workers = workers or os.cpu_count() or 1
        self._pool = ProcessPoolExecutor(self.workers, initializer=_start_worker)

    def map(self, fn: Callable[[list], list], items: Sequence[Any]) -> Iterator[Any]:
        for results in self._pool.map(fn, [[item] for item in items], chunksize=1):
            yield from results

    def close(self) -> None:
        self._pool.shutdown()
