"""The search distribution N(θ̃, Σ) over command parameters (the paper's "high policy")."""

from __future__ import annotations

from dataclasses import dataclass

import torch
from tensordict import TensorDict

from jugglerl.commands import ViaPointCommand
from jugglerl.dps.params import (
    ViaPointConstraints,
    command_to_params,
    component_stds,
    params_to_command,
)

#: Per-component stds of the paper authors' code (s, s, rad, rad).
PAPER_STDS = {"cycle": 0.05, "time": 0.02, "lift": 0.02, "elbow": 0.02}


@dataclass(frozen=True)
class SearchDistribution:
    """A Gaussian over θ: ``mean`` ``[n]`` and full covariance ``cov`` ``[n, n]`` (float64).

    Updates return a new distribution; ``to_tensordict``/``from_tensordict`` carry it through the
    collector's ``update_policy_weights_`` and checkpoints.
    """

    mean: torch.Tensor
    cov: torch.Tensor

    def __post_init__(self):
        n = self.mean.shape[-1]
        if self.mean.shape != (n,) or self.cov.shape != (n, n):
            raise ValueError(f"mean {tuple(self.mean.shape)} and cov {tuple(self.cov.shape)}")

    @classmethod
    def diagonal(cls, mean: torch.Tensor, stds: torch.Tensor) -> SearchDistribution:
        mean = mean.to(torch.float64)
        return cls(mean, torch.diag(stds.to(torch.float64) ** 2))

    @classmethod
    def around(cls, command: ViaPointCommand, stds: dict[str, float]) -> SearchDistribution:
        """Centred on ``command``'s θ, with one std per component (``cycle``, ``time``, ...)."""
        return cls.diagonal(
            command_to_params(command), component_stds(len(command.via_points), stds)
        )

    @property
    def stds(self) -> torch.Tensor:
        return self.cov.diagonal().sqrt()

    def sample(self, count: int, generator: torch.Generator, constraints) -> torch.Tensor:
        """``[count, n]`` samples, each projected by ``constraints.project``."""
        noise = torch.randn(count, len(self.mean), generator=generator, dtype=torch.float64)
        raw = self.mean + noise @ _cholesky_factor(self.cov).T
        return constraints.project(raw)

    def to_tensordict(self) -> TensorDict:
        return TensorDict(mean=self.mean.clone(), cov=self.cov.clone())

    @classmethod
    def from_tensordict(cls, data: TensorDict) -> SearchDistribution:
        return cls(data["mean"].to(torch.float64), data["cov"].to(torch.float64))


def sample_commands(
    command: ViaPointCommand,
    count: int,
    constraints: ViaPointConstraints,
    seed: int = 0,
    stds: dict[str, float] = PAPER_STDS,
) -> list[ViaPointCommand]:
    """``count`` valid commands drawn around ``command`` (for benchmarks and tests)."""
    samples = SearchDistribution.around(command, stds).sample(
        count, torch.Generator().manual_seed(seed), constraints
    )
    return [
        params_to_command(theta, command.pan, f"{command.name}_{i}")
        for i, theta in enumerate(samples)
    ]


def _cholesky_factor(cov: torch.Tensor) -> torch.Tensor:
    """Lower factor L with L Lᵀ = cov; tolerates zero variances (a frozen entry of θ)."""
    factor, info = torch.linalg.cholesky_ex(cov)
    if int(info) == 0:
        return factor
    values, vectors = torch.linalg.eigh(cov)  # positive semi-definite: clip rounding below 0
    return vectors * values.clamp(min=0).sqrt()
