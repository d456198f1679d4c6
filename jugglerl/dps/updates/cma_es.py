"""``cmaes``: CMA-ES (Hansen's covariance matrix adaptation), from the maintained ``cmaes`` package.

The rule tells ``cmaes.CMA`` the batch the collector sampled from the current distribution
(``CMA.tell`` takes any samples of N(m, σ² C), negated returns as costs) and hands back
N(m, σ² C) as the next search distribution. The CMA object is created on the first update from
the distribution it is given (its mean, ``σ = 1`` and ``C`` = its covariance, so ``algo.std`` sets
the initial step per entry); its evolution paths and step size live in the rule's state, so a
resumed run continues the same adaptation. The population is ``algo.rollouts``. Unlike ``ereps``
and ``elite``, no std floor: the step size adapts itself (it grows while the mean keeps moving the
same way), which lets the search travel further than the KL-bounded refits.
"""

from __future__ import annotations

import numpy as np
import torch
from cmaes import CMA

from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.updates import UPDATES, UpdateRule


@UPDATES.register("cmaes")
class CMAES(UpdateRule):
    def __init__(self, population: int, seed: int = 0):
        if population < 2:
            raise ValueError(f"algo.rollouts={population}: CMA-ES needs a population of >= 2")
        self.population = population
        self.seed = seed
        self.cma: CMA | None = None

    @classmethod
    def from_config(cls, algo, initial_stds):
        if torch.any(torch.as_tensor(initial_stds) <= 0):
            # the package inverts C: a zero variance ends the run in a linear-algebra error
            raise ValueError(
                "algo.std: CMA-ES needs every std > 0; to hold a parameter fixed, give it equal"
                " bounds (algo.bounds.NAME=[v,v]) and a small std"
            )
        return cls(algo.rollouts)

    def __call__(self, distribution, params, returns):
        if self.cma is None:
            self.cma = CMA(
                mean=distribution.mean.numpy().copy(),
                sigma=1.0,
                cov=distribution.cov.numpy().copy(),
                population_size=self.population,
                seed=self.seed,  # CMA's own sampler is never used: the collector samples
            )
        if len(returns) != self.population:
            raise ValueError(
                f"CMA-ES got {len(returns)} roll-outs for a population of "
                f"{self.population} (algo.rollouts)"
            )
        costs = (-returns.to(torch.float64)).tolist()
        self.cma.tell(list(zip(params.numpy().copy(), costs, strict=True)))
        # The package keeps σ and C private; N(m, σ² C) is the distribution it samples from. C is
        # made exactly symmetric, as the package's next update would make it first anyway: its
        # pickle keeps one triangle, so a resumed run then continues to the last bit.
        self.cma._C = (self.cma._C + self.cma._C.T) / 2
        cov = self.cma._sigma**2 * self.cma._C
        return SearchDistribution(torch.as_tensor(np.array(self.cma.mean)), torch.as_tensor(cov))

    def state_dict(self) -> dict:
        return {"cma": self.cma}

    def load_state_dict(self, state: dict) -> None:
        self.cma = state["cma"]
