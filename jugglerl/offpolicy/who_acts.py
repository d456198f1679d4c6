"""Who acts in a stage: the teacher, while the student watches (behaviour cloning), or the student,
while a teacher in the loop labels the states it visits (DAgger, RL); white noise of σ on whoever
acts (a stage's ``acts`` and ``noise``, ``jugglerl.offpolicy.stages``).

``WhoActs`` runs last in the acting policy, after the teacher (``jugglerl.offpolicy.teacher``) and
the actor. While collecting (``ExplorationType.RANDOM``) it writes ``action``: the teacher's action
(``("teacher", "action")``) or the actor's, plus ``σ ε`` with ``ε ~ N(0, I)``, clipped to
[-1, 1]; otherwise (evaluation) the actor's action passes through. A stage without ``acts``
explores with the ``exploration`` group's module instead.
"""

from __future__ import annotations

import torch
from tensordict import TensorDictBase
from tensordict.nn import TensorDictModuleBase
from torchrl.envs.utils import ExplorationType, exploration_type

from jugglerl.offpolicy.teacher import TEACHER_ACTION

#: the values of a stage's ``acts``
ACTORS = ("teacher", "student")


def check_who_acts(acts, noise) -> None:
    """``ValueError`` naming ``acts`` or ``noise`` (σ) when it is not one ``WhoActs`` takes."""
    if acts not in ACTORS:
        raise ValueError(f"acts={acts} must be one of {', '.join(ACTORS)}")
    if isinstance(noise, bool) or not isinstance(noise, (int, float)) or noise < 0:
        raise ValueError(f"noise={noise} must be a number >= 0 (σ)")


class WhoActs(TensorDictModuleBase):
    """The action of whoever ``acts`` (``teacher`` or ``student``), with white noise of σ
    ``noise`` (module docstring)."""

    def __init__(self, acts: str, noise: float):
        super().__init__()
        check_who_acts(acts, noise)
        self.acts = acts
        self.noise = float(noise)
        self.in_keys = ["action", *([TEACHER_ACTION] if acts == "teacher" else [])]
        self.out_keys = ["action"]

    def step(self, frames: int = 1) -> None:
        """Nothing anneals: σ holds over the stage (the exploration modules' ``step``)."""

    def forward(self, tensordict: TensorDictBase) -> TensorDictBase:
        if exploration_type() not in (ExplorationType.RANDOM, None):
            return tensordict
        action = tensordict.get("action")
        if self.acts == "teacher":
            action = tensordict.get(TEACHER_ACTION).to(action)
        noisy = action + self.noise * torch.randn_like(action)
        return tensordict.set("action", noisy.clamp(-1.0, 1.0))
