"""``ActorPolicy``: a trained actor as a plain ``Policy`` (observation, time) -> action.

It feeds the actor exactly what it saw in training, through the same transforms
(``observation_transforms``: normalisation and time features), and carries an LSTM's state from
step to step, so ``scripts/evaluate.py`` and the periodic evaluation run any Gymnasium
``JuggleEnv`` (with recorders or perturbations wrapped around it) without TorchRL's env stack.
"""

from __future__ import annotations

import numpy as np
import torch
from omegaconf import OmegaConf
from tensordict import TensorDict
from tensordict.nn import TensorDictSequential
from torchrl.data import Bounded
from torchrl.envs import Transform
from torchrl.envs.utils import ExplorationType, set_exploration_type

from jugglerl.config import action_mapping
from jugglerl.ddpg.actors import actor_lstm, make_actor
from jugglerl.ddpg.env_stack import ACTION_SIZE, OBSERVATION_SIZE, observation_transforms
from jugglerl.ddpg.timestamp import NUM_TIME_FEATURES


class ActorPolicy:
    """Deterministic actions of ``actor`` on observations passed through ``transforms``."""

    def __init__(self, actor: TensorDictSequential, transforms: list[Transform]):
        self.actor = actor
        self.transforms = transforms
        self._lstm = actor_lstm(actor)
        self._memory: TensorDict | None = None

    @classmethod
    def from_state(cls, state: dict) -> ActorPolicy:
        """The deployed actor of a DDPG checkpoint (``DDPGTraining.state_dict``'s ``policy``)."""
        cfg = OmegaConf.create(state["config"])
        transforms = observation_transforms(
            cfg.state,
            cfg.env.duration,
            state["normalisation"]["loc"],
            state["normalisation"]["scale"],
        )
        observation_size = OBSERVATION_SIZE + (NUM_TIME_FEATURES if cfg.state.timestamp else 0)
        action_spec = Bounded(-1.0, 1.0, shape=(ACTION_SIZE,))
        actor = make_actor(cfg.actor, observation_size, action_spec, action_mapping(cfg.env))
        actor.load_state_dict(state["policy"])
        return cls(actor, transforms)

    def reset(self) -> None:
        self._memory = None

    def act(self, observation: np.ndarray, time: float) -> np.ndarray:
        first = self._memory is None
        data = TensorDict(
            {
                "observation": torch.as_tensor(observation, dtype=torch.float32).unsqueeze(0),
                "time": torch.tensor([time], dtype=torch.float32),
                "is_init": torch.tensor([[first]]),
            },
            batch_size=[1],
        )
        if self._lstm is not None:
            data.update(self._lstm_state(data) if first else self._memory)
        for transform in self.transforms:
            data = transform(data)
        with torch.no_grad(), set_exploration_type(ExplorationType.DETERMINISTIC):
            data = self.actor(data)
        self._memory = TensorDict(batch_size=[1])
        if self._lstm is not None:  # the next step starts from the state this one left
            for state_key, next_key in zip(
                self._lstm.in_keys[1:3], self._lstm.out_keys[1:3], strict=True
            ):
                self._memory.set(state_key, data.get(next_key))
        return data["action"][0].numpy()

    def _lstm_state(self, data: TensorDict) -> TensorDict:
        """Zero LSTM states, as the env stack's primer writes them on reset."""
        return self._lstm.make_tensordict_primer().primers.zero(data.batch_size)
