"""``TimestampFeatures``: the time features the paper's future work asked for, as a transform.

Juggling is periodic: a closed-loop policy that knows where it is in a cycle can time its throws.
The transform appends ``1 + 2 harmonics`` features to the networks' input ``state``,

| feature | meaning |
| --- | --- |
| ``time / duration`` | elapsed episode time, scaled to [0, 1] over an episode |
| ``sin(2π k time / period)`` | phase of a cycle of ``period`` seconds, k = 1 .. ``harmonics`` |
| ``cos(2π k time / period)`` | (sin and cos together make the phase continuous across cycles) |

More harmonics let a network draw the sharp turns of a command in its phase (offline, an MLP
given the teacher's own phase imitated its elbow setpoint with half the error on 8 harmonics
as on one: RMS 0.014 against 0.029). ``phase_features`` is shared with the ball clock
(``jugglerl.state.ball_clock``).

``time`` is the env's own clock (seconds since reset, from its info dict), so the features stay
exact across resets of single sub-envs in a batch.
"""

from __future__ import annotations

import math

import torch
from tensordict import TensorDictBase
from torchrl.envs import Transform

from jugglerl.state.spec import resized


def num_time_features(harmonics: int) -> int:
    """How many features ``time_features`` appends."""
    return 1 + 2 * harmonics


def phase_features(time: torch.Tensor, period: float, harmonics: int) -> torch.Tensor:
    """``[sin(2π k time / period), cos(2π k time / period) for k = 1 .. harmonics]`` along a new
    last dim (``time`` in seconds, any shape)."""
    angle = (2 * math.pi / period) * time.unsqueeze(-1)
    angles = angle * torch.arange(1, harmonics + 1, dtype=time.dtype)
    return torch.stack([torch.sin(angles), torch.cos(angles)], dim=-1).flatten(-2)


def time_features(
    time: torch.Tensor, duration: float, period: float, harmonics: int = 1
) -> torch.Tensor:
    """``[time / duration, *phase_features(time, period, harmonics)]`` along a new last dim.

    ``time`` in seconds, any shape; ``duration`` and ``period`` in seconds.
    """
    phase = phase_features(time, period, harmonics)
    return torch.cat([(time / duration).unsqueeze(-1), phase], dim=-1)


class TimestampFeatures(Transform):
    """Appends ``time_features`` of ``time_key`` to the last dim of ``observation_key``."""

    def __init__(
        self,
        duration: float,
        period: float,
        harmonics: int = 1,
        time_key: str = "time",
        observation_key: str = "state",
    ):
        if duration <= 0 or period <= 0:
            raise ValueError(f"duration={duration} and period={period} must be positive seconds")
        if harmonics < 1:
            raise ValueError(f"state.harmonics={harmonics} must be >= 1")
        super().__init__(in_keys=[time_key, observation_key], out_keys=[observation_key])
        self.duration = float(duration)
        self.period = float(period)
        self.harmonics = int(harmonics)
        self.time_key = time_key
        self.observation_key = observation_key

    def _call(self, tensordict: TensorDictBase) -> TensorDictBase:
        observation = tensordict.get(self.observation_key)
        time = tensordict.get(self.time_key).to(observation.dtype)
        time = time.reshape(observation.shape[:-1])
        features = time_features(time, self.duration, self.period, self.harmonics)
        return tensordict.set(self.observation_key, torch.cat([observation, features], dim=-1))

    forward = _call

    def _reset(self, tensordict: TensorDictBase, tensordict_reset: TensorDictBase):
        return self._call(tensordict_reset)

    def transform_observation_spec(self, observation_spec):
        spec = observation_spec[self.observation_key]
        size = spec.shape[-1] + num_time_features(self.harmonics)
        observation_spec[self.observation_key] = resized(spec, size)
        return observation_spec
