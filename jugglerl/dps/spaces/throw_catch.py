"""``throw_catch`` (``algo=throw_catch``): the rest pose, throw and catch of a
``ThrowCatchPolicy``.

θ is the rest pose's lift and elbow (rad), the throw's knots, flattened (``[duration s, lift
rad, elbow rad]`` each), then ``catch_height`` (m), ``settle`` (s), ``carry`` (s) and, where
the start has them, ``lead`` (s, several balls) and ``still`` (s), searched
from the start policy ``algo.start`` (a ``kind: throw_catch`` file), whose pan and wrist lock
stay (the search env must lock the wrist as it does). Constraints (samples are clipped):
``algo.bounds`` for the durations and the scalars, the servos' control ranges for the
angles. Every θ is rolled out closed loop under each of ``algo.conditions``, and an episode
outside ``algo.limits`` (the cup above 0.76 m, a joint faster than the speed limit, two balls in
the cup at once) scores nothing (``ClosedLoopRollouts``). The best
θ is written as ``best_policy.yaml``.
"""

from __future__ import annotations

from dataclasses import asdict, replace
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch
from omegaconf import DictConfig

from jugglerl.dps.closed_loop_space import POLICY_FILE, ClosedLoopSpace
from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.spaces import SPACES
from jugglerl.policies.throw_catch import (
    ThrowCatch,
    ThrowCatchPolicy,
    save_throw_catch_policy,
    throw_catch_from_dict,
)
from jugglerl.runs.policy_files import check_policy_named, read_policy_file

#: The scalars after the knots, in θ order; ``lead`` and ``still`` only where the start has them.
SCALARS = ("catch_height", "settle", "carry", "lead", "still")


@SPACES.register("throw_catch")
class ThrowCatchSpace(ClosedLoopSpace):
    """θ = [rest lift, rest elbow, knots, catch_height, settle, carry]; see the module
    docstring."""

    def __init__(self, cfg: DictConfig):
        super().__init__(cfg)
        algo = cfg.algo
        check_policy_named("algo.start", algo.start)
        data, source = read_policy_file(algo.start)
        if data.get("kind") != "throw_catch":
            raise ValueError(f"algo.start={algo.start} is not a throw_catch policy file")
        self.template = throw_catch_from_dict(data, source)
        env = self.search_env()
        try:  # refuses a search env that does not start where the policy throws from
            ThrowCatchPolicy(self.template, env, str(data["name"]), data.get("env"))
            low, high = env.unwrapped.model.actuator_ctrlrange[1:3].T.copy()  # lift, elbow
        finally:
            env.close()
        self.knots = len(self.template.knots)
        self.scalars = tuple(key for key in SCALARS if getattr(self.template, key) is not None)
        bounds = {key: algo.bounds[key] for key in ("duration", *self.scalars)}
        self.low, self.high = (
            torch.tensor(
                [*ends, *[bounds["duration"][side], *ends] * self.knots]
                + [bounds[key][side] for key in self.scalars],
                dtype=torch.float64,
            )
            for side, ends in enumerate((low, high))
        )
        if torch.any(self.low > self.high):
            raise ValueError("algo.bounds: every [low, high] needs low <= high")
        start = [*self.template.rest[1:], *(v for knot in self.template.knots for v in knot)]
        start += [getattr(self.template, key) for key in self.scalars]
        self.start = torch.tensor(start, dtype=torch.float64)
        problems = self.violations(self.start)
        if problems:
            raise ValueError(f"algo.start={algo.start}: {'; '.join(problems)}")
        std = algo.std
        self.stds = torch.tensor(
            [std.lift, std.elbow, *[std.duration, std.lift, std.elbow] * self.knots]
            + [std[key] for key in self.scalars],
            dtype=torch.float64,
        )

    def _names(self) -> list[str]:
        parts = ("duration", "lift", "elbow")
        knots = [f"knot{i}.{part}" for i in range(self.knots) for part in parts]
        return ["rest.lift", "rest.elbow", *knots, *self.scalars]

    def project(self, params: torch.Tensor) -> torch.Tensor:
        return torch.clamp(params, self.low, self.high)

    def violations(self, params: torch.Tensor) -> list[str]:
        return [
            f"{name}={float(value):g} outside [{float(lo):g}, {float(hi):g}]"
            for name, value, lo, hi in zip(self._names(), params, self.low, self.high, strict=True)
            if not lo <= value <= hi
        ]

    def decode(self, params: torch.Tensor) -> ThrowCatch:
        values = params.tolist()
        split = 2 + 3 * self.knots
        rest = (self.template.rest[0], *values[:2])
        knots = tuple(tuple(values[i : i + 3]) for i in range(2, split, 3))
        scalars = dict(zip(self.scalars, values[split:], strict=True))
        return replace(self.template, rest=rest, knots=knots, **scalars)

    def build(self, candidate: ThrowCatch, env: gym.Env) -> ThrowCatchPolicy:
        return ThrowCatchPolicy(candidate, env)

    def save(self, params: torch.Tensor, run_dir: Path, name: str, role: str = "best") -> str:
        file = POLICY_FILE.format(role=role)
        balls = self.cfg.env.get("balls", 1)
        save_throw_catch_policy(run_dir / file, self.decode(params), name, balls)
        return file

    def describe(self, params: torch.Tensor, name: str) -> dict:
        best = asdict(self.decode(params))
        return {"throw_catch": {key: np.asarray(value).tolist() for key, value in best.items()}}

    def record(self, distribution: SearchDistribution) -> dict[str, float]:
        """The means of the scalars and of the throw's total duration."""
        mean = distribution.mean
        durations = mean[2 : 2 + 3 * self.knots : 3]
        scalars = zip(self.scalars, mean[2 + 3 * self.knots :], strict=True)
        return {
            "mean_throw_duration": float(durations.sum()),
            **{f"mean_{key}": float(value) for key, value in scalars},
        }
