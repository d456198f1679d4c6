"""Rewards of the juggling env, one module each, chosen by the env's ``reward`` argument.

A reward is a function ``reward(env, throws) -> float`` registered in ``REWARDS``: it reads the
env's state after the step (``env.ball_position()``, ``env.cup_position()``,
``env.ball_arm_contacts()``, ...) and ``throws``, the throws this step completed (0 or 1).
Adding one: a module here and a ``configs/reward/NAME.yaml``.
"""

from jugglerl_envs.registry import Registry

REWARDS = Registry("reward", __name__)
