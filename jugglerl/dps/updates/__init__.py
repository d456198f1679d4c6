"""Update rules of the search distribution: from one batch of (θ_i, R_i) to the next N(θ̃, Σ).

A rule is a class registered in ``UPDATES`` under its ``algo.update`` name and built by
``make_update`` from the ``algo`` config and the initial stds; calling it,
``rule(distribution, params, returns)``, returns the next distribution. Rules with state (the
greedy rule's best return) carry it in ``state_dict``/``load_state_dict``. Adding one: a module
here (and its keys in the ``configs/algo/`` files that use it).

- ``greedy``: the mean jumps to the best θ seen so far (the paper's "keep best"); Σ fixed.
- ``weighted``: the mean becomes the reward-weighted mean of the batch (the paper's
  alternative); Σ fixed.
- ``elite``: mean and per-entry std of the top ``algo.elite`` samples (the cross-entropy
  method: the paper's proposed fix for getting stuck).
- ``ereps``: episodic REPS (Ploeger et al. 2020): weights exp(R_i / η) with η from the REPS dual
  under the KL bound ``algo.epsilon``; mean and full covariance refitted.

``elite`` and ``ereps`` keep every std at least ``algo.min_std_scale`` times its initial value,
so the search can still move after it has narrowed.
"""

from __future__ import annotations

import torch
from omegaconf import DictConfig

from jugglerl.dps.distribution import SearchDistribution
from jugglerl_envs.registry import Registry

UPDATES = Registry("algo.update", __name__)


class UpdateRule:
    """Base class: ``from_config`` builds a rule; stateless rules inherit the empty state."""

    @classmethod
    def from_config(cls, algo: DictConfig, initial_stds: torch.Tensor) -> UpdateRule:
        return cls()

    def __call__(
        self, distribution: SearchDistribution, params: torch.Tensor, returns: torch.Tensor
    ) -> SearchDistribution:
        raise NotImplementedError

    def state_dict(self) -> dict:
        return {}

    def load_state_dict(self, state: dict) -> None:
        pass


def make_update(algo: DictConfig, initial_stds: torch.Tensor) -> UpdateRule:
    """The rule named ``algo.update``, built from the ``algo`` config."""
    return UPDATES.get(algo["update"]).from_config(algo, initial_stds)  # item: .update is a method


def floor_variances(cov: torch.Tensor, min_stds: torch.Tensor) -> torch.Tensor:
    """``cov`` with each variance raised to at least ``min_stds²`` (adding to the diagonal keeps
    it positive semi-definite)."""
    shortfall = (min_stds**2 - cov.diagonal()).clamp(min=0)
    return cov + torch.diag(shortfall)
