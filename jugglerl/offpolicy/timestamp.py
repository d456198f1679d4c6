"""``TimestampFeatures``: the time features the paper's future work asked for, as a transform.

Juggling is periodic: a closed-loop policy that knows where it is in a cycle can time its throws.
The transform appends three features to the networks' input ``state``,

| feature | meaning |
| --- | --- |
| ``time / duration`` | elapsed episode time, scaled to [0, 1] over an episode |
| ``sin(2π time / period)`` | phase of a cycle of ``period`` seconds |
| ``cos(2π time / period)`` | (sin and cos together make the phase continuous across cycles) |

``time`` is the env's own clock (seconds since reset, from its info dict), so the features stay
exact across resets of single sub-envs in a batch.
"""

from __future__ import annotations

import math

import torch
from tensordict import TensorDictBase
from torchrl.data import Unbounded
from torchrl.envs import Transform

#: How many features ``time_features`` appends.
NUM_TIME_FEATURES = 3


def time_features(time: torch.Tensor, duration: float, period: float) -> torch.Tensor:
    """``[time / duration, sin(2π time / period), cos(2π time / period)]`` along a new last dim.

    ``time`` in seconds, any shape; ``duration`` and ``period`` in seconds.
    """
    angle = (2 * math.pi / period) * time
    return torch.stack([time / duration, torch.sin(angle), torch.cos(angle)], dim=-1)


class TimestampFeatures(Transform):
    """Appends ``time_features`` of ``time_key`` to the last dim of ``observation_key``."""

    def __init__(
        self,
        duration: float,
        period: float,
        time_key: str = "time",
        observation_key: str = "state",
    ):
        if duration <= 0 or period <= 0:
            raise ValueError(f"duration={duration} and period={period} must be positive seconds")
        super().__init__(in_keys=[time_key, observation_key], out_keys=[observation_key])
        self.duration = float(duration)
        self.period = float(period)
        self.time_key = time_key
        self.observation_key = observation_key

    def _call(self, tensordict: TensorDictBase) -> TensorDictBase:
        observation = tensordict.get(self.observation_key)
        time = tensordict.get(self.time_key).to(observation.dtype)
        features = time_features(time.reshape(observation.shape[:-1]), self.duration, self.period)
        return tensordict.set(self.observation_key, torch.cat([observation, features], dim=-1))

    forward = _call

    def _reset(self, tensordict: TensorDictBase, tensordict_reset: TensorDictBase):
        return self._call(tensordict_reset)

    def transform_observation_spec(self, observation_spec):
        spec = observation_spec[self.observation_key]
        observation_spec[self.observation_key] = Unbounded(
            shape=(*spec.shape[:-1], spec.shape[-1] + NUM_TIME_FEATURES),
            dtype=spec.dtype,
            device=spec.device,
        )
        return observation_spec
