"""``td3``: TorchRL's ``TD3Loss``: twin critics, target policy smoothing, delayed actor updates.

The ``critic.ensemble`` critics (2: TD3's twins) each regress
``r + γ^m (1 - terminated) min_k Q'_k(s', μ'(s') + clip(σ ε, ±c))`` (``m``: the transition's
``steps_to_next_obs``, ``jugglerl.offpolicy.n_step``) with
``σ = algo.policy_noise`` and ``c = algo.noise_clip`` (normalised action units); the actor
(plus ``algo.bc_weight`` times the behaviour-cloning loss) and the targets move only every
``algo.policy_delay`` updates.
"""

from __future__ import annotations

from tensordict import TensorDictBase
from torchrl.modules import set_recurrent_mode
from torchrl.objectives import TD3Loss, ValueEstimators

from jugglerl.offpolicy.critic import make_critic
from jugglerl.offpolicy.losses import LOSSES
from jugglerl.offpolicy.losses.bc import add_cloning_term
from jugglerl.offpolicy.losses.update import Update, check_rl_config


@LOSSES.register("td3")
class TD3(Update):
    def __init__(self, actor, state_size, action_spec, cfg, recurrent: bool = False):
        algo = cfg.algo
        check_rl_config(algo)
        if algo.policy_delay < 1:
            raise ValueError(f"algo.policy_delay={algo.policy_delay} must be >= 1")
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
                loss_actor, _ = self.loss.actor_loss(batch)
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

    def state_dict(self) -> dict:
        return {**super().state_dict(), "updates": self.updates}

    def load_state_dict(self, state: dict) -> None:
        super().load_state_dict(state)
        self.updates = int(state["updates"])
