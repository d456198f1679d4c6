"""``ClosedLoopSpace``: the base of the closed-loop search spaces (``feedback_gains``,
``closed_loop``, ``throw_catch`` in ``jugglerl.dps.spaces``), and the feedback gains' box.

A closed-loop θ is rolled out in the Python env under ``algo.conditions`` within
``algo.limits`` (``ClosedLoopRollouts``); unless a space says otherwise it decodes to a
``(command, gains)`` pair whose best is saved as a feedback policy file, ``best_policy.yaml``.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import gymnasium as gym
import torch
from omegaconf import DictConfig

from jugglerl.config.envs import make_juggle_env
from jugglerl.dps.closed_loop_rollouts import ClosedLoopRollouts
from jugglerl.policies.feedback import (
    PARAM_NAMES,
    FeedbackGains,
    FeedbackPolicy,
    save_feedback_policy,
)

#: A search's policy files: ``best_policy.yaml`` (its best roll-out) and ``mean_policy.yaml``.
POLICY_FILE = "{role}_policy.yaml"


def gains_from_params(params: torch.Tensor, **fixed: float) -> FeedbackGains:
    """θ (``PARAM_NAMES`` order) as ``FeedbackGains``, with the policy's own settings
    (``FIXED_NAMES``: ``max_offset``, the centring gains) from ``fixed``, their defaults where
    absent."""
    return FeedbackGains(*(float(value) for value in params), **fixed)


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

    def save(self, params: torch.Tensor, run_dir: Path, name: str, role: str = "best") -> str:
        balls = self.cfg.env.get("balls", 1)
        file = POLICY_FILE.format(role=role)
        save_feedback_policy(run_dir / file, *self.decode(params), name, balls)
        return file

    def describe(self, params: torch.Tensor, name: str) -> dict:
        command, gains = self.decode(params)
        return {"best_gains": asdict(gains), "command": command.to_dict()}

    def headline(self, metrics: dict) -> str:
        return (
            f"{self.cfg.algo.name} ({self.cfg.algo['update']}): best scored"
            f" {metrics['best_throws']} throws over {len(self.cfg.algo.conditions)} conditions x"
            f" {self.cfg.env.duration:g} s after {metrics['rollouts']} samples"
        )
