"""Where the embarrassingly parallel work runs: this machine's processes, or a Ray cluster.

A cluster backend (``CLUSTERS``, chosen by ``cluster.name`` from ``configs/cluster/``) runs a
module-level function on chunks of picklable items and gives the results back in the order of
the items, so a seeded run is the same, to the last bit, wherever it runs:

| backend | where | chunks |
| --- | --- | --- |
| ``local`` (default) | ``workers`` processes of this machine | one item each |
| ``ray`` (``ray_tasks.py``) | Ray tasks at ``cluster.address`` | ``cluster.chunk`` items each |

Its users: the closed-loop episodes of ``episode_pool`` (the closed-loop searches, the
robustness benchmark) and, on Ray, the open-loop roll-outs of DPS
(``jugglerl.dps.cluster_rollouts``); sweeps (``-m``) run on Ray through
``jugglerl.cluster.launcher``. Adding a backend: a module here registering a class built as
``Backend(cfg, workers)`` with ``distributed``, ``map(fn, items)`` and ``close()``, and a
``configs/cluster/NAME.yaml``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from typing import Any, Protocol

from omegaconf import DictConfig

from jugglerl_envs.registry import Registry

CLUSTERS = Registry("cluster", __name__)


class Cluster(Protocol):
    #: whether work leaves this process's machine (open-loop roll-outs then go as tasks too)
    distributed: bool

    def map(self, fn: Callable[[list], list], items: Sequence[Any]) -> Iterator[Any]:
        """``fn`` (a module-level function from a list of items to a list of results) on
        chunks of ``items``; the results one by one, in the order of ``items``."""

    def close(self) -> None: ...


def register_sweep_launcher() -> None:
    """Make ``cluster=ray``'s sweep launcher (``hydra_plugins.jugglerl_cluster``) known to Hydra,
    which finds plugins by listing its ``hydra_plugins`` folders: an editable install of this
    project has none to list. Scripts with sweeps call this before ``hydra.main`` runs."""
    from hydra.core.plugins import Plugins
    from hydra_plugins.jugglerl_cluster import ClusterLauncher

    Plugins.instance().register(ClusterLauncher)


def is_distributed(cfg: DictConfig | None) -> bool:
    """Whether the backend of ``cfg`` (``None``: local) sends work off this machine."""
    return cfg is not None and CLUSTERS.get(cfg.name).distributed


def open_cluster(cfg: DictConfig | None, workers: int = 0) -> Cluster:
    """The backend of ``cfg`` (a ``configs/cluster`` group; ``None``: local) with ``workers``
    local processes (0: one per core; a distributed backend uses the cluster's CPUs)."""
    name = "local" if cfg is None else cfg.name
    return CLUSTERS.get(name)(cfg, workers)
