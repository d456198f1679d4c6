"""``elite``: mean and per-entry std of the best samples (the cross-entropy method)."""

from __future__ import annotations

import torch

from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.updates import UPDATES, UpdateRule


@UPDATES.register("elite")
class Elite(UpdateRule):
    """Mean and per-entry std of the ``count`` best samples (std floored at ``min_stds``)."""

    def __init__(self, count: int, min_stds: torch.Tensor):
        if count < 2:
            raise ValueError(f"algo.elite={count}: elite needs at least 2 samples to fit a std")
        self.count = count
        self.min_stds = min_stds

    @classmethod
    def from_config(cls, algo, initial_stds):
        if algo.elite > algo.rollouts:
            raise ValueError(f"algo.elite={algo.elite} must be <= algo.rollouts={algo.rollouts}")
        return cls(algo.elite, initial_stds * algo.min_std_scale)

    def __call__(self, distribution, params, returns):
        if self.count > len(returns):
            raise ValueError(f"elite={self.count} is more than the {len(returns)} roll-outs")
        elite = params[torch.topk(returns.to(torch.float64), self.count).indices]
        stds = torch.maximum(elite.std(dim=0), self.min_stds)
        return SearchDistribution(elite.mean(dim=0), torch.diag(stds**2))
