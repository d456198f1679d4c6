"""The replay buffer: uniform transitions for an MLP actor, sub-trajectories for an LSTM actor."""

from __future__ import annotations

import torch
from omegaconf import DictConfig
from tensordict import TensorDictBase
from torchrl.data import LazyTensorStorage, RandomSampler, SliceSampler, TensorDictReplayBuffer

#: Where the collector writes each frame's trajectory id; slices never cross trajectories.
TRAJECTORY_KEY = ("collector", "traj_ids")


class ReplayBuffer:
    """``size`` frames; ``sample()`` gives ``batch_size`` transitions, shaped ``[batch_size]``,
    or with ``slice_len`` ``[batch_size // slice_len, slice_len]`` consecutive steps.

    With ``slice_len`` it can sample (``ready``) once it holds a trajectory piece of at least
    ``slice_len`` steps: batches where every env's episode ended early (a run's first batches,
    or the first after a resume, which starts without the buffer) hold only shorter pieces, and
    TorchRL's ``SliceSampler`` raises on those."""

    def __init__(self, size: int, batch_size: int, slice_len: int | None = None):
        if batch_size < 1 or size < batch_size:
            raise ValueError(
                f"replay_buffer.batch_size={batch_size} must be in [1, replay_buffer.size={size}]"
            )
        if slice_len is not None and (slice_len < 1 or batch_size % slice_len):
            raise ValueError(
                f"replay_buffer.batch_size={batch_size} must be a multiple of"
                f" replay_buffer.slice_len={slice_len}"
            )
        self.slice_len = slice_len
        self.batch_size = batch_size
        sampler = (
            RandomSampler()
            if slice_len is None
            else SliceSampler(slice_len=slice_len, traj_key=TRAJECTORY_KEY, strict_length=True)
        )
        self._buffer = TensorDictReplayBuffer(storage=LazyTensorStorage(size), sampler=sampler)
        self._longest_piece = 0  # steps of the longest trajectory piece stored so far
        self._last_id: torch.Tensor | None = None  # the id the storage ends with, and its run
        self._last_run = 0

    @classmethod
    def from_config(cls, buffer_cfg: DictConfig, recurrent: bool) -> ReplayBuffer:
        slice_len = buffer_cfg.slice_len if recurrent else None
        return cls(buffer_cfg.size, buffer_cfg.batch_size, slice_len)

    def __len__(self) -> int:
        return len(self._buffer)

    @property
    def sliceable(self) -> bool:
        """Whether it holds something to sample: a frame, with ``slice_len`` a long piece."""
        return self._longest_piece >= (self.slice_len or 1)

    @property
    def ready(self) -> bool:
        """Whether ``sample()`` can fill a whole batch."""
        return len(self) >= self.batch_size and self.sliceable

    def extend(self, batch: TensorDictBase) -> None:
        """Store a collector batch ``[envs, time]``, each env's steps kept consecutive (a
        trajectory's piece in one batch is one run of equal ids; pieces of consecutive batches
        are not adjacent in the storage)."""
        flat = batch.reshape(-1)
        self._buffer.extend(flat)
        if self.slice_len is None:
            self._longest_piece = 1
        elif self._longest_piece < self.slice_len:
            ids = flat[TRAJECTORY_KEY]
            if self._last_id is not None:  # one env's batches do follow each other
                ids = torch.cat([self._last_id.expand(self._last_run), ids])
            runs = run_lengths(ids)
            self._longest_piece = max(self._longest_piece, int(runs.max()))
            self._last_id, self._last_run = ids[-1:], int(runs[-1])

    def sample(self, fraction: float = 1.0) -> TensorDictBase:
        """``fraction`` of a batch (rounded to whole sub-trajectories, at least one)."""
        unit = self.slice_len or 1
        count = max(1, round(self.batch_size * fraction / unit)) * unit
        batch = self._buffer.sample(count)
        return batch if self.slice_len is None else batch.reshape(-1, self.slice_len)


def run_lengths(ids: torch.Tensor) -> torch.Tensor:
    """The lengths of the runs of equal consecutive values of ``ids`` (1-d), in order."""
    starts = torch.nonzero(ids[1:] != ids[:-1]).flatten() + 1
    edges = torch.cat([torch.zeros(1, dtype=starts.dtype), starts, torch.tensor([ids.numel()])])
    return edges.diff()
