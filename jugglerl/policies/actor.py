"""A trained actor as it is deployed: ``DeployedActor``, one plain module, and ``ActorPolicy``,
the ``Policy`` (observation, time) -> action around it.

``DeployedActor`` feeds the network exactly what it saw in training: the state encoder
(``jugglerl.state.encoder``, built from the training stack's own transforms) and the actor's
modules run on plain tensors (``jugglerl.networks.plain``), bit for bit the actions of the
training stack, at a fraction of its cost per step. Everything it carries from step to step
travels in one tensor, ``memory [N, memory_size]`` float64, zeros at an episode's start: a
started flag, the ball clock's memory and the actor's recurrent state. That makes it one call,
``(observation, time, memory) -> (action, memory)``, which ``scripts/export_policy.py`` traces
into a TorchScript file that runs with plain ``torch``.

``ActorPolicy`` keeps that memory between calls, so ``scripts/evaluate.py``, the periodic
evaluation and the batched episodes run a network on any Gymnasium ``JuggleEnv`` or batch.
"""

from __future__ import annotations

import math

import numpy as np
import torch
from omegaconf import DictConfig, OmegaConf
from tensordict.nn import TensorDictSequential
from torch import nn
from torchrl.envs import Transform

from jugglerl.networks.actors import ACTION_SIZE, build_actor, recurrent_state
from jugglerl.networks.plain import PlainActor
from jugglerl.state.encoder import StateEncoder
from jugglerl.state.transforms import state_size, state_transforms

#: Memory column 0: 1 once a row's episode has taken its first step.
STARTED = 0


class DeployedActor(nn.Module):
    """``forward(observation [N, obs] float64, time [N] float64, memory [N, memory_size]
    float64) -> (action [N, act] float32, memory)``; ``memory_size`` is a buffer (a traced file
    keeps it: ``torch.zeros(N, int(module.memory_size))`` starts an episode)."""

    def __init__(
        self,
        actor: TensorDictSequential,
        transforms: list[Transform],
        recurrent: dict[str, tuple[int, ...]],
    ):
        super().__init__()
        self.encoder = StateEncoder(transforms)
        self.network = PlainActor(actor)
        self.recurrent = {key: tuple(shape) for key, shape in recurrent.items()}
        size = 1 + self.encoder.memory_size + sum(math.prod(s) for s in self.recurrent.values())
        self.register_buffer("memory_size", torch.tensor(size))

    def forward(
        self, observation: torch.Tensor, time: torch.Tensor, memory: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        fresh = memory[:, STARTED] == 0
        clock_end = 1 + self.encoder.memory_size
        state, clock = self.encoder(observation, time, fresh, memory[:, 1:clock_end])
        values = {"state": state, "time": time}
        column = clock_end
        for key, shape in self.recurrent.items():
            size = math.prod(shape)
            stored = memory[:, column : column + size].to(torch.float32)
            values[key] = stored.reshape(-1, *shape)
            column += size
        values = self.network(values)
        carried = [torch.ones_like(memory[:, :1]), clock]
        for key, shape in self.recurrent.items():
            carried.append(values[("next", key)].reshape(-1, math.prod(shape)).to(memory.dtype))
        return values["action"], torch.cat(carried, dim=-1)


class ActorPolicy:
    """Deterministic actions of a ``DeployedActor``, its memory kept from step to step and
    cleared by ``reset()``."""

    #: ``jugglerl.batch.episodes``: a network acts on every env of a batch in one forward pass
    acts_on_batches = True

    def __init__(self, deployed: DeployedActor):
        self.deployed = deployed
        self._memory: torch.Tensor | None = None

    @classmethod
    def of_actor(
        cls,
        actor: TensorDictSequential,
        state_cfg: DictConfig,
        actor_cfg: DictConfig,
        duration: float,
        loc: torch.Tensor,
        scale: torch.Tensor,
    ) -> ActorPolicy:
        """``actor`` (sharing its parameters) on the state ``state_cfg`` with this normalisation."""
        transforms = state_transforms(state_cfg, duration, loc, scale)
        return cls(DeployedActor(actor, transforms, recurrent_state(actor_cfg)))

    @classmethod
    def from_config(
        cls, cfg: DictConfig, weights: dict, normalisation: dict[str, torch.Tensor]
    ) -> ActorPolicy:
        """The actor ``cfg.actor`` with ``weights``, on the state of ``cfg.state``."""
        actor = build_actor(cfg.actor, state_size(cfg.state), ACTION_SIZE)
        actor.load_state_dict(weights)
        return cls.of_actor(
            actor,
            cfg.state,
            cfg.actor,
            cfg.env.duration,
            normalisation["loc"],
            normalisation["scale"],
        )

    @classmethod
    def from_state(cls, state: dict) -> ActorPolicy:
        """The deployed actor of a training checkpoint (``state["policy"]``)."""
        return cls.from_config(
            OmegaConf.create(state["config"]), state["policy"], state["normalisation"]
        )

    def reset(self) -> None:
        self._memory = None

    def act(self, observation: np.ndarray, time, running: np.ndarray | None = None) -> np.ndarray:
        """The action for one env (``observation [obs]``, ``time`` s), or the actions ``[N, act]``
        for a batch (``[N, obs]``, ``[N]``; every row computed, ``running`` or not). A batch
        keeps its size until ``reset()``."""
        observation = torch.as_tensor(observation)
        single = observation.ndim == 1
        observations = observation.reshape(-1, observation.shape[-1])
        rows = observations.shape[0]
        if self._memory is None:
            self._memory = torch.zeros(rows, int(self.deployed.memory_size), dtype=torch.float64)
        times = torch.as_tensor(time, dtype=torch.float64).reshape(rows)
        with torch.inference_mode():
            actions, self._memory = self.deployed(observations, times, self._memory)
        actions = actions.numpy()
        return actions[0] if single else actions
