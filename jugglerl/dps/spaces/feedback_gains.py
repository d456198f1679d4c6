"""``feedback_gains`` (``algo=feedback``): the gains of the closed-loop ``FeedbackPolicy``.

θ is ``FeedbackGains`` (bounded by ``algo.bounds``), searched from ``algo.start``; the command it
locks to is fixed (``algo.command``). Every θ is rolled out closed loop in the Python env, once
under each of ``algo.conditions`` (env overrides: nominal, kicks, start offsets), in
``algo.workers`` processes (or as tasks of ``cluster=ray``; ``ClosedLoopRollouts``); its return
is its throws summed over the conditions, so the search prefers gains that juggle in all of
them. The best θ is written as ``best_policy.yaml``.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import gymnasium as gym
import torch
from omegaconf import DictConfig

from jugglerl.config import make_juggle_env
from jugglerl.dps.closed_loop_rollouts import ClosedLoopRollouts
from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.spaces import SPACES
from jugglerl.policies.command import load_command
from jugglerl.policies.feedback import (
    PARAM_NAMES,
    FeedbackGains,
    FeedbackPolicy,
    save_feedback_policy,
)

BEST_POLICY = "best_policy.yaml"


def gains_from_params(params: torch.Tensor) -> FeedbackGains:
    """θ (``PARAM_NAMES`` order) as ``FeedbackGains``."""
    return FeedbackGains(*(float(value) for value in params))


class GainBox:
    """Box constraints on the gains (``algo.bounds``: ``[low, high]`` per gain)."""

    def __init__(self, bounds: DictConfig):
        missing = set(PARAM_NAMES) - set(bounds)
        if missing:
            raise ValueError(f"algo.bounds: missing {sorted(missing)}")
        low, high = zip(*(bounds[name] for name in PARAM_NAMES), strict=True)
        self.low, self.high = (torch.tensor(v, dtype=torch.float64) for v in (low, high))
        if torch.any(self.low > self.high):
            raise ValueError("algo.bounds: every [low, high] needs low <= high")

    def project(self, params: torch.Tensor) -> torch.Tensor:
        return torch.clamp(params, self.low, self.high)

    def violations(self, params: torch.Tensor) -> list[str]:
        return [
            f"{name}={float(value):g} outside [{float(lo):g}, {float(hi):g}]"
            for name, value, lo, hi in zip(PARAM_NAMES, params, self.low, self.high, strict=True)
            if not lo <= value <= hi
        ]


class ClosedLoopSpace:
    """What the closed-loop spaces share: roll-outs under ``algo.conditions`` within
    ``algo.limits`` (``jugglerl.dps.closed_loop_rollouts``), and, unless a subclass says
    otherwise, a decoded θ as a ``(command, gains)`` pair whose best is saved as a feedback
    policy file."""

    def __init__(self, cfg: DictConfig):
        self.cfg = cfg

    def decode(self, params: torch.Tensor) -> tuple:
        raise NotImplementedError

    def build(self, candidate, env: gym.Env) -> FeedbackPolicy:
        """The policy of a decoded θ, for envs like ``env``."""
        return FeedbackPolicy(*candidate, env)

    def search_env(self, reset_noise: float | None = None) -> gym.Env:
        return make_juggle_env(self.cfg.env, reset_noise=reset_noise)

    def rollouts(self, reset_noise: float | None = None) -> ClosedLoopRollouts:
        conditions = [dict(c) for c in self.cfg.algo.conditions]
        if reset_noise is not None:
            conditions = [{"reset_noise": reset_noise}]
        algo = self.cfg.algo
        return ClosedLoopRollouts(
            self.cfg.env,
            conditions,
            algo.workers,
            self.build,
            self.cfg.get("cluster"),
            algo.get("limits"),
        )

    def policy(self, params: torch.Tensor, env: gym.Env):
        return self.build(self.decode(params), env)

    def save(self, params: torch.Tensor, run_dir: Path, name: str) -> str:
        save_feedback_policy(run_dir / BEST_POLICY, *self.decode(params), name)
        return BEST_POLICY

    def describe(self, params: torch.Tensor, name: str) -> dict:
        command, gains = self.decode(params)
        return {"best_gains": asdict(gains), "command": command.to_dict()}

    def headline(self, metrics: dict) -> str:
        return (
            f"{self.cfg.algo.name} ({self.cfg.algo['update']}): best scored"
            f" {metrics['best_throws']} throws over {len(self.cfg.algo.conditions)} conditions x"
            f" {self.cfg.env.duration:g} s after {metrics['rollouts']} samples"
        )


@SPACES.register("feedback_gains")
class FeedbackGainSpace(ClosedLoopSpace):
    """θ of ``FeedbackGains``; see the module docstring."""

    def __init__(self, cfg: DictConfig):
        super().__init__(cfg)
        algo = cfg.algo
        self.command = load_command(algo.command)
        self.box = GainBox(algo.bounds)
        self.start = torch.tensor([algo.start[name] for name in PARAM_NAMES], dtype=torch.float64)
        problems = self.violations(self.start)
        if problems:
            raise ValueError(f"algo.start: outside algo.bounds: {'; '.join(problems)}")
        self.stds = torch.tensor([algo.std[name] for name in PARAM_NAMES], dtype=torch.float64)

    def project(self, params: torch.Tensor) -> torch.Tensor:
        return self.box.project(params)

    def violations(self, params: torch.Tensor) -> list[str]:
        return self.box.violations(params)

    def decode(self, params: torch.Tensor) -> tuple:
        return self.command, gains_from_params(params)

    def record(self, distribution: SearchDistribution) -> dict[str, float]:
        means = zip(PARAM_NAMES, distribution.mean, strict=True)
        return {f"mean_{name}": float(mean) for name, mean in means}
