"""``distance``: the inverse cup–ball distance, bounded (the paper's reward 2)."""

import numpy as np

from jugglerl_envs.rewards import REWARDS, lengths

#: m: the reward is 1 within this distance of the cup.
DISTANCE_SCALE = 0.05


@REWARDS.register("distance")
def distance_reward(batch, throws: np.ndarray) -> np.ndarray:
    """``min(1, DISTANCE_SCALE / distance)`` for the first ball's distance from the cup's throat."""
    distance = lengths(batch.ball_positions[:, 0] - batch.cup_position)
    return np.minimum(1.0, DISTANCE_SCALE / np.maximum(distance, 1e-9))
