"""``throws``: 1 for each throw over the threshold (the paper's reward 1 and the DPS objective)."""

import numpy as np

from jugglerl_envs.rewards import REWARDS


@REWARDS.register("throws")
def throws_reward(batch, throws: np.ndarray) -> np.ndarray:
    return throws.astype(np.float64)
