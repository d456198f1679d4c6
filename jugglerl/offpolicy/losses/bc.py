"""``bc``: behaviour cloning, the actor regressed onto a teacher's actions (ours).

The loss is the mean squared error between the actor's action and the teacher's,
``("teacher", "action")``, written in the loop by ``jugglerl.offpolicy.teacher.TeacherModule``.
``algo=bc`` trains with it alone (pre-training; no critic); the RL losses add it with weight
``algo.bc_weight`` beside their own actor loss (TD3+BC style).
"""

from __future__ import annotations

import copy

import torch
from tensordict import TensorDictBase
from tensordict.nn import TensorDictModule
from torchrl.modules import set_recurrent_mode
from torchrl.objectives import LossModule

from jugglerl.offpolicy.losses import LOSSES
from jugglerl.offpolicy.losses.update import Update

TEACHER_ACTION = ("teacher", "action")


def behaviour_cloning_loss(actor: TensorDictModule, batch: TensorDictBase) -> torch.Tensor:
    """Mean squared error of ``actor``'s actions on ``batch`` from the teacher's."""
    if TEACHER_ACTION not in batch.keys(include_nested=True):
        raise ValueError("behaviour cloning needs a teacher in the loop (teacher.policy)")
    predicted = actor(batch.select(*actor.in_keys, strict=False))["action"]
    return torch.nn.functional.mse_loss(predicted, batch[TEACHER_ACTION])


def add_cloning_term(total, actor, batch, weight: float, losses: dict) -> torch.Tensor:
    """``total`` plus ``weight`` times the cloning loss (recorded in ``losses``) when positive:
    the term the RL losses add beside their own (``algo.bc_weight``)."""
    if weight <= 0:
        return total
    loss_bc = behaviour_cloning_loss(actor, batch)
    losses["loss_bc"] = float(loss_bc.detach())
    return total + weight * loss_bc


class CloningModule(LossModule):
    """A ``LossModule`` holding the actor, so that its weights checkpoint as the others' do."""

    def __init__(self, actor: TensorDictModule):
        super().__init__()
        self.actor_network = actor

    def forward(self, batch: TensorDictBase) -> torch.Tensor:
        return behaviour_cloning_loss(self.actor_network, batch)


@LOSSES.register("bc")
class BehaviourCloning(Update):
    """Adam on the actor alone; the deployed actor is the trained one (no targets)."""

    def __init__(self, actor, state_size, action_spec, cfg, recurrent: bool = False):
        super().__init__(CloningModule(actor), actor.parameters(), None, cfg.optim, tau=None)
        self.recurrent = recurrent

    def __call__(self, batch: TensorDictBase) -> dict[str, float]:
        with set_recurrent_mode(self.recurrent):
            loss = self.loss(batch)
        self.apply(loss)
        return {"loss_bc": float(loss.detach())}

    def target_actor(self) -> TensorDictModule:
        return copy.deepcopy(self.loss.actor_network)
