"""Checkpoint files shared by every training algorithm: written atomically, read with clear errors.

A checkpoint is a dict saved with ``torch.save``. It always holds the run's resolved ``config``
(``config["algo"]["trainer"]`` says which training loop resumes it) and ``deploys``, what the run
deploys as a policy: ``"actor"`` (the network in the checkpoint, whatever loss trained it) or the
name of a policy file in the run directory (a search's best command or feedback policy). It also
holds ``config_unresolved``, the same config with its interpolations kept, which a resume starts
from: an override of ``algo.loss`` then reaches the stage whose loss is ``${algo.loss}``.
"""

from __future__ import annotations

from pathlib import Path

import torch
from omegaconf import DictConfig, OmegaConf

from jugglerl.runs.files import write_atomically

CHECKPOINT = "checkpoint.pt"


def config_entries(cfg: DictConfig) -> dict:
    """A run's config as a checkpoint keeps it: resolved, and with its interpolations."""
    return {
        "config": OmegaConf.to_container(cfg, resolve=True),
        "config_unresolved": OmegaConf.to_container(cfg, resolve=False),
    }


def save_checkpoint(state: dict, path: Path) -> None:
    """Write ``state`` atomically: a crash or a full disk mid-write leaves the previous checkpoint
    intact (``RunFileError`` otherwise, ``jugglerl.runs.files``)."""
    write_atomically(path, lambda file: torch.save(state, file))


def load_checkpoint(path: str | Path) -> dict:
    """A checkpoint from its file or its run directory; ``ValueError`` if it is not one."""
    path = Path(path)
    if path.is_dir():
        path = path / CHECKPOINT
    if not path.is_file():
        raise ValueError(f"no checkpoint at {path}")
    try:
        state = torch.load(path, weights_only=False)
    except Exception as error:  # torch raises many kinds on a damaged file
        raise ValueError(f"{path} is not a readable checkpoint ({error})") from None
    if not isinstance(state, dict) or "deploys" not in state or "config" not in state:
        raise ValueError(f"{path} is not a JuggleRL training checkpoint")
    return state
