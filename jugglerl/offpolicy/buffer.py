"""The replay buffer: uniform transitions for an MLP actor, sub-trajectories for an LSTM actor."""

from __future__ import annotations

from omegaconf import DictConfig
from tensordict import TensorDictBase
from torchrl.data import LazyTensorStorage, RandomSampler, SliceSampler, TensorDictReplayBuffer

#: Where the collector writes each frame's trajectory id; slices never cross trajectories.
TRAJECTORY_KEY = ("collector", "traj_ids")


class ReplayBuffer:
    """``size`` frames; ``sample()`` gives ``batch_size`` transitions, shaped ``[batch_size]``,
    or with ``slice_len`` ``[batch_size // slice_len, slice_len]`` consecutive steps."""

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

    @classmethod
    def from_config(cls, buffer_cfg: DictConfig, recurrent: bool) -> ReplayBuffer:
        slice_len = buffer_cfg.slice_len if recurrent else None
        return cls(buffer_cfg.size, buffer_cfg.batch_size, slice_len)

    def __len__(self) -> int:
        return len(self._buffer)

    def extend(self, batch: TensorDictBase) -> None:
        """Store a collector batch ``[envs, time]``, each env's steps kept consecutive."""
        self._buffer.extend(batch.reshape(-1))

    def sample(self, fraction: float = 1.0) -> TensorDictBase:
        """``fraction`` of a batch (rounded to whole sub-trajectories, at least one)."""
        unit = self.slice_len or 1
        count = max(1, round(self.batch_size * fraction / unit)) * unit
        batch = self._buffer.sample(count)
        return batch if self.slice_len is None else batch.reshape(-1, self.slice_len)
