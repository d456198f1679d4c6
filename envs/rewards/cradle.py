"""``cradle`` (ours, for fine-tuning a juggler's robustness): ``juggle`` less a cost for a held
ball that has rolled off the cone's axis.

``juggle - CRADLE_WEIGHT · min(1, r / CRADLE_SCALE)`` while the ball sits in the cup, with ``r``
its distance from the cone's axis. At the paper's gravity the ball sits loosely in the cone: the
arm's jitter rolls it 1-2 cm off-centre and a ball thrown off-centre leaves sideways, which is how
a juggler under action noise drops it (docs/results/two_balls.md). The throws alone tell a critic
about that a whole cycle later; this term tells it at once, while a correction can still centre
the ball. It is a cost, not a payment, so it never pays for holding the ball.
"""

import numpy as np

from jugglerl_envs.rewards import REWARDS
from jugglerl_envs.rewards.juggle import juggle_reward

#: m: the cost is whole this far off the axis, the roll that makes a throw leave sideways.
CRADLE_SCALE = 0.02
#: per step: a ball held 1 cm off-centre for half a second costs a quarter of a throw.
CRADLE_WEIGHT = 0.01


@REWARDS.register("cradle")
def cradle_reward(batch, throws: np.ndarray) -> np.ndarray:
    costs = CRADLE_WEIGHT * np.minimum(1.0, batch.radial / CRADLE_SCALE)
    return juggle_reward(batch, throws) - np.where(batch.in_cup, costs, 0.0).sum(axis=1)
