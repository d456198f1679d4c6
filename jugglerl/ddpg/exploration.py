"""Exploration around the actor: Ornstein-Uhlenbeck noise, or a Gaussian centred on the expert.

``exploration=ou`` is TorchRL's ``OrnsteinUhlenbeckProcessModule`` (correlated noise added to the
actor's action, annealed). ``exploration=gaussian`` is ``ExpertGaussianNoise``: the paper found
that noise centred on the hand-made expert's average command beat OU noise, because it leads
exploration towards a policy known to work. Both anneal only when ``step(frames)`` is called, and
both pass the actor's action through unchanged outside ``ExplorationType.RANDOM`` (evaluation).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch
from omegaconf import DictConfig
from tensordict import TensorDictBase
from tensordict.nn import TensorDictModuleBase, TensorDictSequential
from torchrl.data import TensorSpec
from torchrl.envs.utils import ExplorationType, exploration_type
from torchrl.modules import OrnsteinUhlenbeckProcessModule

from jugglerl.commands import ViaPointCommand, load_command
from jugglerl.ddpg.reference import CommandReference

EXPLORATIONS = ("ou", "gaussian")
CENTRES = ("timed", "average")
#: Samples over one cycle that define a command's average action.
AVERAGE_SAMPLES = 1000


class ExpertCentre:
    """The normalised action of a via-point ``command`` at a given episode time.

    ``mode="timed"``: the command's setpoint at that time in its cycle; ``mode="average"``: its
    average setpoint over a cycle, whatever the time (the paper's choice). ``to_action`` maps
    servo setpoints (rad) to normalised actions (the env's ``ctrl_to_action``).
    """

    def __init__(
        self,
        command: ViaPointCommand,
        to_action: Callable[[np.ndarray], np.ndarray],
        mode: str = "timed",
    ):
        if mode not in CENTRES:
            raise ValueError(f"exploration.centre={mode} is not one of {', '.join(CENTRES)}")
        self.command = command
        self.mode = mode
        self.reference = CommandReference(command, to_action)
        times = np.linspace(0.0, command.cycle, AVERAGE_SAMPLES, endpoint=False)
        self.average = torch.as_tensor(to_action(command.cycle_setpoints(times)).mean(axis=0))

    def __call__(self, time: torch.Tensor) -> torch.Tensor:
        """Actions of shape ``time.shape + (3,)`` for episode times in seconds."""
        if self.mode == "average":
            return self.average.expand(*time.shape, -1)
        return self.reference(time)


def _interpolate(start: float, end: float, progress: float) -> float:
    return start + (end - start) * progress


class ExpertGaussianNoise(TensorDictModuleBase):
    """Exploratory action ``a + w (c(t) - a) + σ ε``, clipped to [-1, 1].

    ``a`` is the actor's action, ``c(t)`` the expert's (``ExpertCentre``) at the episode time read
    from ``time_key``, ``ε ~ N(0, I)``. With the expert weight ``w = 1`` actions are drawn from a
    Gaussian centred on the expert; as ``w`` anneals to ``expert_weight_end`` the actor takes
    over. ``w`` and ``σ`` move linearly from their initial to their final values over
    ``annealing_frames`` frames counted by ``step``.
    """

    def __init__(
        self,
        centre: ExpertCentre,
        sigma_init: float,
        sigma_end: float,
        expert_weight_init: float,
        expert_weight_end: float,
        annealing_frames: int,
        action_key: str = "action",
        time_key: str = "time",
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
        self.action_key = action_key
        self.time_key = time_key
        self.in_keys = [action_key, time_key]
        self.out_keys = [action_key]
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
        action = tensordict.get(self.action_key)
        centre = self.centre(tensordict.get(self.time_key)).to(action)
        noisy = action + self.expert_weight * (centre - action)
        noisy = noisy + self.sigma * torch.randn_like(action)
        return tensordict.set(self.action_key, noisy.clamp(-1.0, 1.0))


def make_exploration(
    exploration_cfg: DictConfig,
    actor: TensorDictSequential,
    action_spec: TensorSpec,
    to_action: Callable[[np.ndarray], np.ndarray],
) -> tuple[TensorDictSequential, TensorDictModuleBase]:
    """The collection policy (actor then noise) and the noise module (call its ``step``)."""
    name = exploration_cfg.name
    if name == "ou":
        noise = OrnsteinUhlenbeckProcessModule(
            spec=action_spec,
            eps_init=exploration_cfg.eps_init,
            eps_end=exploration_cfg.eps_end,
            annealing_num_steps=exploration_cfg.annealing_frames,
            theta=exploration_cfg.theta,
            mu=exploration_cfg.mu,
            sigma=exploration_cfg.sigma,
        )
    elif name == "gaussian":
        centre = ExpertCentre(
            load_command(exploration_cfg.command), to_action, exploration_cfg.centre
        )
        noise = ExpertGaussianNoise(
            centre,
            sigma_init=exploration_cfg.sigma_init,
            sigma_end=exploration_cfg.sigma_end,
            expert_weight_init=exploration_cfg.expert_weight_init,
            expert_weight_end=exploration_cfg.expert_weight_end,
            annealing_frames=exploration_cfg.annealing_frames,
        )
    else:
        raise ValueError(
            f"exploration={name} is not available; choose one of {', '.join(EXPLORATIONS)}"
        )
    return TensorDictSequential(actor, noise), noise
