"""Actors: deterministic networks from the network's ``state`` to an ``action`` in [-1, 1].

Each module registers a class in ``ACTORS`` (chosen by ``actor.name``) with

- ``build(actor_cfg, state_size, action_size) -> TensorDictSequential``: the network, reading
  ``state`` (and, if it needs it, the episode ``time``) and writing ``action``;
- ``recurrent_state(actor_cfg) -> dict``: the recurrent state it carries between steps, as
  ``{key: shape}`` (empty for a feed-forward actor). The env stack adds zero states on reset
  for these keys (``primer``), updates run the actor in recurrent mode on sub-trajectories, and
  ``ActorPolicy`` carries them from step to step;
- ``features(actor_cfg) -> dict``: what it computes on the way that a correction may read, as
  ``{key: size}`` (an LSTM's ``memory``; empty for a feed-forward actor).

Any actor can carry a bounded correction on top (``actor.correction``, ``correction.py``).

Adding one: a module here and a ``configs/actor/NAME.yaml``.
"""

from __future__ import annotations

from omegaconf import DictConfig
from torchrl.data import Unbounded
from torchrl.envs import TensorDictPrimer

from jugglerl.networks.actors.correction import corrected
from jugglerl_envs.registry import Registry
from jugglerl_envs.scene import ACTUATED_JOINTS

ACTORS = Registry("actor", __name__)
#: An actor's action drives the pan, lift and elbow servos (normalised, ``jugglerl_envs.actions``).
ACTION_SIZE = len(ACTUATED_JOINTS)


class FeedForward:
    """Base for actors without recurrent state."""

    @staticmethod
    def recurrent_state(actor_cfg: DictConfig) -> dict[str, tuple[int, ...]]:
        return {}

    @staticmethod
    def features(actor_cfg: DictConfig) -> dict[str, int]:
        return {}


def recurrent_state(actor_cfg: DictConfig) -> dict[str, tuple[int, ...]]:
    """The recurrent state of the actor ``actor_cfg`` names."""
    return ACTORS.get(actor_cfg.name).recurrent_state(actor_cfg)


def build_actor(actor_cfg: DictConfig, state_size: int, action_size: int):
    """The actor ``actor_cfg.name`` names, with ``actor_cfg.correction`` on top when set."""
    kind = ACTORS.get(actor_cfg.name)
    actor = kind.build(actor_cfg, state_size, action_size)
    correction_cfg = actor_cfg.get("correction")
    if correction_cfg is None:
        return actor
    return corrected(actor, correction_cfg, state_size, action_size, kind.features(actor_cfg))


def primer(actor_cfg: DictConfig) -> TensorDictPrimer | None:
    """The env transform that writes the actor's zero recurrent state on reset (None if none)."""
    states = recurrent_state(actor_cfg)
    if not states:
        return None
    return TensorDictPrimer(
        {key: Unbounded(shape=shape) for key, shape in states.items()}, expand_specs=True
    )
