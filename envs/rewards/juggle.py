"""``juggle`` (ours, for closed-loop juggling): the throws plus a small dense centring term.

``throws + CENTRING_WEIGHT · max(0, 1 - d / CENTRING_SCALE)`` with ``d`` the ball's horizontal
distance from the cup. It pays for keeping the cup under the ball, in the cup and in flight,
without paying for holding the ball (as ``distance`` does), and a drop ends the stream of it.
"""

import numpy as np

from jugglerl_envs.rewards import REWARDS, lengths

#: m: the centring term is 0 this far off the cup's axis.
CENTRING_SCALE = 0.1
#: per step: 0.5 per second of a centred ball, about one throw's worth.
CENTRING_WEIGHT = 0.01


@REWARDS.register("juggle")
def juggle_reward(batch, throws: np.ndarray) -> np.ndarray:
    offset = lengths(batch.ball_positions[:, 0, :2] - batch.cup_position[:, :2])
    return throws + CENTRING_WEIGHT * np.maximum(0.0, 1.0 - offset / CENTRING_SCALE)
