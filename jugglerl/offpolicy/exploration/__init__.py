"""Exploration: modules that turn the actor's ``action`` into an exploratory one.

Each module registers a builder in ``EXPLORATIONS`` (chosen by ``exploration.name``):
``build(exploration_cfg, action_spec) -> module``. A module reads the tensordict after the actor,
rewrites ``action``, anneals only when its ``step(frames)`` is called, and passes the action
through unchanged outside ``ExplorationType.RANDOM`` (evaluation). A stage whose teacher or
student acts (``acts``) uses ``jugglerl.offpolicy.who_acts.WhoActs`` instead. Adding one: a
module here and a ``configs/exploration/NAME.yaml``.
"""

from jugglerl_envs.registry import Registry

EXPLORATIONS = Registry("exploration", __name__)


def make_exploration(exploration_cfg, action_spec):
    """The noise module ``exploration_cfg.name`` names."""
    return EXPLORATIONS.get(exploration_cfg.name)(exploration_cfg, action_spec)
