"""``StateEncoder``: the networks' ``state`` from an observation and a time, as one plain module.

It computes what ``state_transforms`` (the training env stack's TorchRL transforms) compute, the
same operations in the same order, so the numbers are equal bit for bit: the observation cast to
float32, cut to ``state.observe``'s parts, normalised, then the time features and the ball clock.
Being plain tensor operations on one ``nn.Module``, it costs a deployed actor no TensorDict per
step and traces into a file that runs without JuggleRL (``scripts/export_policy.py``).

Its only memory is the ball clock's, ``clock [N, 2]`` float64: the last lock time and whether the
clock is armed (``CLOCK_SIZE`` values, none without the clock).
"""

from __future__ import annotations

import torch
from torch import nn
from torchrl.envs import DoubleToFloat, ObservationNorm, RenameTransform, Transform

from jugglerl.state.ball_clock import BallClock, clock_step
from jugglerl.state.observation_parts import OBSERVED_SIZE, ObservationParts, part_values
from jugglerl.state.timestamp import TimestampFeatures, phase_features, time_features

#: Values of the ball clock's memory: the lock time and the armed flag.
CLOCK_SIZE = 2


class StateEncoder(nn.Module):
    """``forward(observation [N, 18] float64, time [N] float64, fresh [N] bool, clock [N, 2])``
    -> ``(state [N, S] float32, clock)``; ``fresh`` rows start their episode at this step.

    Built from the transforms ``state_transforms`` returns, whose settings it reads, so the two
    cannot drift apart: a transform it does not know is refused."""

    def __init__(self, transforms: list[Transform]):
        super().__init__()
        self.parts: tuple[str, ...] | None = None
        self.stamp: tuple[float, float, int] | None = None  # duration, period, harmonics
        self.clock: tuple[float, int, float, float] | None = (
            None  # period, harmonics, height, rearm
        )
        for transform in transforms:
            if isinstance(transform, RenameTransform | DoubleToFloat):
                continue  # the float32 copy of the observation that ``forward`` starts from
            if isinstance(transform, ObservationParts):
                self.parts = transform.parts
            elif isinstance(transform, ObservationNorm):
                self.register_buffer("loc", transform.loc.detach().clone())
                self.register_buffer("scale", transform.scale.detach().clone())
            elif isinstance(transform, TimestampFeatures):
                self.stamp = (transform.duration, transform.period, transform.harmonics)
            elif isinstance(transform, BallClock):
                clock = transform
                self.clock = (clock.period, clock.harmonics, clock.height, clock.rearm)
            else:
                raise TypeError(f"StateEncoder: no plain form of {type(transform).__name__}")

    @property
    def observation_size(self) -> int:
        """How many observation values it reads: the whole observation it was normalised on, or
        the first ``OBSERVED`` ones that its parts cut from."""
        return self.loc.numel() if self.parts is None else OBSERVED_SIZE

    @property
    def memory_size(self) -> int:
        return CLOCK_SIZE if self.clock is not None else 0

    def forward(
        self,
        observation: torch.Tensor,
        time: torch.Tensor,
        fresh: torch.Tensor,
        clock: torch.Tensor,
    ) -> tuple[torch.Tensor, torch.Tensor]:
        state = observation.to(torch.float32)
        if self.parts is not None:
            state = torch.cat([part_values(state, part) for part in self.parts], dim=-1)
        state = (state - self.loc) / self.scale
        if self.stamp is not None:
            state = torch.cat([state, time_features(time.to(state.dtype), *self.stamp)], dim=-1)
        if self.clock is not None:
            period, harmonics, height, rearm = self.clock
            lock, armed = clock_step(
                observation, time, fresh, clock[:, 0], clock[:, 1] > 0, height, rearm
            )
            features = phase_features(time - lock, period, harmonics).to(state.dtype)
            state = torch.cat([state, features], dim=-1)
            clock = torch.stack([lock, armed.to(lock.dtype)], dim=-1)
        return state, clock
