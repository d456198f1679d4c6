"""``ereps``: episodic REPS (Ploeger et al. 2020), weights exp(R / η) under a KL bound."""

from __future__ import annotations

import math

import torch

from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.updates import UPDATES, UpdateRule, floor_variances


@UPDATES.register("ereps")
class EpisodicREPS(UpdateRule):
    """Episodic REPS: weights exp(R_i / η) with η from the dual under KL bound ``epsilon``."""

    def __init__(self, epsilon: float, min_stds: torch.Tensor):
        if epsilon <= 0:
            raise ValueError(f"algo.epsilon={epsilon}: the KL bound of ereps must be > 0")
        self.epsilon = epsilon
        self.min_stds = min_stds

    @classmethod
    def from_config(cls, algo, initial_stds):
        return cls(algo.epsilon, initial_stds * algo.min_std_scale)

    def __call__(self, distribution, params, returns):
        weights, _ = ereps_weights(returns, self.epsilon)
        mean = weights @ params
        centred = params - mean
        cov = (centred * weights[:, None]).T @ centred
        return SearchDistribution(mean, floor_variances(cov, self.min_stds))


def ereps_weights(returns: torch.Tensor, epsilon: float) -> tuple[torch.Tensor, float]:
    """Normalised sample weights and temperature η of episodic REPS.

    η minimises the dual g(η) = η ε + η log((1/N) Σ exp(R_i / η)). Its derivative is
    g'(η) = ε - KL(q_η ‖ uniform), with q_η ∝ exp(R / η), and decreases in η; so the minimum is
    where the weights' KL from uniform equals ε, found by bisection on log η. When no η reaches ε
    (ties at the top cap the KL below ε), the smallest η bracketed is used: weights then go to the
    best samples alone.
    """
    returns = returns.to(torch.float64)
    count = len(returns)
    spread = float(returns.max() - returns.min())
    if spread == 0:
        return torch.full((count,), 1.0 / count, dtype=torch.float64), math.inf

    def kl_from_uniform(eta: float) -> float:
        log_q = torch.log_softmax(returns / eta, dim=0)
        return float((log_q.exp() * (log_q + math.log(count))).sum())

    low, high = math.log(spread * 1e-6), math.log(spread * 1e6)
    if kl_from_uniform(math.exp(low)) <= epsilon:
        high = low
    for _ in range(100):
        middle = (low + high) / 2
        if kl_from_uniform(math.exp(middle)) > epsilon:  # g' < 0: the minimum lies at larger η
            low = middle
        else:
            high = middle
    eta = math.exp(high)  # the side with KL <= ε
    return torch.softmax(returns / eta, dim=0), eta
