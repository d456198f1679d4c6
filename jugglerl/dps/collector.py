"""``DPSCollector``: Direct Policy Search as a TorchRL collector.

Each iteration samples ``frames_per_batch`` parameter vectors θ of a search space
(``jugglerl.dps.spaces``) from the current search distribution, projects them onto the space's
constraints, rolls their decoded candidates out (commands at raw physics speed, or closed-loop
policies in worker processes) and yields a ``[frames_per_batch]`` TensorDict:

- ``params`` (float64, ``[n]``): θ, laid out as the space defines it;
- ``return`` (float64): throws in the roll-out (the paper's reward); ``throws``: the same as int64;
- ``time_to_drop`` (float64): seconds until the ball fell below the drop height, NaN if never;
- ``seed`` (int64): the env reset seed of the roll-out (with ``common_seeds``, one for the whole
  batch: every sample then meets the same starts and the same noise, so their ranking compares
  the samples rather than their luck);
- ``("collector", "iteration")`` (int64): index of the batch.

A "frame" here is one roll-out (one whole episode): ``total_frames`` is the roll-out budget.
The learner refits the distribution from the batch and hands it back with
``update_policy_weights_(distribution.to_tensordict())``; the next batch samples from it.
``state_dict`` holds the distribution, the sampling RNG and the counters, so a run restored with
``load_state_dict`` draws exactly the samples the uninterrupted run would have drawn.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Iterator, Sequence
from typing import Any, Protocol

import torch
from tensordict import TensorDict, TensorDictBase
from torchrl.collectors import BaseCollector

from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.rollouts import RolloutResults

#: Reset seeds of roll-outs are drawn below this bound (they matter when the env has reset noise).
SEED_BOUND = 2**31 - 1


class Space(Protocol):
    """What the collector needs of a search space: its constraints and its decoding."""

    def project(self, params: torch.Tensor) -> torch.Tensor: ...

    def decode(self, params: torch.Tensor) -> Any: ...


class Rollouts(Protocol):
    def evaluate(self, candidates: Sequence[Any], seeds: Sequence[int]) -> RolloutResults: ...

    def close(self) -> None: ...


class DPSCollector(BaseCollector):
    """Samples θ of a search space from a search distribution and rolls them out.

    Args:
        space: the search space (``project`` samples onto its constraints, ``decode`` one θ
            into what ``rollouts`` evaluates).
        rollouts: evaluates candidates (``evaluate(candidates, seeds)`` gives ``RolloutResults``;
            it owns the env and the workers, closed by ``shutdown``).
        distribution: the starting search distribution.
        frames_per_batch: roll-outs per iteration (the paper's N).
        total_frames: roll-out budget; ``-1`` runs until stopped.
        seed: seeds the sampling RNG.
        common_seeds: every sample of a batch rolls out with the batch's one reset seed.
    """

    def __init__(
        self,
        space: Space,
        rollouts: Rollouts,
        distribution: SearchDistribution,
        *,
        frames_per_batch: int,
        total_frames: int = -1,
        seed: int = 0,
        common_seeds: bool = False,
    ):
        super().__init__()
        if frames_per_batch < 1:
            raise ValueError("frames_per_batch (roll-outs per batch) must be >= 1")
        self.space = space
        self.rollouts = rollouts
        self.distribution = distribution
        self.frames_per_batch = self.requested_frames_per_batch = frames_per_batch
        self.total_frames = total_frames
        self.common_seeds = common_seeds
        self.generator = torch.Generator()
        self.set_seed(seed)
        self.iteration = 0
        self.frames = 0

    def iterator(self) -> Iterator[TensorDictBase]:
        while self.total_frames < 0 or self.frames < self.total_frames:
            yield self.collect_batch()

    def collect_batch(self) -> TensorDict:
        """Sample, roll out and count one batch."""
        count = self.frames_per_batch
        if self.total_frames >= 0:
            count = min(count, self.total_frames - self.frames)
        params = self.distribution.sample(count, self.generator, self.space)
        draws = 1 if self.common_seeds else count
        seeds = torch.randint(SEED_BOUND, (draws,), generator=self.generator).repeat(count // draws)
        candidates = [self.space.decode(theta) for theta in params]
        results = self.rollouts.evaluate(candidates, seeds.tolist())
        throws = torch.as_tensor(results.throws, dtype=torch.int64)
        batch = TensorDict(
            {
                "params": params,
                "return": throws.to(torch.float64),
                "throws": throws,
                "time_to_drop": torch.as_tensor(results.time_to_drop, dtype=torch.float64),
                "seed": seeds,
                ("collector", "iteration"): torch.full((count,), self.iteration),
            },
            batch_size=[count],
        )
        self.iteration += 1
        self.frames += count
        return batch

    def update_policy_weights_(self, policy_or_weights=None, *, weights=None, **kwargs) -> None:
        """Replace the search distribution: a ``SearchDistribution`` or its TensorDict
        (``mean``, ``cov``)."""
        new = weights if weights is not None else policy_or_weights
        if isinstance(new, TensorDictBase):
            new = SearchDistribution.from_tensordict(new)
        if not isinstance(new, SearchDistribution):
            raise TypeError(f"expected a SearchDistribution or its TensorDict, got {type(new)}")
        self.distribution = new

    def set_seed(self, seed: int, static_seed: bool = False) -> int:
        self.generator.manual_seed(seed)
        return seed

    def state_dict(self) -> OrderedDict:
        return OrderedDict(
            distribution=self.distribution.to_tensordict().to_dict(),
            generator=self.generator.get_state(),
            iteration=self.iteration,
            frames=self.frames,
        )

    def load_state_dict(self, state_dict: OrderedDict) -> None:
        self.distribution = SearchDistribution.from_tensordict(
            TensorDict(state_dict["distribution"])
        )
        self.generator.set_state(state_dict["generator"])
        self.iteration = int(state_dict["iteration"])
        self.frames = int(state_dict["frames"])

    def shutdown(self, timeout=None, close_env: bool = True, raise_on_error: bool = True) -> None:
        if close_env:
            self.rollouts.close()

    def __repr__(self) -> str:
        return (
            f"DPSCollector(frames_per_batch={self.frames_per_batch},"
            f" total_frames={self.total_frames}, iteration={self.iteration})"
        )
