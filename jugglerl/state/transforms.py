"""``state_transforms``: the networks' ``state`` from the env's observation, as TorchRL
transforms; ``state_size``: how many values it holds.

``state`` is 3 normalised values per observed part (18 for all six) plus, with the timestamp,
``1 + 2 harmonics`` time features and, with the ball clock, ``2 harmonics`` more. The training
env stack appends these transforms to the batched env; a deployed actor runs them on its own
observations, so both see exactly the same inputs.
"""

from __future__ import annotations

import torch
from omegaconf import DictConfig
from torchrl.envs import DoubleToFloat, ObservationNorm, RenameTransform, Transform

from jugglerl.state.ball_clock import BallClock, num_ball_clock_features
from jugglerl.state.observation_parts import (
    PART_SIZE,
    WHOLE_OBSERVATION,
    ObservationParts,
    observed_parts,
)
from jugglerl.state.timestamp import TimestampFeatures, num_time_features
from jugglerl_envs.validation import check_number


def _harmonics(state_cfg: DictConfig) -> int:
    return state_cfg.get("harmonics", 1)  # runs saved before the key existed had one


def normalised_size(state_cfg: DictConfig) -> int:
    """How many values of ``state`` the normalisation standardises: the observed parts."""
    return PART_SIZE * len(observed_parts(state_cfg))


def state_size(state_cfg: DictConfig) -> int:
    """Size of the networks' input ``state``: the observed parts and, optionally, time features
    and the ball clock."""
    harmonics = _harmonics(state_cfg)
    size = normalised_size(state_cfg)
    size += num_time_features(harmonics) if state_cfg.timestamp else 0
    return size + (num_ball_clock_features(harmonics) if state_cfg.get("ball_clock") else 0)


def state_transforms(
    state_cfg: DictConfig, duration: float, loc: torch.Tensor | None, scale: torch.Tensor | None
) -> list[Transform]:
    """``state`` from the observation: copied, cast to float32, cut to ``state.observe``'s parts,
    normalised and (with ``state_cfg.timestamp``, ``state_cfg.ball_clock``) given the time
    features and the ball clock.

    ``loc``/``scale`` of ``None`` leave the normalisation to be fitted by ``fit_normalisation``.
    """
    transforms: list[Transform] = [
        RenameTransform(["observation"], ["state"], create_copy=True),
        DoubleToFloat(in_keys=["state"]),
    ]
    parts = observed_parts(state_cfg)
    if parts != WHOLE_OBSERVATION:
        transforms.append(ObservationParts(parts))
    norm = ObservationNorm(loc=loc, scale=scale, in_keys=["state"], standard_normal=True)
    transforms.append(norm)
    harmonics = _harmonics(state_cfg)
    if state_cfg.timestamp or state_cfg.get("ball_clock"):
        check_number("state.period", state_cfg.get("period"), 0, low_open=True)
    if state_cfg.timestamp:
        transforms.append(TimestampFeatures(duration, state_cfg.period, harmonics))
    if state_cfg.get("ball_clock"):
        transforms.append(BallClock(state_cfg.period, harmonics, state_cfg.ball_clock_height))
    return transforms
