"""``feedback_gains`` (``algo=feedback``): the gains of the closed-loop ``FeedbackPolicy``.

θ is ``FeedbackGains`` (bounded by ``algo.bounds``), searched from ``algo.start``; the command it
locks to is fixed (``algo.command``). Every θ is rolled out closed loop in the Python env, once
under each of ``algo.conditions`` (env overrides: nominal, kicks, start offsets), in
``algo.workers`` processes (or as tasks of ``cluster=ray``; ``ClosedLoopRollouts``); its return
is its throws summed over the conditions, so the search prefers gains that juggle in all of
them. The best θ is written as ``best_policy.yaml``.
"""

from __future__ import annotations

import torch
from omegaconf import DictConfig

from jugglerl.commands import load_command
from jugglerl.dps.closed_loop_space import ClosedLoopSpace, GainBox, gains_from_params
from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.spaces import SPACES
from jugglerl.policies.feedback import PARAM_NAMES


@SPACES.register("feedback_gains")
class FeedbackGainSpace(ClosedLoopSpace):
    """θ of ``FeedbackGains``; see the module docstring."""

    def __init__(self, cfg: DictConfig):
        super().__init__(cfg)
        algo = cfg.algo
        self.command = load_command(algo.command)
        self.box = GainBox(algo.bounds)
        self.start = torch.tensor([algo.start[name] for name in PARAM_NAMES], dtype=torch.float64)
        problems = self.violations(self.start)
        if problems:
            raise ValueError(f"algo.start: outside algo.bounds: {'; '.join(problems)}")
        self.stds = torch.tensor([algo.std[name] for name in PARAM_NAMES], dtype=torch.float64)

    def project(self, params: torch.Tensor) -> torch.Tensor:
        return self.box.project(params)

    def violations(self, params: torch.Tensor) -> list[str]:
        return self.box.violations(params)

    def decode(self, params: torch.Tensor) -> tuple:
        return self.command, gains_from_params(params)

    def record(self, distribution: SearchDistribution) -> dict[str, float]:
        means = zip(PARAM_NAMES, distribution.mean, strict=True)
        return {f"mean_{name}": float(mean) for name, mean in means}
