"""``make_env``: the juggling env batched in one process, under TorchRL's transform stack.

TorchRL costs about half a millisecond per env call whatever the batch (toolchain-notes.md), so
the envs run as one synchronous Gymnasium vector env behind a single ``GymWrapper``. The stack:

| transform | why |
| --- | --- |
| ``DoubleToFloat`` | MuJoCo states are float64; the networks are float32 |
| ``StepCounter`` | ``step_count``: per-episode step index (the slice sampler reads it) |
| ``InitTracker`` | ``is_init``: marks first steps, which reset LSTM states and OU noise |
| ``RewardSum`` | ``episode_reward``: the return of the running episode |
| ``ObservationNorm`` | standardises the 18 physical observations (stats from random steps) |
| ``TimestampFeatures`` | appends elapsed time and cycle phase (``state.timestamp``) |

Observations in the stack are therefore 18 normalised values plus, with the timestamp, 3 time
features. ``observation_transforms`` builds the last two on their own, so that a trained actor
can be run outside TorchRL (``jugglerl.ddpg.policy.ActorPolicy``) on exactly the same inputs.
"""

from __future__ import annotations

import gymnasium as gym
import torch
from omegaconf import DictConfig, OmegaConf
from torchrl.data import Unbounded
from torchrl.envs import (
    DoubleToFloat,
    EnvBase,
    GymWrapper,
    InitTracker,
    ObservationNorm,
    RewardSum,
    StepCounter,
    Transform,
    TransformedEnv,
)
from torchrl.envs.libs.gym import default_info_dict_reader

from jugglerl.ddpg.timestamp import TimestampFeatures
from jugglerl_envs import ENV_ID

#: The info entries training and evaluation read, all numeric (see ``NumericInfo``), and their
#: dtypes in the tensordict.
INFO_KEYS = {"throws": torch.int64, "catches": torch.int64, "time": torch.float64}
OBSERVATION_SIZE = 18
ACTION_SIZE = 3


class NumericInfo(gym.Wrapper):
    """Passes on only ``INFO_KEYS`` and a boolean ``physics_error``.

    TorchRL's reader for vector envs turns every info entry into a tensor; the env's
    ``physics_error`` message is a string, which it cannot hold.
    """

    def reset(self, **kwargs):
        observation, info = self.env.reset(**kwargs)
        return observation, self._numeric(info)

    def step(self, action):
        observation, reward, terminated, truncated, info = self.env.step(action)
        return observation, reward, terminated, truncated, self._numeric(info)

    @staticmethod
    def _numeric(info: dict) -> dict:
        numeric = {key: info[key] for key in INFO_KEYS}
        numeric["physics_error"] = bool(info["physics_error"])
        return numeric


def make_vector_env(env_cfg: DictConfig, num_envs: int) -> gym.vector.VectorEnv:
    """``num_envs`` juggling envs from a ``configs/env`` group, stepped in this process.

    Without auto-reset: TorchRL resets finished envs itself (``_reset`` masks), so each
    transition's next observation is the true last one and no terminal-observation reader runs
    on every step. Bad env values raise ``ValueError`` naming the key.
    """
    if num_envs < 1:
        raise ValueError(f"collector.num_envs={num_envs} must be >= 1")
    kwargs = OmegaConf.to_container(env_cfg, resolve=True)
    try:
        return gym.make_vec(
            ENV_ID,
            num_envs=num_envs,
            vectorization_mode="sync",
            vector_kwargs={"autoreset_mode": gym.vector.AutoresetMode.DISABLED},
            wrappers=[NumericInfo],
            **kwargs,
        )
    except TypeError as error:  # an unknown key in the env group
        raise ValueError(f"env config: {error}") from None


def observation_transforms(
    state_cfg: DictConfig, duration: float, loc: torch.Tensor | None, scale: torch.Tensor | None
) -> list[Transform]:
    """The observation normalisation and (when ``state_cfg.timestamp``) the time features.

    ``loc``/``scale`` of ``None`` leave the normalisation to be fitted by
    ``fit_normalisation``.
    """
    transforms: list[Transform] = [
        ObservationNorm(loc=loc, scale=scale, in_keys=["observation"], standard_normal=True)
    ]
    if state_cfg.timestamp:
        transforms.append(TimestampFeatures(duration=duration, period=state_cfg.period))
    return transforms


def make_env(
    cfg: DictConfig,
    num_envs: int,
    loc: torch.Tensor | None = None,
    scale: torch.Tensor | None = None,
) -> EnvBase:
    """The batched env of ``cfg.env`` under the transform stack (see the module docstring).

    Pass the ``loc``/``scale`` of a trained run to reuse its normalisation; otherwise it is
    fitted on ``cfg.state.norm_frames`` random steps.
    """
    env = TransformedEnv(GymWrapper(make_vector_env(cfg.env, num_envs)))
    info_specs = {key: Unbounded((num_envs,), dtype=dtype) for key, dtype in INFO_KEYS.items()}
    info_specs["physics_error"] = Unbounded((num_envs,), dtype=torch.bool)
    env.base_env.set_info_dict_reader(default_info_dict_reader(list(info_specs), spec=info_specs))
    for transform in (DoubleToFloat(), StepCounter(), InitTracker(), RewardSum()):
        env.append_transform(transform)
    for transform in observation_transforms(cfg.state, cfg.env.duration, loc, scale):
        env.append_transform(transform)
    if loc is None:
        fit_normalisation(env, cfg.state.norm_frames)
    return env


def normalisation(env: EnvBase) -> ObservationNorm:
    """The env stack's ``ObservationNorm``."""
    return next(t for t in env.transform if isinstance(t, ObservationNorm))


def fit_normalisation(env: EnvBase, frames: int) -> None:
    """Fit the observation normalisation on about ``frames`` steps of uniformly random actions."""
    # init_stats rolls out until it has ``frames`` (batch x time) observations
    normalisation(env).init_stats(num_iter=frames, reduce_dim=(0, 1), cat_dim=1)
