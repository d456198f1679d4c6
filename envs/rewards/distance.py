"""``distance``: the inverse cup–ball distance, bounded (the paper's reward 2)."""

import numpy as np

from jugglerl_envs.rewards import REWARDS

#: m: the reward is 1 within this distance of the cup.
DISTANCE_SCALE = 0.05


@REWARDS.register("distance")
def distance_reward(env, throws: int) -> float:
    """``min(1, DISTANCE_SCALE / distance)`` for the ball's distance from the cup's throat."""
    distance = np.linalg.norm(env.ball_position() - env.cup_position())
    return float(min(1.0, DISTANCE_SCALE / max(distance, 1e-9)))
