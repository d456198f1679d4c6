"""The replay buffer: uniform transitions for an MLP actor, sub-trajectories for an LSTM actor.

In a run folder the frames live in TorchRL's memory-mapped storage (``LazyMemmapStorage``), in
files the buffer writes into as it fills (sparse files of the buffer's whole size, only the
frames stored taking space). A checkpoint then saves only how far the buffer has filled
(``state_dict``: a few numbers, where writing its 1.2 GB again would take seconds), and a
resumed run reopens the files in place (``load_state_dict``). Frames written after the
checkpoint, before a kill, lie beyond the saved fill and are written again; only a buffer that
was full at the checkpoint may have lost old frames to them (``wrapped``).
"""

from __future__ import annotations

import logging
import shutil
import warnings
from pathlib import Path

import torch
from omegaconf import DictConfig
from tensordict import TensorDictBase
from torchrl.data import (
    LazyMemmapStorage,
    LazyTensorStorage,
    RandomSampler,
    RoundRobinWriter,
    SliceSampler,
    TensorDictReplayBuffer,
)

from jugglerl.batch.collector import TRAJECTORY_KEY
from jugglerl.runs.files import RunFileError, failure

# TorchRL logs each storage it allocates at INFO, between a run's progress bar and its results
logging.getLogger("torchrl").setLevel(logging.WARNING)


class MemmapStorage(LazyMemmapStorage):
    """TorchRL's memory-mapped storage, read through plain tensor views of its maps.

    Indexing tensordict's ``MemoryMappedTensor`` does Python work per key and call (it keeps the
    file name and index for pickling), and TorchRL's slice sampler reads every key of the sampled
    rows three times per batch. The views share the maps' memory, so they read what the storage
    writes; saving and reopening still go through the maps. ``get(index, keys)`` reads only the
    entries ``keys`` name."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._views = self._views_of = None

    def get(self, index, keys: list | None = None):
        if not self.initialized:
            return super().get(index)
        if self._views_of is not self._storage:  # built, or reopened from the files
            self._views = self._storage.apply(lambda tensor: tensor.as_subclass(torch.Tensor))
            self._views_of = self._storage
        views = self._views if keys is None else self._views.select(*keys)
        views = views if self._is_full else views[: self._len_along_dim0]
        return views[index]


class ReplayBuffer:
    """``size`` frames; ``sample()`` gives ``batch_size`` transitions, shaped ``[batch_size]``,
    or with ``slice_len`` ``[batch_size // slice_len, slice_len]`` consecutive steps.

    With ``slice_len`` it can sample (``ready``) once it holds a trajectory piece of at least
    ``slice_len`` steps: batches where every env's episode ended early (a run's first batches,
    or the first after a resume, which starts without the buffer) hold only shorter pieces, and
    TorchRL's ``SliceSampler`` raises on those.

    With ``folder`` the frames are memory-mapped there; without, they stay in memory."""

    def __init__(
        self,
        size: int,
        batch_size: int,
        slice_len: int | None = None,
        folder: Path | None = None,
    ):
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
        self._sampler = (
            RandomSampler()
            if slice_len is None
            else SliceSampler(
                slice_len=slice_len,
                traj_key=TRAJECTORY_KEY,
                strict_length=True,
                cache_values=True,  # the trajectories' bounds, found again after each extend
            )
        )
        self.folder = folder
        self._storage = (
            LazyTensorStorage(size)
            if folder is None
            else MemmapStorage(size, scratch_dir=folder / "storage", existsok=True)
        )
        self._writer = RoundRobinWriter()
        self._buffer = TensorDictReplayBuffer(
            storage=self._storage, sampler=self._sampler, writer=self._writer
        )
        self._longest_piece = 0  # steps of the longest trajectory piece stored so far
        self._last_id: torch.Tensor | None = None  # the id the storage ends with, and its run
        self._last_run = 0

    @classmethod
    def from_config(
        cls, buffer_cfg: DictConfig, recurrent: bool, folder: Path | None = None
    ) -> ReplayBuffer:
        slice_len = buffer_cfg.slice_len if recurrent else None
        return cls(buffer_cfg.size, buffer_cfg.batch_size, slice_len, folder)

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
        self._check_space(flat)
        try:
            self._buffer.extend(flat)
        except (OSError, RuntimeError) as error:  # torch's memory maps could not be made
            raise failure(self.folder, "write the replay buffer", error) from None
        if self.slice_len is None:
            self._longest_piece = 1
        elif self._longest_piece < self.slice_len:
            ids = flat[TRAJECTORY_KEY]
            if self._last_id is not None:  # one env's batches do follow each other
                ids = torch.cat([self._last_id.expand(self._last_run), ids])
            runs = run_lengths(ids)
            self._longest_piece = max(self._longest_piece, int(runs.max()))
            self._last_id, self._last_run = ids[-1:], int(runs[-1])

    def _check_space(self, frames: TensorDictBase) -> None:
        """``RunFileError`` when the folder's disk cannot take ``frames``: a write into a
        memory-mapped file on a full disk kills the process (``SIGBUS``) instead of raising."""
        if self.folder is None:
            return
        self.folder.mkdir(parents=True, exist_ok=True)
        free = shutil.disk_usage(self.folder).free
        if free < 2 * frames.bytes():
            raise RunFileError(
                f"{self.folder}: could not write the replay buffer (no space left on device:"
                f" {free / 1e6:.0f} MB free for batches of {frames.bytes() / 1e6:.0f} MB)"
            )

    def sample(self, fraction: float = 1.0, keys: list | None = None) -> TensorDictBase:
        """``fraction`` of a batch (rounded to whole sub-trajectories, at least one); with
        ``keys``, the memory-mapped frames give only those entries (the same frames: the sampler
        draws as TorchRL's buffer has it draw)."""
        unit = self.slice_len or 1
        count = max(1, round(self.batch_size * fraction / unit)) * unit
        if keys is None or not isinstance(self._storage, MemmapStorage):
            batch = self._buffer.sample(count)
        else:
            index, _ = self._sampler.sample(self._storage, count)
            batch = self._storage.get(index, keys)
        return batch if self.slice_len is None else batch.reshape(-1, self.slice_len)

    @property
    def capacity(self) -> int:
        return self._storage.max_size

    @property
    def wrapped(self) -> bool:
        """Whether the buffer is full, so that new frames replace its oldest ones."""
        return len(self) >= self.capacity

    def state_dict(self) -> dict:
        """How far the buffer has filled (its frames are in ``folder``), for a checkpoint;
        TorchRL's metadata files beside the frames are brought up to date with it."""
        if self.folder is None:
            raise ValueError("a replay buffer without a folder keeps its frames in memory only")
        state = {
            "length": len(self),
            "writer": self._writer.state_dict(),
            "longest_piece": self._longest_piece,
            "last_id": self._last_id,
            "last_run": self._last_run,
        }
        if len(self):
            try:
                with warnings.catch_warnings():  # TorchRL's cursor is for save hooks: none here
                    warnings.filterwarnings("ignore", "last_cursor is None")
                    self._buffer.dumps(self.folder)
            except OSError as error:
                raise failure(self.folder, "write the replay buffer", error) from None
        return state

    def load_state_dict(self, state: dict) -> bool:
        """Reopen the frames in ``folder`` filled as far as ``state`` says; ``False`` (the
        buffer left empty) when the folder does not hold them."""
        if state["length"] == 0:
            return True
        if self.folder is None or not (self.folder / "storage" / "storage_metadata.json").exists():
            return False
        self._buffer.loads(self.folder)
        # the checkpoint's fill, not the one the files were last synced with: a kill between
        # the two leaves the files a step ahead (TorchRL's own checkpointer sets it the same way)
        self._storage._len = state["length"]
        self._writer.load_state_dict(state["writer"])
        self._longest_piece = state["longest_piece"]
        self._last_id, self._last_run = state["last_id"], state["last_run"]
        return True


def run_lengths(ids: torch.Tensor) -> torch.Tensor:
    """The lengths of the runs of equal consecutive values of ``ids`` (1-d), in order."""
    starts = torch.nonzero(ids[1:] != ids[:-1]).flatten() + 1
    edges = torch.cat([torch.zeros(1, dtype=starts.dtype), starts, torch.tensor([ids.numel()])])
    return edges.diff()
