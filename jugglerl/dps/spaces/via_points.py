"""``via_points`` (``algo=dps``): the paper's search over an open-loop command's θ.

θ is the command's cycle and via-points (``jugglerl.dps.params``), searched from ``algo.start``;
the pan angle and the lead-in (``algo.lead_in``) are not searched. Every θ is rolled out open
loop in C (``CommandRollouts``), each from a start with the ball offset by up to
``algo.reset_noise``, so the best command is one that juggles from imperfect starts too.
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import torch
from omegaconf import DictConfig, OmegaConf

from jugglerl.cluster import is_distributed, open_cluster
from jugglerl.commands import ViaPointCommand, load_command, save_command
from jugglerl.config.envs import make_juggle_env
from jugglerl.dps.cluster_rollouts import ClusterCommandRollouts
from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.params import (
    ViaPointConstraints,
    command_to_params,
    component_stds,
    params_to_command,
)
from jugglerl.dps.rollouts import CommandRollouts
from jugglerl.dps.spaces import SPACES
from jugglerl.policies.command import CommandPolicy
from jugglerl.runs.policy_files import check_policy_named
from jugglerl_envs.settings import MAX_RESET_NOISE
from jugglerl_envs.validation import check_number

#: A search's command files: ``best_command.yaml`` (its best roll-out) and ``mean_command.yaml``.
COMMAND_FILE = "{role}_command.yaml"


@SPACES.register("via_points")
class ViaPointSpace:
    """θ of a via-point command; see the module docstring."""

    def __init__(self, cfg: DictConfig):
        self.cfg = cfg
        algo = cfg.algo
        self.reset_noise = check_number("algo.reset_noise", algo.reset_noise, 0, MAX_RESET_NOISE)
        lead_in = check_number("algo.lead_in", algo.lead_in, 0.0)
        check_policy_named("algo.start", algo.start)
        start = load_command(algo.start)
        self.pan, self.lead_in = start.pan, lead_in
        env = self.search_env()
        self.constraints = ViaPointConstraints.from_model(
            env.unwrapped.model, algo.min_cycle, algo.max_cycle, algo.min_gap
        )
        env.close()
        self.start = command_to_params(start)
        self.constraints.check(len(start.via_points))
        problems = self.constraints.violations(self.start)
        if problems:
            raise ValueError(
                f"algo.start={algo.start}: outside the constraints: {'; '.join(problems)}"
            )
        self.stds = component_stds(len(start.via_points), dict(algo.std))

    def project(self, params: torch.Tensor) -> torch.Tensor:
        return self.constraints.project(params)

    def violations(self, params: torch.Tensor) -> list[str]:
        return self.constraints.violations(params)

    def decode(self, params: torch.Tensor, name: str = "dps") -> ViaPointCommand:
        """The via-point command of θ, with the parts that are not searched."""
        return params_to_command(params, self.pan, name, self.lead_in)

    def search_env(self, reset_noise: float | None = None) -> gym.Env:
        noise = self.reset_noise if reset_noise is None else reset_noise
        return make_juggle_env(self.cfg.env, reset_noise=noise)

    def rollouts(self, reset_noise: float | None = None) -> CommandRollouts:
        """In C on ``algo.threads`` threads here, or as tasks of a distributed ``cluster``."""
        cluster = self.cfg.get("cluster")
        env = self.search_env(reset_noise)
        if not is_distributed(cluster):
            return CommandRollouts(env, nthread=self.cfg.algo.threads)
        env.close()  # built to check the values here; the workers build their own
        kwargs = OmegaConf.to_container(self.cfg.env, resolve=True)
        kwargs["reset_noise"] = env.unwrapped.reset_noise
        return ClusterCommandRollouts(kwargs, open_cluster(cluster))

    def policy(self, params: torch.Tensor, env: gym.Env) -> CommandPolicy:
        return CommandPolicy(self.decode(params))

    def save(self, params: torch.Tensor, run_dir: Path, name: str, role: str = "best") -> str:
        file = COMMAND_FILE.format(role=role)
        save_command(self.decode(params, name), run_dir / file)
        return file

    def describe(self, params: torch.Tensor, name: str) -> dict:
        return {"best_command": self.decode(params, name).to_dict()}

    def record(self, distribution: SearchDistribution) -> dict[str, float]:
        """What the history keeps of the search distribution: its cycle's mean and std."""
        return {"mean_cycle": float(distribution.mean[0]), "std_cycle": float(distribution.stds[0])}

    def headline(self, metrics: dict) -> str:
        return (
            f"DPS ({self.cfg.algo['update']}): best {metrics['best_throws']} throws in"
            f" {self.cfg.env.duration:g} s after {metrics['rollouts']} roll-outs"
            f" (found at roll-out {metrics['best_found_at_rollout']})"
        )
