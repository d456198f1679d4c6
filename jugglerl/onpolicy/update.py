"""``PPOUpdate``: what PPO learns from one collected batch, whatever env it came from.

GAE (TorchRL's ``GAE``, ``algo.gamma`` and ``algo.lmbda``) once per batch with the critic that
collected it, then ``algo.epochs`` passes of TorchRL's ``ClipPPOLoss`` over shuffled minibatches
of ``algo.minibatch_size`` frames: clip ``algo.clip_epsilon``, advantages normalised per
minibatch, an L2 critic of weight ``algo.critic_coeff``, an entropy bonus only when
``algo.entropy_coeff`` > 0. One Adam (``optim.lr``) steps actor, σ and critic together after
their gradients are clipped to ``optim.max_grad_norm`` in norm; with ``optim.anneal_lr`` the
rate falls linearly to 0 over the run. The juggling trainer (``jugglerl.onpolicy.training``) and
the Gymnasium sanity check (``jugglerl.onpolicy.gym_check``) learn through it.
"""

from __future__ import annotations

import numpy as np
import torch
from omegaconf import DictConfig
from tensordict import TensorDict
from torchrl.objectives import ClipPPOLoss
from torchrl.objectives.value import GAE

from jugglerl.onpolicy.agent import Agent

#: What each update logs, as ``ClipPPOLoss`` names it (the first three are summed and minimised).
LOSS_KEYS = ("loss_objective", "loss_critic", "loss_entropy", "kl_approx", "clip_fraction")


class PPOUpdate:
    """Clipped PPO updates of ``agent`` with the ``algo`` and ``optim`` settings of a config."""

    def __init__(self, agent: Agent, algo: DictConfig, optim: DictConfig):
        self.algo, self.optim = algo, optim
        self.advantage = GAE(
            gamma=algo.gamma, lmbda=algo.lmbda, value_network=agent.critic, average_gae=False
        )
        self.loss = ClipPPOLoss(
            agent.policy,
            agent.critic,
            clip_epsilon=algo.clip_epsilon,
            entropy_bonus=algo.entropy_coeff > 0,
            entropy_coeff=algo.entropy_coeff,
            critic_coeff=algo.critic_coeff,
            loss_critic_type="l2",
            normalize_advantage=True,
        )
        self.optimizer = torch.optim.Adam(self.loss.parameters(), lr=optim.lr)

    def __call__(self, batch: TensorDict, done: float) -> tuple[dict[str, float], int]:
        """Learn from ``batch`` (``[envs, steps]``, as collected), ``done`` the share of the
        run's frames before it (for the annealed rate); the mean losses, the mean value, the
        learning rate, and the number of gradient steps taken."""
        if self.optim.anneal_lr:
            for group in self.optimizer.param_groups:
                group["lr"] = self.optim.lr * (1 - done)
        parameters = list(self.loss.parameters())
        totals: dict[str, list[float]] = {key: [] for key in LOSS_KEYS}
        with torch.no_grad():
            self.advantage(batch)
        flat = batch.reshape(-1)
        steps = 0
        for _ in range(self.algo.epochs):
            for indices in torch.randperm(flat.numel()).split(self.algo.minibatch_size):
                losses = self.loss(flat[indices])
                objective = sum(losses[k] for k in LOSS_KEYS[:3] if k in losses)
                self.optimizer.zero_grad()
                objective.backward()
                torch.nn.utils.clip_grad_norm_(parameters, self.optim.max_grad_norm)
                self.optimizer.step()
                steps += 1
                for key in LOSS_KEYS:
                    if key in losses:
                        totals[key].append(float(losses[key].detach()))
        record = {key: float(np.mean(values)) for key, values in totals.items() if values}
        record["value"] = float(batch["state_value"].mean())
        record["lr"] = self.optimizer.param_groups[0]["lr"]
        return record, steps

    def state_dict(self) -> dict:
        return self.optimizer.state_dict()

    def load_state_dict(self, state: dict) -> None:
        self.optimizer.load_state_dict(state)
