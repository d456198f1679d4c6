"""``make_agent``: PPO's Gaussian policy around an actor, the deployed actor and the critic.

The policy's mean is the deterministic actor ``actor`` (``jugglerl.networks.actors``): with the
``residual`` actor, a command's action at the episode's time plus a bounded correction whose last
layer starts at zero, so the untrained policy's mean plays the command exactly. Its standard
deviation is state-independent, ``algo.sigma_init`` at the start (normalised action units) and
learned (``exp`` of a parameter). The actor is what a run deploys and ships: the policy's mean,
without the noise. The critic ``V(state)`` is an MLP of ``critic.hidden`` sizes on the same state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
from omegaconf import DictConfig
from tensordict import TensorDictBase
from tensordict.nn import AddStateIndependentNormalScale, TensorDictModuleBase, TensorDictSequential
from torch import nn
from torchrl.envs import ExplorationType
from torchrl.modules import MLP, IndependentNormal, ProbabilisticActor, ValueOperator

from jugglerl.networks.actors import ACTION_SIZE, build_actor, recurrent_state
from jugglerl.networks.modules import TensorModule

LOC, SCALE = "loc", "scale"


@dataclass
class Agent:
    """``policy`` samples ``action`` (and its log-probability) around ``actor``'s;
    ``critic`` writes ``state_value``."""

    actor: TensorDictModuleBase
    policy: ProbabilisticActor
    critic: ValueOperator


class ActionAsLoc(TensorDictModuleBase):
    """Runs a deterministic actor beside the tensordict and writes its action as ``loc``, so
    that the action a policy sampled (which the loss reads back) is never overwritten."""

    def __init__(self, actor: TensorDictModuleBase):
        super().__init__()
        self.actor = actor
        self.in_keys = list(actor.in_keys)
        self.out_keys = [LOC]

    def forward(self, tensordict: TensorDictBase) -> TensorDictBase:
        acted = self.actor(tensordict.select(*self.in_keys, strict=False))
        return tensordict.set(LOC, acted.get("action"))


def make_agent(cfg: DictConfig, state_size: int, action_size: int = ACTION_SIZE) -> Agent:
    """The actor ``cfg.actor``, the Gaussian policy around it and the critic ``cfg.critic``, on
    a ``state`` of ``state_size`` and actions of ``action_size`` (the juggler's servos)."""
    if recurrent_state(cfg.actor):
        raise ValueError(
            f"actor={cfg.actor.name}: algo=ppo trains feed-forward actors (residual, mlp)"
        )
    sigma = cfg.algo.sigma_init
    if not 0 < sigma <= 1:
        raise ValueError(f"algo.sigma_init={sigma} must be in (0, 1] (normalised action units)")
    actor = build_actor(cfg.actor, state_size, action_size)
    scale = AddStateIndependentNormalScale(action_size, scale_lb=1e-6, init_value=math.log(sigma))
    policy = ProbabilisticActor(
        TensorDictSequential(ActionAsLoc(actor), TensorModule(scale, [LOC], [LOC, SCALE])),
        in_keys=[LOC, SCALE],
        distribution_class=IndependentNormal,
        return_log_prob=True,
        default_interaction_type=ExplorationType.RANDOM,
    )
    body = MLP(state_size, 1, num_cells=list(cfg.critic.hidden), activation_class=nn.Tanh)
    critic = ValueOperator(body, in_keys=["state"])
    return Agent(actor, policy, critic)


def policy_sigma(agent: Agent) -> torch.Tensor:
    """The policy's current standard deviation per action (normalised units)."""
    scale = next(m for m in agent.policy.modules() if isinstance(m, AddStateIndependentNormalScale))
    return scale.state_independent_scale.detach().exp()
