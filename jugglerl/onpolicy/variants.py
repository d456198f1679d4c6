"""``training_variants``: the perturbation each env of an on-policy run's batch meets.

A policy is judged under start offsets, kicks, action noise, a noisy ball tracker and a weaker
arm (``scripts/robustness.py``), so it trains under them: env ``i`` of the batch runs under the
condition ``algo.perturbed`` lists at ``i % len(algo.perturbed)`` (``{}``: nominal), with its
servos' gain drawn uniformly in ``algo.servo_gain`` (kp scaled; one MuJoCo model per env). Each
env keeps its draw for the whole run; the batch as a whole covers the range.
"""

from __future__ import annotations

import numpy as np
from omegaconf import DictConfig, OmegaConf


def training_variants(cfg: DictConfig, num_envs: int) -> list[dict]:
    """Env arguments on top of ``cfg.env`` for each of ``num_envs`` envs (seeded by
    ``cfg.seed``)."""
    conditions = list(OmegaConf.to_container(cfg.algo.perturbed or {}, resolve=True).values())
    conditions = conditions or [{}]
    low, high = cfg.algo.servo_gain if cfg.algo.servo_gain is not None else (1.0, 1.0)
    if not 0 < low <= high:
        raise ValueError(f"algo.servo_gain=[{low}, {high}]: a range of positive gains, low first")
    gains = np.random.default_rng(cfg.seed).uniform(low, high, num_envs)
    return [
        {"servo_gain": round(float(gain), 4), **conditions[env % len(conditions)]}
        for env, gain in enumerate(gains)
    ]
