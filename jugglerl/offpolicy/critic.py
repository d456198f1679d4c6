"""The critic: ``Q(state, action)`` as ``state_action_value`` (the key TorchRL's losses read), an
MLP of ``critic.hidden`` sizes on both, concatenated. TD3 clones it into its twin critics."""

from __future__ import annotations

from omegaconf import DictConfig
from torchrl.modules import MLP

from jugglerl.offpolicy.modules import TensorModule


def make_critic(critic_cfg: DictConfig, state_size: int, action_size: int) -> TensorModule:
    return TensorModule(
        MLP(state_size + action_size, 1, num_cells=list(critic_cfg.hidden)),
        in_keys=["state", "action"],
        out_keys=["state_action_value"],
    )
