"""``cluster=ray``: Ray tasks of ``cluster.chunk`` items each, on the cluster at
``cluster.address``.

``cluster.address`` is passed to ``ray.init``: ``local`` starts a Ray instance in this process
(using this machine's cores), ``HOST:PORT`` joins the cluster whose head ``ray start --head``
started there, ``auto`` the one in ``RAY_ADDRESS`` or the last one started on this machine.
Every node must have the project installed at the same path (the tasks import ``jugglerl``, and
policy files are read by path). Results come back in the order of the items: a seeded run is
the same as on one machine.
"""

from __future__ import annotations

import socket
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from omegaconf import DictConfig

from jugglerl.cluster import CLUSTERS

#: s to wait for a cluster's head to accept a connection before giving up on its address
CONNECT_TIMEOUT = 5.0
INSTALL_HINT = "cluster=ray needs Ray: pip install -e '.[ray]'"


def import_ray():
    """The ``ray`` module; ``ValueError`` saying how to install it when it is missing."""
    try:
        import ray
    except ImportError:
        raise ValueError(INSTALL_HINT) from None
    return ray


def connect(address: str) -> None:
    """Connect this process to the Ray cluster at ``address`` (see the module docstring), once,
    and say how big it is.

    A missing Ray or a cluster that does not answer raises ``ValueError`` naming
    ``cluster.address``, at once rather than after Ray's own retries.
    """
    ray = import_ray()
    if ray.is_initialized():
        return
    address = str(address)
    if address not in ("local", "auto"):
        host, _, port = address.split("://")[-1].rpartition(":")
        try:
            socket.create_connection((host, int(port)), timeout=CONNECT_TIMEOUT).close()
        except (OSError, ValueError) as error:
            raise ValueError(
                f"cluster.address={address}: no Ray cluster answers there ({error}); start one"
                " with `ray start --head` (it prints the address) or use cluster.address=local"
            ) from None
    options = {"include_dashboard": False} if address == "local" else {}
    try:
        ray.init(address=address, logging_level="WARNING", **options)
    except (ConnectionError, RuntimeError) as error:
        raise ValueError(f"cluster.address={address}: {error}") from None
    nodes = sum(node["Alive"] for node in ray.nodes())
    cpus = ray.cluster_resources().get("CPU", 0)
    print(f"cluster: Ray at {address}: {nodes} node(s), {cpus:g} CPUs")


def _run_chunk(fn: Callable[[list], list], chunk: list) -> list:
    return fn(chunk)


@CLUSTERS.register("ray")
class RayCluster:
    """Tasks of ``cfg.chunk`` items, ``cfg.cpus_per_task`` CPUs each, on ``cfg.address``."""

    distributed = True

    def __init__(self, cfg: DictConfig, workers: int = 0):
        if cfg.chunk < 1 or cfg.cpus_per_task <= 0:
            raise ValueError(
                f"cluster.chunk={cfg.chunk} must be >= 1 and"
                f" cluster.cpus_per_task={cfg.cpus_per_task} > 0"
            )
        self.chunk = int(cfg.chunk)
        self.cpus_per_task = cfg.cpus_per_task
        connect(cfg.address)
        self._ray = import_ray()
        # SPREAD: by default a node queues the tasks it is handed and lends them on late
        self._task = self._ray.remote(num_cpus=self.cpus_per_task, scheduling_strategy="SPREAD")(
            _run_chunk
        )

    def map(self, fn: Callable[[list], list], items: Sequence[Any]) -> Iterator[Any]:
        items = list(items)
        chunks = [items[start : start + self.chunk] for start in range(0, len(items), self.chunk)]
        futures = [self._task.remote(fn, chunk) for chunk in chunks]  # all queued at once
        for future in futures:
            yield from self._ray.get(future)

    def close(self) -> None:
        """Nothing to release: the connection serves the whole process (Ray ends it at exit)."""
