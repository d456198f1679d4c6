"""``td3``: TorchRL's ``TD3Loss``: twin critics, target policy smoothing, delayed actor updates.

The ``critic.ensemble`` critics (2: TD3's twins) each regress
``r + γ^m (1 - terminated) min_k Q'_k(s', μ'(s') + clip(σ ε, ±c))`` (``m``: the transition's
``steps_to_next_obs``, ``jugglerl.offpolicy.n_step``) with
``σ = algo.policy_noise`` and ``c = algo.noise_clip`` (normalised action units); the actor
(plus ``algo.bc_weight`` times the behaviour-cloning loss) and the targets move only every
``algo.policy_delay`` updates.

The actor climbs the first critic (TD3's), or with ``algo.pessimism`` = β the ensemble's
``mean_k Q_k(s, μ(s)) - β std_k Q_k(s, μ(s))``: where the critics disagree (actions the data
hardly covers, such as the small corrections of a residual RL stage) the gradient is their
uncertainty's, not one critic's noise (ensemble pessimism, as in SAC-N/EDAC).
"""

from __future__ import annotations

import torch
from tensordict import TensorDictBase
from torchrl.modules import set_recurrent_mode
from torchrl.objectives import TD3Loss, ValueEstimators

from jugglerl.networks.critic import make_critic
from jugglerl.offpolicy.losses import LOSSES
from jugglerl.offpolicy.losses.bc import add_cloning_term
from jugglerl.offpolicy.losses.update import Update, check_rl_config


@LOSSES.register("td3")
class TD3(Update):
    @classmethod
    def check_config(cls, cfg) -> None:
        check_rl_config(cfg, ("algo.policy_delay", "algo.policy_noise", "algo.noise_clip"))
        if cfg.algo.policy_delay < 1:
            raise ValueError(f"algo.policy_delay={cfg.algo.policy_delay} must be >= 1")

    def __init__(self, actor, state_size, action_spec, cfg, recurrent: bool = False):
        self.check_config(cfg)
        algo = cfg.algo
        critic = make_critic(cfg.critic, state_size, action_spec.shape[-1])
        loss = TD3Loss(
            actor,
            critic,
            bounds=(-1.0, 1.0),  # the actions' range (the env's spec is batched)
            num_qvalue_nets=cfg.critic.get("ensemble", 2),
            policy_noise=algo.policy_noise,
            noise_clip=algo.noise_clip,
            loss_function="l2",
        )
        loss.make_value_estimator(ValueEstimators.TD0, gamma=algo.gamma)
        super().__init__(
            loss,
            loss.actor_network_params.flatten_keys().values(),
            loss.qvalue_network_params.flatten_keys().values(),
            cfg.optim,
            tau=algo.tau,
        )
        self.bc_weight = algo.bc_weight
        self.pessimism = algo.get("pessimism")
        if self.pessimism is not None and self.pessimism < 0:
            raise ValueError(f"algo.pessimism={self.pessimism} must be >= 0 or null")
        self.policy_delay = algo.policy_delay
        self.recurrent = recurrent
        self.updates = 0

    def __call__(self, batch: TensorDictBase) -> dict[str, float]:
        """One critic update on ``batch`` and, every ``policy_delay``-th call, an actor update;
        returns the losses before the step."""
        step_actor = self.updates % self.policy_delay == 0
        self.updates += 1
        losses = {}
        with set_recurrent_mode(self.recurrent):
            loss_critic, info = self.loss.value_loss(batch)
            total = loss_critic
            if step_actor:
                loss_actor = (
                    self.loss.actor_loss(batch)[0]
                    if self.pessimism is None
                    else -self.ensemble_objective(batch).mean()
                )
                losses["loss_actor"] = float(loss_actor.detach())
                total = add_cloning_term(
                    total + loss_actor, self.loss.actor_network, batch, self.bc_weight, losses
                )
        self.apply(total, step_actor=step_actor)
        return {
            "loss_critic": float(loss_critic.detach()),
            "q_value": float(info["pred_value"].detach().mean()),
            **losses,
        }

    def ensemble_objective(self, batch: TensorDictBase) -> torch.Tensor:
        """``mean_k Q_k - pessimism · std_k Q_k`` at the actor's actions on ``batch``, with
        gradients to the actor only."""
        loss = self.loss
        acted = batch.select(*loss.actor_network.in_keys, strict=False)
        with loss.actor_network_params.to_module(loss.actor_network):
            acted = loss.actor_network(acted)
        acted = acted.select(*loss.qvalue_network.in_keys)
        values = []
        for params in loss.qvalue_network_params.detach().unbind(0):
            with params.to_module(loss.qvalue_network):
                values.append(loss.qvalue_network(acted.clone(False))["state_action_value"])
        values = torch.stack(values).squeeze(-1)
        return values.mean(0) - self.pessimism * values.std(0)

    def state_dict(self) -> dict:
        return {**super().state_dict(), "updates": self.updates}

    def load_state_dict(self, state: dict) -> None:
        super().load_state_dict(state)
        self.updates = int(state["updates"])
