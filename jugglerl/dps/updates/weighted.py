"""``weighted``: the reward-weighted mean of the batch (the paper's alternative); Σ fixed."""

from __future__ import annotations

import torch

from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.updates import UPDATES, UpdateRule


@UPDATES.register("weighted")
class RewardWeighted(UpdateRule):
    """Mean = Σ R_i θ_i / Σ R_i over the batch (returns must be >= 0, as throw counts are)."""

    def __call__(self, distribution, params, returns):
        if torch.any(returns < 0):
            raise ValueError("the reward-weighted update needs returns >= 0")
        total = returns.sum()
        if total <= 0:
            return distribution
        mean = (returns.to(params.dtype) / total) @ params
        return SearchDistribution(mean, distribution.cov)
