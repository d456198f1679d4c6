"""``BatchCollector``: batches of steps from every env of a TorchRL env stack, whose running
episodes carry on from one batch to the next and through a checkpoint.

TorchRL's collectors carry the envs' state between batches too, but a collector rebuilt from a
checkpoint starts every env on a new episode (the env state is not theirs to save). Here the
carried tensordict (each env's last step under the transform stack: step counts, the ball clock,
an LSTM's state, exploration noise) and, on a ``JuggleBatchEnv``, the physics, random generators
and event trackers of every env are the collector's state: a collector that loads it continues
bit for bit. On a Gymnasium vector env (``collector.env=gym``) the env state cannot be saved, so
a loaded collector starts new episodes (``resumes_exactly`` says which).

Each step is numbered with its episode's trajectory id (``("collector", "traj_ids")``, as
TorchRL's collectors write it, so the replay buffer's ``SliceSampler`` keeps slices within one
episode); an env that starts an episode gets the next free id.
"""

from __future__ import annotations

import torch
from tensordict import TensorDict
from torchrl.envs import EnvBase
from torchrl.envs.utils import ExplorationType, set_exploration_type

from jugglerl.batch.torchrl_env import JuggleBatchEnv
from jugglerl.runs.interrupts import deferred_interrupt

#: Where each step's trajectory id is written (TorchRL's collectors' key).
TRAJECTORY_KEY = ("collector", "traj_ids")


class BatchCollector:
    """Steps of ``env`` (a ``TransformedEnv`` of ``batch_size=[num_envs]``) under a policy."""

    def __init__(self, env: EnvBase):
        self.env = env
        self.carried: TensorDict | None = None  # every env's state after the last step
        self.next_trajectory = 0  # the id the next episode gets

    @property
    def resumes_exactly(self) -> bool:
        """Whether ``state_dict`` holds the envs' running episodes (a ``JuggleBatchEnv``)."""
        return isinstance(self.env.base_env, JuggleBatchEnv)

    def restart(self, seed: int) -> None:
        """Every env starts a new episode at the next batch, env ``i`` seeded with ``seed + i``."""
        self.env.set_seed(seed)
        self.carried = None

    def collect(self, policy, steps: int, random: bool = False) -> TensorDict:
        """``steps`` steps of every env under ``policy`` (sampling its exploration), or of
        uniformly random actions with ``random``: a tensordict ``[num_envs, steps]``. A Ctrl-C
        during the batch is raised once it is whole and carried, so that a checkpoint never
        pairs envs stepped part of a batch with the steps carried from the batch before (the
        interrupted batch itself is dropped: a resume after a Ctrl-C continues the episodes but
        does not repeat the uninterrupted run exactly, as one from a periodic checkpoint does)."""
        carried = self.carried if self.carried is not None else self._start()
        trajectory = []
        with deferred_interrupt(), torch.no_grad(), set_exploration_type(ExplorationType.RANDOM):
            for _ in range(steps):
                carried = self.env.rand_action(carried) if random else policy(carried)
                step, carried = self.env.step_and_maybe_reset(carried)
                trajectory.append(step)
                carried.set(TRAJECTORY_KEY, self._numbered(step))
            self.carried = carried
        return torch.stack(trajectory, dim=1)

    def _start(self) -> TensorDict:
        carried = self.env.reset()
        carried.set(TRAJECTORY_KEY, self._new_ids(self.env.batch_size.numel()))
        return carried

    def _numbered(self, step: TensorDict) -> torch.Tensor:
        """The trajectory ids after ``step``: a new one for each env whose episode ended."""
        ids = step.get(TRAJECTORY_KEY).clone()
        ended = step.get(("next", "done")).reshape(ids.shape)
        if ended.any():
            ids[ended] = self._new_ids(int(ended.sum()))
        return ids

    def _new_ids(self, count: int) -> torch.Tensor:
        ids = torch.arange(self.next_trajectory, self.next_trajectory + count)
        self.next_trajectory += count
        return ids

    def state_dict(self) -> dict:
        """The carried steps, the trajectory counter and (``resumes_exactly``) every env's state;
        ``{}`` for a collector whose episodes cannot be saved."""
        if not self.resumes_exactly:
            return {}
        return {
            "carried": self.carried,
            "envs": self.env.base_env.batch.state_dict(),
            "next_trajectory": self.next_trajectory,
        }

    def load_state_dict(self, state: dict) -> bool:
        """Continue the episodes of ``state_dict()``; ``False`` (the envs start new episodes at
        the next batch) for an empty one, or one of another number of envs."""
        if not state or not self.resumes_exactly:
            return False
        if len(state["envs"]["physics"]) != self.env.batch_size.numel():
            return False
        self.env.base_env.batch.load_state_dict(state["envs"])
        self.carried = state["carried"]
        self.next_trajectory = state.get("next_trajectory", 0)
        return True
