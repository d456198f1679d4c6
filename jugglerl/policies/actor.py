"""``ActorPolicy``: a trained actor as a plain ``Policy`` (observation, time) -> action.

It feeds the actor exactly what it saw in training, through the same transforms
(``state_transforms``: the state copy, its cast, normalisation, time features and ball clock),
and carries the actor's recurrent state and the transforms' memory (``carried_keys``) from step
to step, so ``scripts/evaluate.py`` and the periodic
evaluation run any Gymnasium ``JuggleEnv`` (with recorders or perturbations wrapped around it)
without TorchRL's env stack.
"""

from __future__ import annotations

import numpy as np
import torch
from omegaconf import DictConfig, OmegaConf
from tensordict import TensorDict
from tensordict.nn import TensorDictSequential
from torchrl.envs import Transform
from torchrl.envs.utils import ExplorationType, set_exploration_type

from jugglerl.networks.actors import ACTION_SIZE, build_actor, recurrent_state
from jugglerl.state.transforms import state_size, state_transforms


class ActorPolicy:
    """Deterministic actions of ``actor`` on observations passed through ``transforms``;
    ``recurrent`` is the actor's recurrent state (``{key: shape}``), zero at each episode's
    start."""

    def __init__(
        self,
        actor: TensorDictSequential,
        transforms: list[Transform],
        recurrent: dict[str, tuple[int, ...]],
    ):
        self.actor = actor
        self.transforms = transforms
        self.recurrent = recurrent
        self._memory: TensorDict | None = None

    @classmethod
    def from_config(
        cls, cfg: DictConfig, weights: dict, normalisation: dict[str, torch.Tensor]
    ) -> ActorPolicy:
        """The actor ``cfg.actor`` with ``weights``, on the state of ``cfg.state``."""
        transforms = state_transforms(
            cfg.state, cfg.env.duration, normalisation["loc"], normalisation["scale"]
        )
        actor = build_actor(cfg.actor, state_size(cfg.state), ACTION_SIZE)
        actor.load_state_dict(weights)
        return cls(actor, transforms, recurrent_state(cfg.actor))

    @classmethod
    def from_state(cls, state: dict) -> ActorPolicy:
        """The deployed actor of a training checkpoint (``state["policy"]``)."""
        return cls.from_config(
            OmegaConf.create(state["config"]), state["policy"], state["normalisation"]
        )

    def reset(self) -> None:
        self._memory = None

    #: ``jugglerl.batch.episodes``: a network acts on every env of a batch in one forward pass
    acts_on_batches = True

    def act(self, observation: np.ndarray, time, running: np.ndarray | None = None) -> np.ndarray:
        """The action for one env (``observation [obs]``, ``time`` s), or the actions ``[N, act]``
        for a batch (``[N, obs]``, ``[N]``; every row computed, ``running`` or not). A batch
        keeps its size until ``reset()``."""
        observation = torch.as_tensor(observation)
        single = observation.ndim == 1
        observations = observation.reshape(-1, observation.shape[-1])
        rows = observations.shape[0]
        first = self._memory is None
        data = TensorDict(
            {
                "observation": observations,
                "time": torch.as_tensor(time, dtype=torch.float64).reshape(rows),
                "is_init": torch.full((rows, 1), first),
            },
            batch_size=[rows],
        )
        if first:
            self._memory = TensorDict(
                {key: torch.zeros(rows, *shape) for key, shape in self.recurrent.items()},
                batch_size=[rows],
            )
        data.update(self._memory)
        for transform in self.transforms:
            data = transform(data)
        with torch.no_grad(), set_exploration_type(ExplorationType.DETERMINISTIC):
            data = self.actor(data)
        # the next step starts from the state this one left: the actor's and the transforms'
        memory = {key: data.get(("next", key)) for key in self.recurrent}
        for transform in self.transforms:
            memory.update({key: data.get(key) for key in getattr(transform, "carried_keys", ())})
        self._memory = TensorDict(memory, batch_size=[rows])
        actions = data["action"].numpy()
        return actions[0] if single else actions
