"""``ClusterLauncher``: the jobs of a sweep (``-m ... cluster=ray``) as Ray tasks.

Hydra finds launchers only in its ``hydra_plugins`` namespace, so this folder installs as
``hydra_plugins.jugglerl_cluster`` (``pyproject.toml``) and is selected by
``configs/hydra/launcher/cluster_ray.yaml``.

The work is Hydra's Ray launcher's (``hydra-ray-launcher``, in the ``ray`` extra): each job is
one Ray task holding ``cluster.cpus_per_job`` CPUs. This launcher puts two things in front of
it: the connection (``jugglerl.cluster.ray_tasks.connect``: one ``error:`` line naming
``cluster.address`` when Ray is missing or the cluster does not answer), and the sweep
directory made absolute, so each job's run directory and ``.rrd`` land where a local sweep puts
them, whichever node runs it (on several machines that path must be shared, e.g. NFS).
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path

from hydra.core.utils import JobReturn
from hydra.plugins.launcher import Launcher
from hydra.types import HydraContext, TaskFunction
from omegaconf import DictConfig, OmegaConf

from jugglerl.cluster.ray_tasks import INSTALL_HINT, connect


class ClusterLauncher(Launcher):
    def __init__(self, address: str, cpus_per_job: float):
        self.address = address
        self.cpus_per_job = cpus_per_job
        self._setup: dict = {}

    def setup(
        self, *, hydra_context: HydraContext, task_function: TaskFunction, config: DictConfig
    ) -> None:
        self._setup = {
            "hydra_context": hydra_context,
            "task_function": task_function,
            "config": config,
        }

    def launch(
        self, job_overrides: Sequence[Sequence[str]], initial_job_idx: int
    ) -> Sequence[JobReturn]:
        try:
            from hydra_plugins.hydra_ray_launcher.ray_launcher import RayLauncher

            connect(self.address)
        except ImportError:
            sys.exit(f"error: {INSTALL_HINT}")
        except ValueError as error:
            sys.exit(f"error: {error}")
        ray_cfg = {"init": {"address": self.address}, "remote": {"num_cpus": self.cpus_per_job}}
        launcher = RayLauncher(ray=OmegaConf.create(ray_cfg))
        launcher.setup(**self._setup)
        sweep_dir = Path(str(self._setup["config"].hydra.sweep.dir)).absolute()
        pinned = [[*overrides, f"hydra.sweep.dir='{sweep_dir}'"] for overrides in job_overrides]
        return launcher.launch(pinned, initial_job_idx)
