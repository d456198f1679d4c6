"""``residual``: a via-point command's setpoint plus a bounded, learned correction.

``reference(time) + max_correction · tanh(MLP(state))``, clipped to [-1, 1]: the command is
``actor.command`` (``CommandReference``), the MLP has ``actor.hidden`` sizes and its last layer
starts at zero, so an untrained residual actor plays the command exactly and training learns
only the feedback the open-loop command lacks. ``actor.max_correction`` (normalised action units)
bounds how far it may stray.
"""

from __future__ import annotations

import torch
from tensordict.nn import TensorDictSequential
from torch import nn
from torchrl.modules import MLP

from jugglerl.commands import load_command
from jugglerl.networks.actors import ACTORS, FeedForward
from jugglerl.networks.modules import TensorModule
from jugglerl.networks.reference import CommandReference


class ResidualNetwork(nn.Module):
    def __init__(self, reference: CommandReference, body: MLP, max_correction: float):
        super().__init__()
        if not 0 < max_correction <= 2:
            raise ValueError(f"actor.max_correction={max_correction} must be in (0, 2]")
        self.reference = reference
        self.body = body
        self.max_correction = float(max_correction)
        last = body[-1]
        nn.init.zeros_(last.weight)
        nn.init.zeros_(last.bias)

    def forward(self, state: torch.Tensor, time: torch.Tensor) -> torch.Tensor:
        correction = self.max_correction * torch.tanh(self.body(state))
        reference = self.reference(time.reshape(state.shape[:-1]))
        return (reference + correction).clamp(-1.0, 1.0)


@ACTORS.register("residual")
class ResidualActor(FeedForward):
    @staticmethod
    def build(actor_cfg, state_size: int, action_size: int) -> TensorDictSequential:
        reference = CommandReference(load_command(actor_cfg.command))
        body = MLP(state_size, action_size, num_cells=list(actor_cfg.hidden))
        network = ResidualNetwork(reference, body, actor_cfg.max_correction)
        return TensorDictSequential(TensorModule(network, ["state", "time"], ["action"]))
