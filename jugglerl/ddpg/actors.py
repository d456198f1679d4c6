"""The networks: a deterministic actor (``mlp``, ``lstm`` or ``residual``) and an MLP critic.

The actors read ``observation`` and write ``action`` in [-1, 1] (the env's action space: a tanh
squashes their output). The residual actor also reads the episode ``time``: its action is a
via-point command's (``CommandReference``) plus a bounded correction of an MLP on the state, so
it starts as that open-loop command and learns only the feedback. The LSTM actor carries its
hidden state in the tensordict (``recurrent_state_h``/``_c``): the env stack needs its primer
(``lstm_primer``), and updates run it on sampled sub-trajectories under
``set_recurrent_mode(True)``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch
from omegaconf import DictConfig
from tensordict.nn import TensorDictModule, TensorDictSequential
from torch import nn
from torchrl.data import TensorSpec
from torchrl.envs import Transform
from torchrl.modules import MLP, LSTMModule

from jugglerl.commands import load_command
from jugglerl.ddpg.reference import CommandReference

ACTORS = ("mlp", "lstm", "residual")


class TensorModule(TensorDictModule):
    """A ``TensorDictModule`` whose outputs, plain tensors, are set straight into the tensordict.

    tensordict 0.14 passes every module output through ``TensorDict.from_any``, which for a plain
    tensor ends in ``importlib.util.find_spec("pandas")``: ≈ 0.15 ms a call on this machine, 5 %
    of a DDPG update (5 network calls) and of a collection step. Anything else (an output
    tensordict, ``inplace=False``) takes the parent's path.
    """

    def _write_to_tensordict(self, tensordict, tensors, tensordict_out=None, out_keys=None):
        if tensordict_out is not None or self.inplace is not True:
            return super()._write_to_tensordict(tensordict, tensors, tensordict_out, out_keys)
        for key, tensor in zip(out_keys or self.out_keys_source, tensors, strict=True):
            if key != "_":
                tensordict.set(key, tensor)
        return tensordict


class ResidualNetwork(nn.Module):
    """``reference(time) + max_correction · tanh(body(observation))``, clipped to [-1, 1].

    The body's last layer starts at zero, so an untrained residual actor plays the reference
    command exactly; ``max_correction`` (normalised action units) bounds how far it may stray.
    """

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

    def forward(self, observation: torch.Tensor, time: torch.Tensor) -> torch.Tensor:
        correction = self.max_correction * torch.tanh(self.body(observation))
        reference = self.reference(time.reshape(observation.shape[:-1]))
        return (reference + correction).clamp(-1.0, 1.0)


def make_actor(
    actor_cfg: DictConfig,
    observation_size: int,
    action_spec: TensorSpec,
    to_action: Callable[[np.ndarray], np.ndarray] | None = None,
):
    """The actor named by ``actor_cfg.name``: ``mlp`` (``hidden`` sizes), ``lstm`` (an LSTM of
    ``hidden_size`` units followed by an MLP head of ``head`` sizes) or ``residual`` (``command``
    plus ``max_correction`` times the tanh of an MLP of ``hidden`` sizes; needs ``to_action``,
    the env's map from servo setpoints to normalised actions)."""
    if actor_cfg.name not in ACTORS:
        raise ValueError(
            f"actor={actor_cfg.name} is not available; choose one of {', '.join(ACTORS)}"
        )
    bounds = action_spec.space
    if not (torch.all(bounds.low == -1) and torch.all(bounds.high == 1)):
        raise ValueError("the actors' tanh output needs actions in [-1, 1]")
    action_size = action_spec.shape[-1]
    if actor_cfg.name == "residual":
        if to_action is None:
            raise ValueError("the residual actor needs the env's to_action mapping")
        reference = CommandReference(load_command(actor_cfg.command), to_action)
        body = MLP(observation_size, action_size, num_cells=list(actor_cfg.hidden))
        network = ResidualNetwork(reference, body, actor_cfg.max_correction)
        return TensorDictSequential(TensorModule(network, ["observation", "time"], ["action"]))
    if actor_cfg.name == "mlp":
        network = MLP(observation_size, action_size, num_cells=list(actor_cfg.hidden))
        return TensorDictSequential(
            TensorModule(nn.Sequential(network, nn.Tanh()), ["observation"], ["action"])
        )
    lstm = LSTMModule(
        input_size=observation_size,
        hidden_size=actor_cfg.hidden_size,
        in_key="observation",
        out_key="memory",
    )
    head = MLP(actor_cfg.hidden_size, action_size, num_cells=list(actor_cfg.head))
    return TensorDictSequential(
        lstm, TensorModule(nn.Sequential(head, nn.Tanh()), ["memory"], ["action"])
    )


def actor_lstm(actor: TensorDictSequential) -> LSTMModule | None:
    """The actor's LSTM (``None`` for an MLP)."""
    return next((m for m in actor.module if isinstance(m, LSTMModule)), None)


def lstm_primer(actor: TensorDictSequential) -> Transform | None:
    """The env transform that adds the LSTM's zero states on reset (``None`` for an MLP)."""
    lstm = actor_lstm(actor)
    return None if lstm is None else lstm.make_tensordict_primer()


def is_recurrent(actor: TensorDictSequential) -> bool:
    return actor_lstm(actor) is not None


def make_critic(critic_cfg: DictConfig, observation_size: int, action_size: int) -> TensorModule:
    """Q(observation, action) as ``state_action_value`` (the key ``DDPGLoss`` reads): an MLP of
    ``critic_cfg.hidden`` sizes on both, concatenated."""
    return TensorModule(
        MLP(observation_size + action_size, 1, num_cells=list(critic_cfg.hidden)),
        in_keys=["observation", "action"],
        out_keys=["state_action_value"],
    )
