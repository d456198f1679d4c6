"""``PPOCheck``: ``algo=ppo``'s learner on a Gymnasium task.

What the juggling trainer (``jugglerl.onpolicy.training``) learns with: the Gaussian policy
around an actor and the critic (``jugglerl.onpolicy.agent``), the update
(``jugglerl.onpolicy.update.PPOUpdate``), the collector that carries episodes across batches and
the normalisation fitted once on the untrained policy's roll-outs (here the sampling policy's,
σ = ``algo.sigma_init``). Torch runs on one thread while collecting, on every core while
learning, as there.
"""

from __future__ import annotations

import torch
from omegaconf import DictConfig
from tensordict import TensorDict
from torchrl.envs.utils import ExplorationType

from jugglerl.batch.env_stack import fit_normalisation_on
from jugglerl.gym_check.run import TaskRun
from jugglerl.onpolicy.agent import make_agent, policy_sigma
from jugglerl.onpolicy.update import PPOUpdate
from jugglerl_envs.batch import usable_cores


class PPOCheck(TaskRun):
    def __init__(self, cfg: DictConfig):
        super().__init__(cfg)
        self.agent = make_agent(cfg, self.state_size, self.action_size)
        self.actor = self.agent.actor
        self.update = PPOUpdate(self.agent, cfg.algo, cfg.optim)
        fit_normalisation_on(
            self.env, self.agent.policy, cfg.norm_frames, None, ExplorationType.RANDOM
        )

    def collect(self, steps: int) -> TensorDict:
        torch.set_num_threads(1)
        return self.collector.collect(self.agent.policy, steps)

    def learn(self, batch: TensorDict) -> dict[str, str]:
        torch.set_num_threads(usable_cores())
        self.update(batch, (self.frames - batch.numel()) / self.cfg.collector.total_frames)
        return {"sigma": f"{float(policy_sigma(self.agent).mean()):.3g}"}
