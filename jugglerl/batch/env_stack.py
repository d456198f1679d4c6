"""``make_env``: the juggling envs batched in one process, under TorchRL's transform stack.

TorchRL costs about half a millisecond per env call whatever the batch size, so the envs run as
one batch behind a single TorchRL env, chosen by ``collector.env``:

- ``batch`` (``jugglerl.batch.torchrl_env.JuggleBatchEnv``): a ``JuggleBatch``, its physics on
  every core, several times faster (``scripts/benchmarks/bench_batch.py``);
- ``gym``: a synchronous Gymnasium vector env of ``JuggleEnv``s behind TorchRL's ``GymWrapper``.

Both give each env the same episode, value for value. The stack keeps the env's physical
``observation`` (float64) and episode ``time`` (s, float64) as they are, for teachers acting in
the loop (``jugglerl.offpolicy.teacher``), and builds the networks' input ``state`` beside them:

| transform | why |
| --- | --- |
| ``RenameTransform`` | copies ``observation`` to ``state``, the networks' input |
| ``DoubleToFloat`` | ``state`` to float32 (MuJoCo states are float64; the networks are float32) |
| ``ObservationParts`` | keeps the parts ``state.observe`` names (absent for all six: the default) |
| ``StepCounter`` | ``step_count``: per-episode step index (the slice sampler reads it) |
| ``InitTracker`` | ``is_init``: marks first steps, which reset LSTM states and OU noise |
| ``RewardSum`` | ``episode_reward``: the return of the running episode |
| ``ObservationNorm`` | standardises ``state`` (stats fitted on random steps) |
| ``TimestampFeatures`` | appends elapsed time and cycle phase to ``state`` (``state.timestamp``) |
| ``BallClock`` | appends the phase since the ball last fell past the cup (``state.ball_clock``) |
| ``TensorDictPrimer`` | the actor's zero recurrent state on reset (recurrent actors only) |

The copy, the cast, the parts, the normalisation, the time features and the ball clock come
from ``jugglerl.state.transforms``, which a deployed actor (``jugglerl.policies.actor``) runs too.
"""

from __future__ import annotations

from functools import partial

import gymnasium as gym
import torch
from omegaconf import DictConfig, OmegaConf
from torchrl.data import Unbounded
from torchrl.envs import (
    EnvBase,
    GymWrapper,
    InitTracker,
    ObservationNorm,
    RewardSum,
    StepCounter,
    TransformedEnv,
)
from torchrl.envs.libs.gym import default_info_dict_reader
from torchrl.envs.utils import ExplorationType, set_exploration_type

from jugglerl.batch.episodes import per_env_arguments
from jugglerl.batch.torchrl_env import INFO_KEYS, JuggleBatchEnv
from jugglerl.networks.actors import primer
from jugglerl.state.observation_parts import part_values
from jugglerl.state.transforms import state_transforms
from jugglerl_envs import ENV_ID

#: The base envs ``collector.env`` chooses from.
BASE_ENVS = ("batch", "gym")


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


def make_vector_env(
    env_cfg: DictConfig, num_envs: int, variants: list[dict] | None = None
) -> gym.vector.VectorEnv:
    """``num_envs`` juggling envs from a ``configs/env`` group, stepped in this process; with
    ``variants`` (env arguments), env ``i`` runs with ``variants[i % len(variants)]`` on top,
    so a batch meets each variant (a perturbation, or ``{}`` for none) in equal shares.

    Without auto-reset: TorchRL resets finished envs itself (``_reset`` masks), so each
    transition's next observation is the true last one and no terminal-observation reader runs
    on every step. Bad env values raise ``ValueError`` naming the key.
    """
    if num_envs < 1:
        raise ValueError(f"collector.num_envs={num_envs} must be >= 1")
    kwargs = OmegaConf.to_container(env_cfg, resolve=True)
    variants = variants or [{}]
    makers = [
        partial(_numeric_env, {**kwargs, **variants[index % len(variants)]})
        for index in range(num_envs)
    ]
    try:
        return gym.vector.SyncVectorEnv(makers, autoreset_mode=gym.vector.AutoresetMode.DISABLED)
    except TypeError as error:  # an unknown key in the env group
        raise ValueError(f"env config: {error}") from None


def _numeric_env(kwargs: dict) -> gym.Env:
    return NumericInfo(gym.make(ENV_ID, **kwargs))


def check_collector(cfg: DictConfig) -> None:
    """``ValueError`` naming the ``collector`` (or ``env``) keys of a budget that cannot work."""
    if cfg.env.balls != 1:
        raise ValueError(
            f"env.balls={cfg.env.balls}: the networks' state observes one ball (jugglerl/state);"
            " the trainers run with env.balls=1"
        )
    check_batches(cfg.collector)


def check_batches(collect: DictConfig) -> None:
    """``ValueError`` naming the ``collector`` keys of batches that cannot be collected: each
    batch a whole number of steps of every env, the budget at least one batch."""
    if collect.num_envs < 1:
        raise ValueError(f"collector.num_envs={collect.num_envs} must be >= 1")
    if collect.frames_per_batch < collect.num_envs or collect.frames_per_batch % collect.num_envs:
        raise ValueError(
            f"collector.frames_per_batch={collect.frames_per_batch} must be a multiple of"
            f" collector.num_envs={collect.num_envs}"
        )
    if collect.total_frames < collect.frames_per_batch:
        raise ValueError(
            f"collector.total_frames={collect.total_frames} must be at least"
            f" collector.frames_per_batch={collect.frames_per_batch}"
        )


def make_env(
    cfg: DictConfig,
    num_envs: int,
    loc: torch.Tensor | None = None,
    scale: torch.Tensor | None = None,
    variants: list[dict] | None = None,
) -> EnvBase:
    """The batched env of ``cfg.env`` (its envs split among ``variants``, see
    ``make_vector_env``; ``collector.env`` chooses the base env) under the transform stack (see
    the module docstring), with the recurrent state of the actor ``cfg.actor`` primed.

    Pass the ``loc``/``scale`` of a trained run to reuse its normalisation; otherwise it is
    fitted on ``cfg.state.norm_frames`` random steps.
    """
    env = TransformedEnv(base_env(cfg, num_envs, variants))
    copy, cast, *rest = state_transforms(cfg.state, cfg.env.duration, loc, scale)
    for transform in (copy, cast, StepCounter()):
        env.append_transform(transform)
    for transform in (InitTracker(), RewardSum(), *rest):
        env.append_transform(transform)
    if loc is None:
        fit_normalisation(env, cfg.state.norm_frames)
    recurrent = primer(cfg.actor)
    if recurrent is not None:
        env.append_transform(recurrent)
    return env


def base_env(cfg: DictConfig, num_envs: int, variants: list[dict] | None = None) -> EnvBase:
    """The envs of ``cfg.env`` as one TorchRL env of ``batch_size=[num_envs]``, env ``i`` with
    ``variants[i % len(variants)]`` on top, of the kind ``collector.env`` names."""
    kind = cfg.collector.get("env", "gym")
    if kind not in BASE_ENVS:
        raise ValueError(f"collector.env={kind!r} is not available; choose one of {BASE_ENVS}")
    if kind == "gym":
        env = GymWrapper(make_vector_env(cfg.env, num_envs, variants))
        info_specs = {key: Unbounded((num_envs,), dtype=dtype) for key, dtype in INFO_KEYS.items()}
        info_specs["physics_error"] = Unbounded((num_envs,), dtype=torch.bool)
        reader = default_info_dict_reader(list(info_specs), spec=info_specs)
        env.set_info_dict_reader(reader)
        return env
    if num_envs < 1:
        raise ValueError(f"collector.num_envs={num_envs} must be >= 1")
    kwargs = OmegaConf.to_container(cfg.env, resolve=True)
    variants = variants or [{}]
    envs = [{**kwargs, **variants[index % len(variants)]} for index in range(num_envs)]
    try:
        return JuggleBatchEnv(num_envs, **per_env_arguments(envs))
    except TypeError as error:  # an unknown key in the env group
        raise ValueError(f"env config: {error}") from None


def normalisation(env: EnvBase) -> ObservationNorm:
    """The env stack's ``ObservationNorm``."""
    return next(t for t in env.transform if isinstance(t, ObservationNorm))


def fit_normalisation(env: EnvBase, frames: int) -> None:
    """Fit the observation normalisation on about ``frames`` steps of uniformly random actions."""
    # init_stats rolls out until it has ``frames`` (batch x time) observations
    normalisation(env).init_stats(num_iter=frames, reduce_dim=(0, 1), cat_dim=1)


#: Least spread the normalisation divides by (rad, rad/s, m, m/s): a part a policy's roll-outs
#: barely move (the pan joint of a command that never pans) is not blown up from noise.
MIN_SCALE = 0.05


def fit_normalisation_on(
    env: EnvBase,
    policy,
    frames: int,
    parts: tuple[str, ...] | None,
    exploration: ExplorationType = ExplorationType.DETERMINISTIC,
) -> None:
    """Fit the observation normalisation on about ``frames`` steps of ``policy`` acting (by
    default its deterministic action; ``None``: uniformly random actions): the states a policy
    starting from it will meet first. ``parts`` are the juggling observation's parts the state
    keeps (``state.observe``); ``None`` for an env whose whole observation is the state."""
    steps = max(1, -(-frames // env.batch_size.numel()))
    with torch.no_grad(), set_exploration_type(exploration):
        rollout = env.rollout(steps, policy, break_when_any_done=False)
    observation = rollout.get("observation").flatten(0, -2)
    if parts is not None:
        observation = torch.cat([part_values(observation, part) for part in parts], dim=-1)
    values = observation.float()
    norm = normalisation(env)
    norm.loc.copy_(values.mean(dim=0))
    norm.scale.copy_(values.std(dim=0).clamp_min(MIN_SCALE))
