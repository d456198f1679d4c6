"""``lstm``: a recurrent actor (the paper's future work), an LSTM over the state and an MLP head.

TorchRL's ``LSTMModule`` of ``actor.hidden_size`` units, then ``tanh(MLP)`` of ``actor.head``
sizes. Its hidden and cell states are the tensordict entries ``recurrent_state_h`` and
``recurrent_state_c`` (one layer: shape ``[1, hidden_size]``).
"""

from __future__ import annotations

from tensordict.nn import TensorDictSequential
from torch import nn
from torchrl.modules import MLP, LSTMModule

from jugglerl.networks.actors import ACTORS
from jugglerl.networks.modules import TensorModule

HIDDEN, CELL = "recurrent_state_h", "recurrent_state_c"


@ACTORS.register("lstm")
class LSTMActor:
    @staticmethod
    def recurrent_state(actor_cfg) -> dict[str, tuple[int, ...]]:
        return {HIDDEN: (1, actor_cfg.hidden_size), CELL: (1, actor_cfg.hidden_size)}

    @staticmethod
    def features(actor_cfg) -> dict[str, int]:
        return {"memory": actor_cfg.hidden_size}

    @staticmethod
    def build(actor_cfg, state_size: int, action_size: int) -> TensorDictSequential:
        lstm = LSTMModule(
            input_size=state_size,
            hidden_size=actor_cfg.hidden_size,
            in_keys=["state", HIDDEN, CELL],
            out_keys=["memory", ("next", HIDDEN), ("next", CELL)],
        )
        head = MLP(actor_cfg.hidden_size, action_size, num_cells=list(actor_cfg.head))
        return TensorDictSequential(
            lstm, TensorModule(nn.Sequential(head, nn.Tanh()), ["memory"], ["action"])
        )
