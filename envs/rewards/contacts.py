"""``contacts``: the number of ball–arm contacts after the step (the paper's reward 3)."""

import numpy as np

from jugglerl_envs.rewards import REWARDS


@REWARDS.register("contacts")
def contacts_reward(batch, throws: np.ndarray) -> np.ndarray:
    return batch.ball_arm_contacts().astype(np.float64)
