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
from torch.optim.swa_utils import AveragedModel, get_ema_multi_avg_fn
from torchrl.modules import set_recurrent_mode
from torchrl.objectives import LossModule

from jugglerl.networks.plain import PlainActor, starts_inside
from jugglerl.offpolicy.losses import LOSSES
from jugglerl.offpolicy.losses.update import Update
from jugglerl.offpolicy.teacher import TEACHER_ACTION


def behaviour_cloning_loss(
    actor: TensorDictModule, batch: TensorDictBase, plain: PlainActor | None = None
) -> torch.Tensor:
    """Mean squared error of ``actor``'s actions on ``batch`` from the teacher's; with ``plain``
    (``actor`` on plain tensors, the same actions) it acts where it can."""
    if TEACHER_ACTION not in batch.keys(include_nested=True):
        raise ValueError("behaviour cloning needs a teacher in the loop (teacher.policy)")
    if plain is not None and not starts_inside(batch["is_init"]):
        predicted = plain({key: batch[key] for key in plain.in_keys})["action"]
    else:
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
    """A ``LossModule`` holding the actor, so that its weights checkpoint as the others' do (the
    update computes ``behaviour_cloning_loss`` itself, on plain tensors where it can)."""

    def __init__(self, actor: TensorDictModule):
        super().__init__()
        self.actor_network = actor


@LOSSES.register("bc")
class BehaviourCloning(Update):
    """Adam on the actor alone. The deployed actor is the trained one, or with ``algo.bc_tau``
    an exponential moving average of its weights (``θ' ← θ' + bc_tau (θ - θ')`` after each
    step; torch's ``AveragedModel``).

    Why the average: a cloned actor's closed loop is chaotic in its weights. With the trained
    actor deployed, evaluations 20,480 frames apart swung between 2 and 13 throws in 30 s; the
    average of the last ≈ 1/bc_tau updates juggled through four evaluations in a row
    (docs/results/apprentice.md).
    """

    @classmethod
    def check_config(cls, cfg) -> None:
        if cfg.teacher.policy is None:
            raise ValueError("algo.loss=bc clones a teacher in the loop: set teacher.policy")
        tau = cfg.algo.get("bc_tau")
        if tau is not None and not 0 < tau <= 1:
            raise ValueError(f"algo.bc_tau={tau} must be in (0, 1] or null")

    def __init__(self, actor, state_size, action_spec, cfg, recurrent: bool = False):
        self.check_config(cfg)
        super().__init__(CloningModule(actor), actor.parameters(), None, cfg.optim, tau=None)
        self.recurrent = recurrent
        # a recurrent actor's sub-trajectories run on plain tensors (the same actions)
        self.plain = PlainActor(actor, sequences=True) if recurrent else None
        self.reads = [*actor.in_keys, TEACHER_ACTION]
        tau = cfg.algo.get("bc_tau")  # runs saved before the key existed had none
        self.average = (
            None
            if tau is None
            else AveragedModel(actor, multi_avg_fn=get_ema_multi_avg_fn(1.0 - tau))
        )

    def __call__(self, batch: TensorDictBase) -> dict[str, float]:
        with set_recurrent_mode(self.recurrent):
            loss = behaviour_cloning_loss(self.loss.actor_network, batch, self.plain)
        self.apply(loss)
        if self.average is not None:
            self.average.update_parameters(self.loss.actor_network)
        return {"loss_bc": float(loss.detach())}

    def target_actor(self) -> TensorDictModule:
        source = self.loss.actor_network if self.average is None else self.average.module
        return copy.deepcopy(source)

    def state_dict(self) -> dict:
        state = super().state_dict()
        if self.average is not None:
            state["average"] = self.average.state_dict()
        return state

    def load_state_dict(self, state: dict) -> None:
        super().load_state_dict(state)
        if self.average is not None and "average" in state:
            self.average.load_state_dict(state["average"])
