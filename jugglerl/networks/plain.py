"""``PlainActor``: an actor's modules run on plain tensors, without TensorDicts.

An actor (``jugglerl.networks.actors``) is a ``TensorDictSequential`` of modules that read and
write named entries: ``TensorDictModule`` s around plain ``nn.Module`` s, and TorchRL's
``LSTMModule``. Stepping it through TensorDicts costs far more than the arithmetic at the size of
one env (about 85 % of a deployed step). ``PlainActor`` holds the same modules (the same
parameters, shared) and passes the named tensors between them in a dict, calling each module's
own network: an ``LSTMModule`` as its ``nn.LSTM`` on a sequence of one step, as TorchRL does
outside recurrent mode. So its actions equal the actor's bit for bit, and it traces to a file.

With ``sequences`` it runs sub-trajectories ``[B, T]`` instead, as TorchRL's recurrent mode runs
the pieces of one episode each that the replay buffer samples: the ``nn.LSTM`` over each piece
from the recurrent state stored at its first step (about half the time of a cloning update's
forward pass goes to the TensorDicts around it). A piece in which an episode starts after its
first step needs TorchRL's splitting (``starts_inside``): the caller runs the actor instead.
"""

from __future__ import annotations

import torch
from tensordict.nn import TensorDictModule, TensorDictSequential
from torch import nn
from torchrl.modules import LSTMModule


class _LSTMStep(nn.Module):
    """One step of an ``LSTMModule``'s ``nn.LSTM``: ``[N, in]`` and states ``[N, layers,
    hidden]`` under its keys to its outputs, as TorchRL runs it outside recurrent mode."""

    def __init__(self, module: LSTMModule):
        super().__init__()
        self.lstm = module.lstm
        self.in_keys = list(module.in_keys[:3])  # then is_init: zero states start an episode
        self.out_keys = list(module.out_keys)

    def forward(self, values: dict) -> None:
        value_key, hidden_key, cell_key = self.in_keys
        hidden = tuple(values[key].transpose(0, 1).contiguous() for key in (hidden_key, cell_key))
        output, (hidden_out, cell_out) = self.lstm(values[value_key].unsqueeze(1), hidden)
        output_key, next_hidden_key, next_cell_key = self.out_keys
        values[output_key] = output.squeeze(1)
        values[next_hidden_key] = hidden_out.transpose(0, 1)
        values[next_cell_key] = cell_out.transpose(0, 1)


class _LSTMSequence(_LSTMStep):
    """An ``LSTMModule``'s ``nn.LSTM`` over sub-trajectories ``[B, T, in]``, each from the
    recurrent state stored at its first step, as TorchRL runs it in recurrent mode."""

    def forward(self, values: dict) -> None:
        value_key, hidden_key, cell_key = self.in_keys
        hidden = tuple(
            values[key][:, 0].transpose(0, 1).contiguous() for key in (hidden_key, cell_key)
        )
        output, _ = self.lstm(values[value_key], hidden)
        values[self.out_keys[0]] = output


class _ModuleStep(nn.Module):
    """A ``TensorDictModule``'s own network, called on the tensors under its keys."""

    def __init__(self, module: TensorDictModule):
        super().__init__()
        self.module = module.module
        self.in_keys = list(module.in_keys)
        self.out_keys = list(module.out_keys)

    def forward(self, values: dict) -> None:
        outputs = self.module(*(values[key] for key in self.in_keys))
        if isinstance(outputs, torch.Tensor):
            outputs = (outputs,)
        for key, output in zip(self.out_keys, outputs, strict=True):
            values[key] = output


class PlainActor(nn.Module):
    """``forward(values)``: ``values`` (``state``, ``time``, the recurrent state) with the
    actor's outputs added (``action``; one step at a time, ``("next", key)`` for each recurrent
    key)."""

    def __init__(self, actor: TensorDictSequential, sequences: bool = False):
        super().__init__()
        self.in_keys = list(actor.in_keys)
        steps = []
        for module in actor.module:
            if isinstance(module, LSTMModule):
                steps.append(_LSTMSequence(module) if sequences else _LSTMStep(module))
            elif isinstance(module, TensorDictModule):
                steps.append(_ModuleStep(module))
            else:
                raise TypeError(f"PlainActor: no plain form of {type(module).__name__}")
        self.steps = nn.ModuleList(steps)

    def forward(self, values: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        values = dict(values)
        for step in self.steps:
            step(values)
        return values


def starts_inside(is_init: torch.Tensor) -> bool:
    """Whether an episode starts after the first step of a sub-trajectory of ``is_init``
    (``[B, T, 1]``), where ``PlainActor(sequences=True)`` would carry a state across it."""
    return bool(is_init[:, 1:].any())
