"""``OffPolicyCheck``: the off-policy trainer's RL losses on a Gymnasium task.

The loss plug-in ``algo.loss`` names (``td3``, ``ddpg``: ``jugglerl.offpolicy.losses``, built as
the trainer builds it, with its optimisers, clipping and soft targets) updates an actor of
``jugglerl.networks.actors`` and its critic from uniform samples of a replay buffer of every
frame (TorchRL's ``ReplayBuffer``, up to ``replay_buffer.size``); the envs act with the actor's
action plus Gaussian noise of ``exploration.sigma`` (TorchRL's ``AdditiveGaussianModule``,
clipped to [-1, 1] by the env), uniformly random actions for the first
``collector.init_random_frames``, whose end the updates wait for. The normalisation is fitted on
``norm_frames`` random steps, as the off-policy trainer's is. What it leaves out is the juggling
env, its time features, teachers, stages and evaluations.
"""

from __future__ import annotations

from omegaconf import DictConfig
from tensordict import TensorDict
from tensordict.nn import TensorDictSequential
from torchrl.data import LazyTensorStorage, ReplayBuffer
from torchrl.modules import AdditiveGaussianModule

from jugglerl.batch.env_stack import fit_normalisation_on
from jugglerl.gym_check.run import TaskRun
from jugglerl.networks.actors import build_actor
from jugglerl.offpolicy.losses import LOSSES


class OffPolicyCheck(TaskRun):
    def __init__(self, cfg: DictConfig):
        super().__init__(cfg)
        fit_normalisation_on(self.env, None, cfg.norm_frames, None)  # random actions
        self.actor = build_actor(cfg.actor, self.state_size, self.action_size)
        self.update = LOSSES.get(cfg.algo.loss)(
            self.actor, self.state_size, self.env.action_spec, cfg
        )
        sigma = cfg.exploration.sigma
        noise = AdditiveGaussianModule(
            self.env.action_spec, sigma_init=sigma, sigma_end=sigma, annealing_num_steps=1
        )
        self.policy = TensorDictSequential(self.actor, noise)
        self.buffer = ReplayBuffer(
            storage=LazyTensorStorage(cfg.replay_buffer.size),
            batch_size=cfg.replay_buffer.batch_size,
        )

    def _random(self) -> bool:
        return self.frames < self.cfg.collector.init_random_frames

    def collect(self, steps: int) -> TensorDict:
        return self.collector.collect(self.policy, steps, random=self._random())

    def learn(self, batch: TensorDict) -> dict[str, str]:
        self.buffer.extend(batch.reshape(-1))
        if self._random():
            return {}
        for _ in range(self.cfg.optim.updates_per_batch):
            losses = self.update(self.buffer.sample())
        return {"q": f"{losses['q_value']:.3g}"}
