"""A learned, bounded correction on top of any actor (``actor.correction``): residual RL.

``action = clamp(base_action + max_correction · tanh(MLP([state, base_action, features])), ±1)``
where ``base_action`` is what the actor ``actor.name`` would do and ``features`` what it computes
on the way that a correction may read (an LSTM's ``memory``). The MLP's last layer starts at zero,
so a corrected actor acts exactly as its base until the correction trains, and the MLP's inputs
are detached, so the correction's gradients never reach the base (the base still learns from its
own, through ``base_action``). A stage chooses which part its updates train (``trains: base |
correction``, ``jugglerl.offpolicy.stages``): the cloning stages train the base with the
correction at zero, the RL stage the correction on the frozen clone (ResFiT, Policy Decorator).
The correction writes the base's action beside its own as ``base_action``.
"""

from __future__ import annotations

import torch
from omegaconf import DictConfig
from tensordict.nn import TensorDictSequential
from torch import nn
from torchrl.modules import MLP

from jugglerl.networks.modules import TensorModule

BASE_ACTION = "base_action"
#: What a stage's updates may train (``trains``).
PARTS = ("base", "correction")


class Correction(nn.Module):
    """``max_correction · tanh(MLP(...))`` added to the base action, from a zero start."""

    def __init__(self, input_size: int, action_size: int, hidden: list[int], max_correction: float):
        super().__init__()
        if not 0 < max_correction <= 2:
            raise ValueError(f"actor.correction.max_correction={max_correction} must be in (0, 2]")
        self.max_correction = float(max_correction)
        self.body = MLP(input_size, action_size, num_cells=list(hidden))
        nn.init.zeros_(self.body[-1].weight)
        nn.init.zeros_(self.body[-1].bias)

    def forward(self, state: torch.Tensor, base_action: torch.Tensor, *features: torch.Tensor):
        inputs = torch.cat([state, base_action, *features], dim=-1).detach()
        correction = self.max_correction * torch.tanh(self.body(inputs))
        return (base_action + correction).clamp(-1.0, 1.0), base_action


def corrected(
    base: TensorDictSequential,
    correction_cfg: DictConfig,
    state_size: int,
    action_size: int,
    features: dict[str, int],
) -> TensorDictSequential:
    """``base`` followed by a ``Correction`` reading ``state``, its ``action`` and ``features``
    (``{key: size}``). Its weights are drawn from a fork of torch's random stream, so that a
    run's other draws (exploration, sampling) are the same with or without a correction."""
    with torch.random.fork_rng():
        correction = Correction(
            state_size + action_size + sum(features.values()),
            action_size,
            correction_cfg.hidden,
            correction_cfg.max_correction,
        )
    module = TensorModule(correction, ["state", "action", *features], ["action", BASE_ACTION])
    return TensorDictSequential(*base.module, module)


def trained_parameters(actor: nn.Module, parameters, part: str) -> list[nn.Parameter]:
    """Those of ``parameters`` (the actor's, or a loss's copies that share them) that a stage
    training ``part`` updates: the correction's, or all the others (the base)."""
    if part not in PARTS:
        raise ValueError(f"trains={part!r} must be one of {', '.join(PARTS)}")
    owned = {id(p) for m in actor.modules() if isinstance(m, Correction) for p in m.parameters()}
    if part == "correction" and not owned:
        raise ValueError("trains=correction needs an actor with actor.correction set")
    return [p for p in parameters if (id(p) in owned) == (part == "correction")]
