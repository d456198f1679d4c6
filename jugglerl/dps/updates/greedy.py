"""``greedy``: keep the best (the paper's rule); Σ fixed."""

from __future__ import annotations

import math

import torch

from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.updates import UPDATES, UpdateRule


@UPDATES.register("greedy")
class Greedy(UpdateRule):
    """The mean moves to a sample only when it beats every earlier sample."""

    def __init__(self):
        self.best_return = -math.inf

    def __call__(self, distribution, params, returns):
        best = int(torch.argmax(returns))
        if float(returns[best]) <= self.best_return:
            return distribution
        self.best_return = float(returns[best])
        return SearchDistribution(params[best].clone(), distribution.cov)

    def state_dict(self) -> dict:
        return {"best_return": self.best_return}

    def load_state_dict(self, state: dict) -> None:
        self.best_return = float(state["best_return"])
