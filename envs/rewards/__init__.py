"""Rewards of the juggling env, one module each, chosen by the env's ``reward`` argument.

A reward is a function ``reward(batch, throws) -> rewards`` registered in ``REWARDS``: it reads
the arrays a ``JuggleBatch`` holds after a step, one row per env (``batch.ball_positions``,
``batch.cup_position``, ``batch.in_cup``, ``batch.radial``, ``batch.ball_arm_contacts()``, ...),
and ``throws``, the throws each env's step completed (``[N]``, 0 or 1), and returns one reward
per env. ``JuggleEnv`` is a batch of one. Adding one: a module here and a
``configs/reward/NAME.yaml``.
"""

import numpy as np

from jugglerl_envs.registry import Registry

REWARDS = Registry("reward", __name__)


def lengths(vectors: np.ndarray) -> np.ndarray:
    """Euclidean length along the last axis, bit for bit ``np.linalg.norm`` of each vector alone
    (a dot product, not a sum of squares, which rounds differently)."""
    return np.sqrt(np.vecdot(vectors, vectors))
