"""``Update``: the optimisers, gradient clipping and soft target update the losses share.

An update back-propagates all its loss terms together before any optimiser steps: stepping the
critic first would change weights the actor's graph still needs. The targets then move by
``algo.tau`` (``θ' ← τ θ + (1 - τ) θ'``) through ``FlatSoftUpdate``.
"""

from __future__ import annotations

import copy

import torch
from omegaconf import DictConfig, OmegaConf
from tensordict.nn import TensorDictModule
from torchrl.objectives import LossModule, SoftUpdate

from jugglerl.networks.actors.correction import trained_parameters


class FlatSoftUpdate(SoftUpdate):
    """``SoftUpdate`` that moves all targets with one ``foreach`` lerp over cached tensor lists.

    TorchRL's version walks the parameter TensorDicts (and builds ``.data`` views of them) on
    every step, ≈ 0.6 ms per network on this CPU, a tenth of a whole update. The leaves are the
    loss's own parameters and targets, updated in place by the optimisers and by
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


#: What an RL loss reads beyond configs/offpolicy.yaml: configs/critic.yaml and the discounting.
RL_KEYS = ("critic", "optim.lr_critic", "optim.weight_decay", "algo.gamma", "algo.tau")


def check_rl_config(cfg: DictConfig, keys: tuple[str, ...] = ()) -> None:
    """``ValueError`` for an RL loss's settings (``RL_KEYS`` and its own ``keys``) that are
    missing or out of range."""
    missing = [key for key in (*RL_KEYS, *keys) if OmegaConf.select(cfg, key) is None]
    if missing:
        raise ValueError(
            f"algo.loss={cfg.algo.loss} needs {', '.join(missing)} (configs/critic.yaml and the"
            " discounting, which algo=ddpg|td3 and +experiment=apprentice_rl compose)"
        )
    algo = cfg.algo
    if not 0 < algo.tau <= 1:
        raise ValueError(f"algo.tau={algo.tau} must be in (0, 1]")
    if not 0 <= algo.gamma < 1:
        raise ValueError(f"algo.gamma={algo.gamma} must be in [0, 1)")
    if algo.bc_weight < 0:
        raise ValueError(f"algo.bc_weight={algo.bc_weight} must be >= 0")


class Update:
    """Adam for the part of the actor the stage trains (``optim.trains``: its base or its
    correction, ``jugglerl.networks.actors.correction``; ``optim.lr_actor``) and, given
    ``critic_params``, for the critics (``optim.lr_critic``, ``optim.weight_decay``); clipping
    at ``optim.max_grad_norm`` (``null``: none); soft targets of ``loss`` with ``algo.tau`` when
    it has targets."""

    @classmethod
    def check_config(cls, cfg: DictConfig) -> None:
        """Raise ``ValueError`` naming a setting of ``cfg`` (a stage's) this loss cannot run with:
        the stages check each stage's as the run starts, before any loss is built."""

    def __init__(
        self,
        loss: LossModule,
        actor_params,
        critic_params,
        optim_cfg: DictConfig,
        tau: float | None,
    ):
        self.loss = loss
        trains = optim_cfg.get("trains", "base")
        actor_params = trained_parameters(loss.actor_network, actor_params, trains)
        self.actor_optimiser = torch.optim.Adam(actor_params, lr=optim_cfg.lr_actor)
        self.critic_optimiser = (
            None
            if critic_params is None
            else torch.optim.Adam(
                critic_params, lr=optim_cfg.lr_critic, weight_decay=optim_cfg.weight_decay
            )
        )
        self.targets = None if tau is None else FlatSoftUpdate(loss, tau=tau)
        #: the entries of a sampled batch the update reads (``None``: all of them)
        self.reads: list | None = None
        self.bc_weight = 0.0  # the RL losses' cloning weight; a stage may anneal it
        self.actor_frozen = False  # a stage's critic warm-up: only the critics step
        self.max_grad_norm = optim_cfg.max_grad_norm
        self.clipped_groups = [
            [p for group in optimiser.param_groups for p in group["params"]]
            for optimiser in self.optimisers
        ]

    @property
    def optimisers(self) -> list[torch.optim.Optimizer]:
        return [o for o in (self.actor_optimiser, self.critic_optimiser) if o is not None]

    def apply(self, total: torch.Tensor, step_actor: bool = True) -> None:
        """Back-propagate ``total``, clip, step the optimisers (the actor's only when
        ``step_actor`` and not ``actor_frozen``) and, with ``step_actor``, the targets (a frozen
        actor's target stays equal to it)."""
        for optimiser in self.optimisers:
            optimiser.zero_grad()
        total.backward()
        if self.max_grad_norm is not None:
            for params in self.clipped_groups:
                torch.nn.utils.clip_grad_norm_(params, self.max_grad_norm)
        if step_actor and not self.actor_frozen:
            self.actor_optimiser.step()
        if self.critic_optimiser is not None:
            self.critic_optimiser.step()
        if step_actor and self.targets is not None:  # during a warm-up too: the critics'
            self.targets.step()  # targets must follow them for values to reach past n steps

    def target_actor(self) -> TensorDictModule:
        """A copy of the actor carrying the target (Polyak-averaged) weights."""
        actor = copy.deepcopy(self.loss.actor_network)
        self.loss.target_actor_network_params.data.to_module(actor)
        return actor

    def state_dict(self) -> dict:
        """Networks and their targets, and the optimisers."""
        return {
            "loss": self.loss.state_dict(),
            "optimisers": [optimiser.state_dict() for optimiser in self.optimisers],
        }

    def load_state_dict(self, state: dict) -> None:
        self.loss.load_state_dict(state["loss"])
        for optimiser, saved in zip(self.optimisers, state["optimisers"], strict=True):
            optimiser.load_state_dict(saved)
