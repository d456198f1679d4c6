"""``closed_loop`` (``algo=closed_loop``): a command's via-points and its feedback gains together.

θ is the via-point command's θ (cycle and via-points, ``jugglerl.dps.params``) followed by the
``FeedbackGains``, searched from the feedback policy ``algo.start`` (its command and gains; its own
settings, ``max_offset`` and the centring gains, are kept), and rolled out closed loop under each
of ``algo.conditions``, which may include the imprecision perturbations (action noise, a tracked
ball): a throw that only just clears the threshold loses its throws to them, so the search is
pushed to throws with a margin, and the feedback, which catches a ball that lands early or late,
lets it shorten the cycle all the same. Constraints: the command's (``algo.min_cycle``,
``algo.max_cycle``, ``algo.min_gap``, the servos' ranges) and ``algo.bounds`` on the gains. The
best θ is written as ``best_policy.yaml``.
"""

from __future__ import annotations

import torch
from omegaconf import DictConfig

from jugglerl.dps.closed_loop_space import ClosedLoopSpace, GainBox, gains_from_params
from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.params import (
    ViaPointConstraints,
    command_to_params,
    component_stds,
    params_to_command,
)
from jugglerl.dps.spaces import SPACES
from jugglerl.policies.feedback import FIXED_NAMES, PARAM_NAMES, FeedbackPolicy
from jugglerl.policies.loading import load_named_policy


@SPACES.register("closed_loop")
class CommandAndGainSpace(ClosedLoopSpace):
    """θ = [command θ, gains]; see the module docstring."""

    def __init__(self, cfg: DictConfig):
        super().__init__(cfg)
        algo = cfg.algo
        env = self.search_env()
        start = load_named_policy("algo.start", algo.start, env)
        if not isinstance(start, FeedbackPolicy):
            raise ValueError(f"algo.start={algo.start} is not a feedback policy (kind: feedback)")
        self.pan, self.lead_in = start.command.pan, start.command.lead_in
        self.fixed = {name: getattr(start.gains, name) for name in FIXED_NAMES}
        self.constraints = ViaPointConstraints.from_model(
            env.unwrapped.model, algo.min_cycle, algo.max_cycle, algo.min_gap
        )
        env.close()
        self.box = GainBox(algo.bounds)
        command = command_to_params(start.command)
        self.split = len(command)
        gains = torch.tensor([getattr(start.gains, n) for n in PARAM_NAMES], dtype=torch.float64)
        self.start = torch.cat([command, gains])
        problems = self.violations(self.start)
        if problems:
            raise ValueError(f"algo.start={algo.start}: {'; '.join(problems)}")
        points = len(start.command.via_points)
        command_stds = component_stds(
            points, {k: algo.std[k] for k in ("cycle", "time", "lift", "elbow")}
        )
        gain_stds = torch.tensor([algo.std[name] for name in PARAM_NAMES], dtype=torch.float64)
        self.stds = torch.cat([command_stds, gain_stds])

    def project(self, params: torch.Tensor) -> torch.Tensor:
        command, gains = params[..., : self.split], params[..., self.split :]
        return torch.cat([self.constraints.project(command), self.box.project(gains)], dim=-1)

    def violations(self, params: torch.Tensor) -> list[str]:
        command, gains = params[: self.split], params[self.split :]
        return self.constraints.violations(command) + self.box.violations(gains)

    def decode(self, params: torch.Tensor) -> tuple:
        command = params_to_command(params[: self.split], self.pan, "closed_loop", self.lead_in)
        return command, gains_from_params(params[self.split :], **self.fixed)

    def record(self, distribution: SearchDistribution) -> dict[str, float]:
        """The cycle's mean and std, and the gains' means."""
        means = zip(PARAM_NAMES, distribution.mean[self.split :], strict=True)
        return {
            "mean_cycle": float(distribution.mean[0]),
            "std_cycle": float(distribution.stds[0]),
            **{f"mean_{name}": float(mean) for name, mean in means},
        }
