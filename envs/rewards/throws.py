"""``throws``: 1 for each throw over the threshold (the paper's reward 1 and the DPS objective)."""

from jugglerl_envs.rewards import REWARDS


@REWARDS.register("throws")
def throws_reward(env, throws: int) -> float:
    return float(throws)
