"""Bridges between Hydra configs and the package's objects."""

from __future__ import annotations

import gymnasium as gym
from omegaconf import DictConfig, OmegaConf

from jugglerl_envs import JuggleEnv


def make_juggle_env(env_cfg: DictConfig, **overrides) -> gym.Env:
    """A ``JuggleEnv`` from a ``configs/env/*.yaml`` group, with keyword ``overrides`` applied.

    Bad values raise ``ValueError`` naming the key (the env validates its arguments): a key of
    the group as ``env.KEY``, an override by its own name.
    """
    overrides = {key: value for key, value in overrides.items() if value is not None}
    kwargs = {**OmegaConf.to_container(env_cfg, resolve=True), **overrides}
    try:
        return JuggleEnv(**kwargs)
    except TypeError as error:  # an unknown key in the env group
        raise ValueError(f"env config: {error}") from None
    except ValueError as error:
        key = str(error).split("=", 1)[0]
        blamed = f"env.{error}" if key in env_cfg and key not in overrides else str(error)
        raise ValueError(blamed) from None
