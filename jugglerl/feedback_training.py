"""``algo=feedback``: eREPS (or any DPS rule) over the gains of the closed-loop ``FeedbackPolicy``.

The loop is ``DPSTraining``'s, over a different search space: θ is ``FeedbackGains`` (bounded by
``algo.bounds``), the command it locks to is fixed (``algo.command``), and every θ is rolled out
closed loop in the Python env, once under each of ``algo.conditions`` (env overrides: nominal,
kicks, start offsets), in ``algo.workers`` processes. A θ's return is its throws summed over the
conditions, so the search prefers gains that juggle in all of them. The best θ is written as
``best_policy.yaml`` (``scripts/evaluate.py policy=<run dir>/best_policy.yaml``).
"""

from __future__ import annotations

import math
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
from omegaconf import DictConfig, OmegaConf

from jugglerl.commands import ViaPointCommand, load_command
from jugglerl.config import make_juggle_env
from jugglerl.dps.rollouts import RolloutResults
from jugglerl.dps.training import DPSTraining
from jugglerl.evaluation import run_episode
from jugglerl.feedback import PARAM_NAMES, FeedbackGains, FeedbackPolicy, save_feedback_policy

BEST_POLICY = "best_policy.yaml"


def gains_from_params(params: torch.Tensor) -> FeedbackGains:
    """θ (``PARAM_NAMES`` order) as ``FeedbackGains``: the collector's ``decode``."""
    return FeedbackGains(*(float(value) for value in params))


@dataclass(frozen=True)
class GainBounds:
    """Box constraints on ``θ`` (the DPS collector's ``constraints``): samples are clipped."""

    low: torch.Tensor
    high: torch.Tensor

    @classmethod
    def from_config(cls, bounds: dict) -> GainBounds:
        missing = set(PARAM_NAMES) - set(bounds)
        if missing:
            raise ValueError(f"algo.bounds: missing {sorted(missing)}")
        low, high = zip(*(bounds[name] for name in PARAM_NAMES), strict=True)
        result = cls(*(torch.tensor(values, dtype=torch.float64) for values in (low, high)))
        if torch.any(result.low > result.high):
            raise ValueError("algo.bounds: every [low, high] needs low <= high")
        return result

    def project(self, params: torch.Tensor) -> torch.Tensor:
        return torch.clamp(params, self.low, self.high)

    def violations(self, params: torch.Tensor) -> list[str]:
        return [
            f"{name}={float(value):g} outside [{float(lo):g}, {float(hi):g}]"
            for name, value, lo, hi in zip(PARAM_NAMES, params, self.low, self.high, strict=True)
            if not lo <= value <= hi
        ]


def _episode(task: tuple[dict, ViaPointCommand, FeedbackGains, int]) -> tuple[int, float]:
    """Worker: one closed-loop episode; (throws, time to drop or NaN)."""
    env_kwargs, command, gains, seed = task
    env = make_juggle_env(OmegaConf.create(env_kwargs))
    policy = FeedbackPolicy(command, gains, env)
    metrics = run_episode(env, policy, seed=seed)
    env.close()
    drop = math.nan if metrics.time_to_drop is None else metrics.time_to_drop
    return metrics.throws, drop


class FeedbackRollouts:
    """Rolls ``FeedbackGains`` out with ``command`` under each of ``conditions``.

    ``evaluate(gains, seeds)`` gives, per θ, the throws summed over the conditions and the
    earliest drop (NaN when none dropped); episode ``k`` of θ ``i`` uses reset seed
    ``seeds[i] + k``.
    """

    def __init__(
        self, env_cfg: DictConfig, command: ViaPointCommand, conditions: list[dict], workers: int
    ):
        base = OmegaConf.to_container(env_cfg, resolve=True)
        self.envs = [{**base, **condition} for condition in conditions]
        for env_kwargs in self.envs:  # bad keys or values fail here, not in a worker
            make_juggle_env(OmegaConf.create(env_kwargs)).close()
        self.command = command
        self._pool = ProcessPoolExecutor(workers)

    def evaluate(self, candidates: list[FeedbackGains], seeds: list[int]) -> RolloutResults:
        tasks = [
            (env, self.command, gains, seed + k)
            for gains, seed in zip(candidates, seeds, strict=True)
            for k, env in enumerate(self.envs)
        ]
        results = np.array(list(self._pool.map(_episode, tasks)), dtype=np.float64)
        results = results.reshape(len(candidates), len(self.envs), 2)
        return RolloutResults(
            throws=results[..., 0].sum(axis=1).astype(np.int64),
            time_to_drop=np.fmin.reduce(results[..., 1], axis=1),
        )

    def close(self) -> None:
        self._pool.shutdown()

    def __enter__(self) -> FeedbackRollouts:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()


class FeedbackTraining(DPSTraining):
    """One ``algo=feedback`` run; see the module docstring."""

    def _search_space(self):
        algo = self.cfg.algo
        self.command = load_command(algo.command)
        bounds = GainBounds.from_config(dict(algo.bounds))
        start = torch.tensor([algo.start[name] for name in PARAM_NAMES], dtype=torch.float64)
        problems = bounds.violations(start)
        if problems:
            raise ValueError(f"algo.start: outside algo.bounds: {'; '.join(problems)}")
        stds = torch.tensor([algo.std[name] for name in PARAM_NAMES], dtype=torch.float64)
        rollouts = self._rollouts(list(algo.conditions))
        return start, stds, bounds, rollouts, gains_from_params

    def _rollouts(self, conditions: list) -> FeedbackRollouts:
        conditions = [dict(condition) for condition in conditions]
        return FeedbackRollouts(self.cfg.env, self.command, conditions, self.cfg.algo.workers)

    def _distribution_record(self, distribution) -> dict[str, float]:
        means = zip(PARAM_NAMES, distribution.mean, strict=True)
        return {f"mean_{name}": float(mean) for name, mean in means}

    def best_gains(self) -> FeedbackGains:
        return gains_from_params(self.best.params)

    def best_policy(self, env) -> FeedbackPolicy:
        return FeedbackPolicy(self.command, self.best_gains(), env)

    def save_best(self) -> None:
        save_feedback_policy(
            Path(self.run_dir) / BEST_POLICY, self.command, self.best_gains(), "feedback_best"
        )

    def _best_description(self) -> dict:
        return {"best_gains": vars(self.best_gains()), "command": self.command.to_dict()}

    def _headline(self, metrics: dict) -> str:
        return (
            f"feedback ({self.cfg.algo['update']}): best gains scored {metrics['best_throws']}"
            f" throws over {len(self.cfg.algo.conditions)} conditions x"
            f" {self.cfg.env.duration:g} s after {metrics['rollouts']} samples"
        )

    def _rollouts_with_reset_noise(self, reset_noise: float) -> FeedbackRollouts:
        return self._rollouts([{"reset_noise": reset_noise}])
