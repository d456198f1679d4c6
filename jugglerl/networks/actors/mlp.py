"""``mlp``: a feed-forward actor, ``tanh(MLP(state))`` with hidden sizes ``actor.hidden``."""

from __future__ import annotations

from tensordict.nn import TensorDictSequential
from torch import nn
from torchrl.modules import MLP

from jugglerl.networks.actors import ACTORS, FeedForward
from jugglerl.networks.modules import TensorModule


@ACTORS.register("mlp")
class MLPActor(FeedForward):
    @staticmethod
    def build(actor_cfg, state_size: int, action_size: int) -> TensorDictSequential:
        network = MLP(state_size, action_size, num_cells=list(actor_cfg.hidden))
        return TensorDictSequential(
            TensorModule(nn.Sequential(network, nn.Tanh()), ["state"], ["action"])
        )
