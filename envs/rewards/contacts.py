"""``contacts``: the number of ball–arm contacts after the step (the paper's reward 3)."""

from jugglerl_envs.rewards import REWARDS


@REWARDS.register("contacts")
def contacts_reward(env, throws: int) -> float:
    return float(env.ball_arm_contacts())
