"""``ddpg``: TorchRL's ``DDPGLoss`` (the paper's method), TD targets from target networks.

The critic regresses ``r + γ^m (1 - terminated) Q'(s', μ'(s'))`` (``algo.gamma``; ``m``: the
transition's ``steps_to_next_obs``, ``jugglerl.offpolicy.n_step``); the actor climbs
``Q(s, μ(s))``, plus ``algo.bc_weight`` times the behaviour-cloning loss when it is positive; both
targets then move by ``algo.tau``. With a recurrent actor the batch is ``[sub-trajectories,
time]`` and the actor runs in recurrent mode.
"""

from __future__ import annotations

from tensordict import TensorDictBase
from torchrl.modules import set_recurrent_mode
from torchrl.objectives import DDPGLoss, ValueEstimators

from jugglerl.networks.critic import make_critic
from jugglerl.offpolicy.losses import LOSSES
from jugglerl.offpolicy.losses.bc import add_cloning_term
from jugglerl.offpolicy.losses.update import Update, check_rl_config


@LOSSES.register("ddpg")
class DDPG(Update):
    @classmethod
    def check_config(cls, cfg) -> None:
        check_rl_config(cfg)

    def __init__(self, actor, state_size, action_spec, cfg, recurrent: bool = False):
        self.check_config(cfg)
        critic = make_critic(cfg.critic, state_size, action_spec.shape[-1])
        loss = DDPGLoss(actor, critic, delay_actor=True, delay_value=True)
        loss.make_value_estimator(ValueEstimators.TD0, gamma=cfg.algo.gamma)
        super().__init__(
            loss,
            loss.actor_network_params.flatten_keys().values(),
            loss.value_network_params.flatten_keys().values(),
            cfg.optim,
            tau=cfg.algo.tau,
        )
        self.bc_weight = cfg.algo.bc_weight
        self.recurrent = recurrent

    def __call__(self, batch: TensorDictBase) -> dict[str, float]:
        """One update on ``batch``; returns the losses before the step."""
        with set_recurrent_mode(self.recurrent):
            # the two halves of DDPGLoss.forward, without packing them into a TensorDict
            loss_critic, critic_info = self.loss.loss_value(batch)
            loss_actor, _ = self.loss.loss_actor(batch)
            losses = {}
            total = add_cloning_term(
                loss_actor + loss_critic, self.loss.actor_network, batch, self.bc_weight, losses
            )
        self.apply(total)
        return {
            "loss_actor": float(loss_actor.detach()),
            "loss_critic": float(loss_critic.detach()),
            "q_value": float(critic_info["pred_value"].detach().mean()),
            **losses,
        }
