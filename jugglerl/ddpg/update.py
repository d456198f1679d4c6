"""``DDPGUpdate``: one gradient step of DDPG on a sampled batch, then the soft target update.

The critic regresses TD(0) targets ``r + γ (1 - terminated) Q'(s', μ'(s'))`` from the target
networks; the actor climbs the critic's ``Q(s, μ(s))``; both targets then move by ``tau``
(``θ' ← τ θ + (1 - τ) θ'``). Both losses are back-propagated together before either optimiser
steps: stepping the critic first would change weights the actor's graph still needs.
"""

from __future__ import annotations

import copy

import torch
from omegaconf import DictConfig
from tensordict import TensorDictBase
from tensordict.nn import TensorDictModule
from torchrl.modules import set_recurrent_mode
from torchrl.objectives import DDPGLoss, SoftUpdate, ValueEstimators


class FlatSoftUpdate(SoftUpdate):
    """``SoftUpdate`` that moves all targets with one ``foreach`` lerp over cached tensor lists.

    TorchRL's version walks the parameter TensorDicts (and builds ``.data`` views of them) on
    every step, which costs about 0.6 ms per network on this CPU, a tenth of a whole update. The
    leaves are the loss's own parameters and targets, updated in place by the optimisers and by
    ``load_state_dict``, so the lists gathered once at ``init_`` stay valid. The result is the same
    ``θ' ← θ' + τ (θ - θ')``.
    """

    def init_(self) -> None:
        super().init_()
        self._target_leaves, self._source_leaves = [], []
        for key, source in self._sources.items(include_nested=True, leaves_only=True):
            key = key if isinstance(key, tuple) else (key,)
            self._target_leaves.append(self._targets[("target_" + key[0], *key[1:])])
            self._source_leaves.append(source)

    @torch.no_grad()
    def step(self) -> None:
        torch._foreach_lerp_(self._target_leaves, self._source_leaves, 1 - self.eps)


class DDPGUpdate:
    """Loss, optimisers and target networks of a DDPG agent; call it with a batch to update.

    ``algo_cfg``: ``gamma``, ``tau``; ``optim_cfg``: ``lr_actor``, ``lr_critic``,
    ``weight_decay`` (critic), ``max_grad_norm`` (``null`` = no clipping). With ``recurrent``
    the batch is ``[sub-trajectories, time]`` and the actor runs in recurrent mode.
    """

    def __init__(
        self,
        actor: TensorDictModule,
        critic: TensorDictModule,
        algo_cfg: DictConfig,
        optim_cfg: DictConfig,
        recurrent: bool = False,
    ):
        if not 0 < algo_cfg.tau <= 1:
            raise ValueError(f"algo.tau={algo_cfg.tau} must be in (0, 1]")
        if not 0 <= algo_cfg.gamma < 1:
            raise ValueError(f"algo.gamma={algo_cfg.gamma} must be in [0, 1)")
        self.loss = DDPGLoss(actor, critic, delay_actor=True, delay_value=True)
        self.loss.make_value_estimator(ValueEstimators.TD0, gamma=algo_cfg.gamma)
        self.targets = FlatSoftUpdate(self.loss, tau=algo_cfg.tau)
        self.actor_optimiser = torch.optim.Adam(
            self.loss.actor_network_params.flatten_keys().values(), lr=optim_cfg.lr_actor
        )
        self.critic_optimiser = torch.optim.Adam(
            self.loss.value_network_params.flatten_keys().values(),
            lr=optim_cfg.lr_critic,
            weight_decay=optim_cfg.weight_decay,
        )
        self.max_grad_norm = optim_cfg.max_grad_norm
        self.clipped_groups = [
            [p for group in optimiser.param_groups for p in group["params"]]
            for optimiser in (self.actor_optimiser, self.critic_optimiser)
        ]
        self.recurrent = recurrent

    def __call__(self, batch: TensorDictBase) -> dict[str, float]:
        """One update on ``batch``; returns the actor and critic losses before the step."""
        with set_recurrent_mode(self.recurrent):
            # the two halves of DDPGLoss.forward, without packing them into a TensorDict
            loss_critic, critic_info = self.loss.loss_value(batch)
            loss_actor, _ = self.loss.loss_actor(batch)
        self.actor_optimiser.zero_grad()
        self.critic_optimiser.zero_grad()
        (loss_actor + loss_critic).backward()
        if self.max_grad_norm is not None:
            for params in self.clipped_groups:
                torch.nn.utils.clip_grad_norm_(params, self.max_grad_norm)
        self.actor_optimiser.step()
        self.critic_optimiser.step()
        self.targets.step()
        return {
            "loss_actor": float(loss_actor.detach()),
            "loss_critic": float(loss_critic.detach()),
            "q_value": float(critic_info["pred_value"].detach().mean()),
        }

    def target_actor(self) -> TensorDictModule:
        """A copy of the actor carrying the target (Polyak-averaged) weights."""
        actor = copy.deepcopy(self.loss.actor_network)
        self.loss.target_actor_network_params.data.to_module(actor)
        return actor

    def state_dict(self) -> dict:
        """Networks and their targets, and both optimisers."""
        return {
            "loss": self.loss.state_dict(),
            "actor_optimiser": self.actor_optimiser.state_dict(),
            "critic_optimiser": self.critic_optimiser.state_dict(),
        }

    def load_state_dict(self, state: dict) -> None:
        self.loss.load_state_dict(state["loss"])
        self.actor_optimiser.load_state_dict(state["actor_optimiser"])
        self.critic_optimiser.load_state_dict(state["critic_optimiser"])
