"""``rise`` (ours, for learning to throw high enough): ``juggle`` plus the height each ball gains
in free flight, up to the threshold.

``juggle + RISE_WEIGHT · vz · dt`` for a ball in free flight, rising, below ``threshold``: over a
throw it sums to ``RISE_WEIGHT`` times the height the ball rose before it crossed the threshold (or
before its apex, if it never did). A throw that falls 5 cm short is worth almost what a throw that
counts is worth in this term, and the throw itself pays 1, so a learner whose throws fall short
(an arm with weaker servos) is shown which way is up before its first counted throw. Only free
flight counts: lifting the ball in the cup earns nothing.
"""

import numpy as np

from jugglerl_envs.rewards import REWARDS
from jugglerl_envs.rewards.juggle import juggle_reward

#: per metre of free rise below the threshold: a whole throw's rise (≈ 0.45 m) is worth 0.45.
RISE_WEIGHT = 1.0


@REWARDS.register("rise")
def rise_reward(batch, throws: np.ndarray) -> np.ndarray:
    threshold = batch.settings.threshold[:, None]
    climbing = batch.in_flight & (batch.ball_heights < threshold)
    speed = np.maximum(batch.ball_velocities[:, :, 2], 0.0)
    rise = np.where(climbing, speed, 0.0).sum(axis=1) * batch.dt
    return juggle_reward(batch, throws) + RISE_WEIGHT * rise
