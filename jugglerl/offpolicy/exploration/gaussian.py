"""``gaussian``: a Gaussian around a centre, the expert command (the paper's exploration).

Action ``a + w (c - a) + σ ε``, clipped to [-1, 1], with ``a`` the actor's action, ``ε ~ N(0, I)``
and the centre ``c`` chosen by ``exploration.centre``:

- ``timed``: the setpoint of the command ``exploration.command`` at the episode time in its cycle;
- ``average``: that command's average setpoint over a cycle (the paper's choice: noise centred
  on the hand-made expert's average command beat OU noise for them).

With the expert's weight ``w = 1`` actions are drawn around the centre; as ``w`` anneals to
``expert_weight_end`` the actor takes over. ``w`` and ``σ`` move linearly from their initial to
their final values over ``annealing_frames`` frames counted by ``step``.
"""

from __future__ import annotations

import numpy as np
import torch
from tensordict import TensorDictBase
from tensordict.nn import TensorDictModuleBase
from torchrl.envs.utils import ExplorationType, exploration_type

from jugglerl.commands import ViaPointCommand, load_command
from jugglerl.networks.reference import CommandReference
from jugglerl.offpolicy.exploration import EXPLORATIONS
from jugglerl_envs.actions import ctrl_to_action

#: Samples over one cycle that define a command's average action.
AVERAGE_SAMPLES = 1000


class CommandCentre:
    """A via-point command's action at the episode ``time`` (``timed``), or its average over a
    cycle whatever the time (``average``)."""

    def __init__(self, command: ViaPointCommand, average: bool):
        self.reference = CommandReference(command)
        times = np.linspace(0.0, command.cycle, AVERAGE_SAMPLES, endpoint=False)
        self.average = (
            torch.as_tensor(ctrl_to_action(command.cycle_setpoints(times)).mean(axis=0))
            if average
            else None
        )
        self.in_keys = ["time"]

    def __call__(self, tensordict: TensorDictBase) -> torch.Tensor:
        time = tensordict.get("time")
        if self.average is not None:
            return self.average.expand(*time.shape, -1)
        return self.reference(time)


def _interpolate(start: float, end: float, progress: float) -> float:
    return start + (end - start) * progress


class CentredGaussianNoise(TensorDictModuleBase):
    """Exploratory action ``a + w (c - a) + σ ε``, clipped to [-1, 1] (module docstring)."""

    def __init__(
        self,
        centre: CommandCentre,
        sigma_init: float,
        sigma_end: float,
        expert_weight_init: float,
        expert_weight_end: float,
        annealing_frames: int,
    ):
        super().__init__()
        for name, value in (("sigma_init", sigma_init), ("sigma_end", sigma_end)):
            if value < 0:
                raise ValueError(f"exploration.{name}={value} must be >= 0")
        for name, value in (
            ("expert_weight_init", expert_weight_init),
            ("expert_weight_end", expert_weight_end),
        ):
            if not 0 <= value <= 1:
                raise ValueError(f"exploration.{name}={value} must be in [0, 1]")
        if annealing_frames < 1:
            raise ValueError(f"exploration.annealing_frames={annealing_frames} must be >= 1")
        self.centre = centre
        self.sigma_range = (float(sigma_init), float(sigma_end))
        self.weight_range = (float(expert_weight_init), float(expert_weight_end))
        self.annealing_frames = int(annealing_frames)
        self.in_keys = ["action", *centre.in_keys]
        self.out_keys = ["action"]
        self.register_buffer("frames", torch.zeros((), dtype=torch.long))

    @property
    def progress(self) -> float:
        """Fraction of the annealing done, in [0, 1]."""
        return min(1.0, int(self.frames) / self.annealing_frames)

    @property
    def sigma(self) -> float:
        return _interpolate(*self.sigma_range, self.progress)

    @property
    def expert_weight(self) -> float:
        return _interpolate(*self.weight_range, self.progress)

    def step(self, frames: int = 1) -> None:
        """Count ``frames`` collected frames towards the annealing."""
        self.frames += frames

    def forward(self, tensordict: TensorDictBase) -> TensorDictBase:
        if exploration_type() not in (ExplorationType.RANDOM, None):
            return tensordict
        action = tensordict.get("action")
        centre = self.centre(tensordict).to(action)
        noisy = action + self.expert_weight * (centre - action)
        noisy = noisy + self.sigma * torch.randn_like(action)
        return tensordict.set("action", noisy.clamp(-1.0, 1.0))


CENTRES = ("timed", "average")


@EXPLORATIONS.register("gaussian")
def centred_gaussian(exploration_cfg, action_spec) -> CentredGaussianNoise:
    mode = exploration_cfg.centre
    if mode not in CENTRES:
        raise ValueError(f"exploration.centre={mode} is not one of {', '.join(CENTRES)}")
    centre = CommandCentre(load_command(exploration_cfg.command), average=mode == "average")
    return CentredGaussianNoise(
        centre,
        sigma_init=exploration_cfg.sigma_init,
        sigma_end=exploration_cfg.sigma_end,
        expert_weight_init=exploration_cfg.expert_weight_init,
        expert_weight_end=exploration_cfg.expert_weight_end,
        annealing_frames=exploration_cfg.annealing_frames,
    )
