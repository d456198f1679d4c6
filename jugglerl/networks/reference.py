"""``CommandReference``: a via-point command's normalised action at episode times, in torch.

The residual actor adds its correction to this reference, and the expert-centred exploration
draws around it; both need it on batches of times inside the networks' forward passes (the
replay buffer's sampled transitions, the env batch), so it is a module with the via-points as
buffers rather than a call into NumPy per sample.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn

from jugglerl.commands import ViaPointCommand
from jugglerl_envs.actions import ctrl_to_action


class CommandReference(nn.Module):
    """``forward(time)``: the action the command holds at ``time`` seconds, shape ``time.shape +
    (3,)``."""

    def __init__(self, command: ViaPointCommand):
        super().__init__()
        times = np.array([point[0] for point in command.via_points])
        self.register_buffer("times", torch.as_tensor(times, dtype=torch.float32))
        actions = ctrl_to_action(command.cycle_setpoints(times))  # what each via-point holds
        self.register_buffer("actions", torch.as_tensor(actions, dtype=torch.float32))
        self.cycle = float(command.cycle)
        self.lead_in = float(command.lead_in)

    def forward(self, time: torch.Tensor) -> torch.Tensor:
        cycle_time = (time.to(self.times.dtype) - self.lead_in).clamp(min=0.0)
        phase = torch.remainder(cycle_time, self.cycle)
        index = torch.searchsorted(self.times, phase.contiguous(), right=True) - 1  # -1: the last
        return self.actions[index]
