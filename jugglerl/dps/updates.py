"""Update rules of the search distribution: from one batch of (θ_i, R_i) to the next N(θ̃, Σ).

- ``greedy``: the mean jumps to the best θ seen so far (the paper's "keep best"); Σ fixed.
- ``weighted``: the mean becomes the reward-weighted mean of the batch (the paper's alternative);
  Σ fixed.
- ``elite``: mean and per-entry std of the top ``elite`` samples (the cross-entropy method: the
  paper's proposed fix for getting stuck).
- ``ereps``: episodic REPS (Ploeger et al. 2020): the temperature η solves the REPS dual under a
  KL bound ε, samples get weights exp(R_i / η), mean and full covariance are refitted.

``elite`` and ``ereps`` keep every std at least ``min_std_scale`` times its initial value, so the
search can still move after it has narrowed.

Each rule is a callable ``rule(distribution, params, returns) -> distribution`` with a
``state_dict``/``load_state_dict`` pair (only ``greedy`` has state: the best return so far).
"""

from __future__ import annotations

import math

import torch

from jugglerl.dps.distribution import SearchDistribution

UPDATES = ("greedy", "weighted", "elite", "ereps")


class UpdateRule:
    """Base class: stateless rules inherit the empty state."""

    def __call__(
        self, distribution: SearchDistribution, params: torch.Tensor, returns: torch.Tensor
    ) -> SearchDistribution:
        raise NotImplementedError

    def state_dict(self) -> dict:
        return {}

    def load_state_dict(self, state: dict) -> None:
        pass


class Greedy(UpdateRule):
    """Keep the best: the mean moves to a sample only when it beats every earlier sample."""

    def __init__(self):
        self.best_return = -math.inf

    def __call__(self, distribution, params, returns):
        best = int(torch.argmax(returns))
        if float(returns[best]) <= self.best_return:
            return distribution
        self.best_return = float(returns[best])
        return SearchDistribution(params[best].clone(), distribution.cov)

    def state_dict(self) -> dict:
        return {"best_return": self.best_return}

    def load_state_dict(self, state: dict) -> None:
        self.best_return = float(state["best_return"])


class RewardWeighted(UpdateRule):
    """Mean = Σ R_i θ_i / Σ R_i over the batch (returns must be >= 0, as throw counts are)."""

    def __call__(self, distribution, params, returns):
        if torch.any(returns < 0):
            raise ValueError("the reward-weighted update needs returns >= 0")
        total = returns.sum()
        if total <= 0:
            return distribution
        mean = (returns.to(params.dtype) / total) @ params
        return SearchDistribution(mean, distribution.cov)


class Elite(UpdateRule):
    """Mean and per-entry std of the ``count`` best samples (std floored at ``min_stds``)."""

    def __init__(self, count: int, min_stds: torch.Tensor):
        if count < 2:
            raise ValueError(f"elite needs at least 2 samples to fit a std, got {count}")
        self.count = count
        self.min_stds = min_stds

    def __call__(self, distribution, params, returns):
        if self.count > len(returns):
            raise ValueError(f"elite={self.count} is more than the {len(returns)} roll-outs")
        elite = params[torch.topk(returns.to(torch.float64), self.count).indices]
        stds = torch.maximum(elite.std(dim=0), self.min_stds)
        return SearchDistribution(elite.mean(dim=0), torch.diag(stds**2))


class EpisodicREPS(UpdateRule):
    """Episodic REPS: weights exp(R_i / η) with η from the dual under KL bound ``epsilon``."""

    def __init__(self, epsilon: float, min_stds: torch.Tensor):
        if epsilon <= 0:
            raise ValueError(f"ereps epsilon (KL bound) must be > 0, got {epsilon}")
        self.epsilon = epsilon
        self.min_stds = min_stds

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


def floor_variances(cov: torch.Tensor, min_stds: torch.Tensor) -> torch.Tensor:
    """``cov`` with each variance raised to at least ``min_stds²`` (adding to the diagonal keeps
    it positive semi-definite)."""
    shortfall = (min_stds**2 - cov.diagonal()).clamp(min=0)
    return cov + torch.diag(shortfall)


def make_update(
    name: str, initial_stds: torch.Tensor, *, elite: int, epsilon: float, min_std_scale: float
) -> UpdateRule:
    """The update rule called ``name`` (one of ``UPDATES``)."""
    min_stds = initial_stds * min_std_scale
    rules = {
        "greedy": Greedy,
        "weighted": RewardWeighted,
        "elite": lambda: Elite(elite, min_stds),
        "ereps": lambda: EpisodicREPS(epsilon, min_stds),
    }
    if name not in rules:
        raise ValueError(f"algo.update={name!r} is not one of {', '.join(UPDATES)}")
    return rules[name]()
