"""The critic: ``Q(state, action)`` as ``state_action_value`` (the key TorchRL's losses read), an
MLP of ``critic.hidden`` sizes on both, concatenated; with ``critic.layer_norm`` each hidden
layer is layer-normalised, which keeps Q-values from drifting on the narrow data a cloned actor
collects. TD3 clones it into ``critic.ensemble`` critics."""

from __future__ import annotations

from omegaconf import DictConfig
from torch import nn
from torchrl.modules import MLP

from jugglerl.networks.modules import TensorModule


def make_critic(critic_cfg: DictConfig, state_size: int, action_size: int) -> TensorModule:
    hidden = list(critic_cfg.hidden)
    norm = {}
    if critic_cfg.get("layer_norm", False):
        norm = {
            "norm_class": nn.LayerNorm,
            "norm_kwargs": [{"normalized_shape": size} for size in hidden],
        }
    return TensorModule(
        MLP(state_size + action_size, 1, num_cells=hidden, **norm),
        in_keys=["state", "action"],
        out_keys=["state_action_value"],
    )
