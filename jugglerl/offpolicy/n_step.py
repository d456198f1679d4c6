"""n-step returns on a collected batch, so that the critic's targets see further than one step.

A throw comes every ≈ 100 steps (2.06 s at 50 Hz), so a one-step target with γ = 0.95 hardly
sees the reward the task is about. ``n_step_returns(batch, n, gamma)`` rewrites each transition
``t`` of a batch ``[envs, time]`` to reach ``m = min(n, steps to the episode's end, steps left in
the batch)`` steps ahead:

- ``("next", "reward")``: ``Σ_{k<m} γ^k r_{t+k}``;
- every other ``"next"`` entry (state, recurrent state, ``terminated``, ``done``, ...): that of
  step ``t + m - 1``, so a target bootstraps from the state ``m`` steps on, and not at all when
  the episode terminated within the window;
- ``steps_to_next_obs``: ``m``, which TorchRL's TD(0) estimator turns into the discount ``γ^m``.

TorchRL's ``MultiStepTransform`` keeps the one-step ``terminated`` flag (a target would bootstrap
from the terminal state) and holds the last ``n`` steps of each batch back for the next one; this
function keeps each batch whole and cuts the window at its end instead. With ``n = 1`` it only
adds ``steps_to_next_obs = 1``: every batch carries the key, so batches of one-step and n-step
stages share one replay buffer.
"""

from __future__ import annotations

import torch
from tensordict import TensorDictBase

STEPS = "steps_to_next_obs"


def n_step_returns(batch: TensorDictBase, n: int, gamma: float) -> TensorDictBase:
    """``batch`` (``[envs, time]``, time last) with its ``"next"`` entries ``n`` steps ahead."""
    if n < 1:
        raise ValueError(f"n_steps={n} must be >= 1")
    *envs, steps = batch.batch_size
    if n == 1:
        batch.set(STEPS, torch.ones(*envs, steps, 1, dtype=torch.int64))
        return batch
    done = batch.get(("next", "done")).reshape(*envs, steps)
    reward = batch.get(("next", "reward")).reshape(*envs, steps)
    # reach[..., t]: how many steps transition t looks ahead; grows while no episode ends
    reach = torch.ones(*envs, steps, dtype=torch.int64)
    returns = reward.clone()
    open_ = ~done  # the window of t has not met an episode's end yet
    for k in range(1, n):
        ahead = torch.zeros_like(returns)
        ahead[..., : steps - k] = reward[..., k:]
        inside = torch.zeros_like(open_)
        inside[..., : steps - k] = open_[..., : steps - k]
        returns = returns + inside * gamma**k * ahead
        reach = reach + inside.long()
        shifted_done = torch.ones_like(done)
        shifted_done[..., : steps - k] = done[..., k:]
        open_ = inside & ~shifted_done
    last = torch.arange(steps).expand(*envs, steps) + reach - 1
    reward_shape = batch.get(("next", "reward")).shape
    following = batch.get("next").exclude("reward")
    following = following.apply(lambda values: _gather(values, last, len(envs)))
    following.set("reward", returns.reshape(reward_shape))
    batch.set("next", following)
    batch.set(STEPS, reach.unsqueeze(-1))
    return batch


def _gather(values: torch.Tensor, index: torch.Tensor, time_dim: int) -> torch.Tensor:
    """``values`` (time at ``time_dim``) at time ``index[..., t]`` for each ``t``."""
    shape = (*index.shape, *([1] * (values.dim() - index.dim())))
    return values.gather(time_dim, index.reshape(shape).expand_as(values))
