"""What ``scripts/train.py`` runs: the trainer of ``algo.trainer``, resumed or new, to the end.

Trainers (``TRAINERS``): ``offpolicy`` (``jugglerl.offpolicy.training.OffPolicyTraining``: DDPG,
TD3, behaviour cloning) and ``search`` (``jugglerl.dps.training.SearchTraining``: DPS over a
search space). Both are built as ``Trainer(cfg, run_dir, state)`` (``state``: a checkpoint to
resume) and offer ``run(logger, progress)``, ``position()``, ``summary(metrics)``, ``close()`` and
``recording_id``.
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

from omegaconf import DictConfig, OmegaConf

from jugglerl.checkpoints import CHECKPOINT, load_checkpoint
from jugglerl.recording.logger import RerunLogger

TRAINERS = {
    "offpolicy": "jugglerl.offpolicy.training:OffPolicyTraining",
    "search": "jugglerl.dps.training:SearchTraining",
}


def trainer_class(name: str):
    """The trainer class ``algo.trainer`` names (imported on demand: each pulls in its stack)."""
    if name not in TRAINERS:
        raise ValueError(
            f"algo.trainer={name!r} is not available; choose one of {', '.join(TRAINERS)}"
        )
    module, attribute = TRAINERS[name].split(":")
    return getattr(importlib.import_module(module), attribute)


def resume_state(resume: str, cfg: DictConfig, overrides: list[str]) -> tuple:
    """(config, run directory, checkpoint) of ``resume=PATH``: the checkpoint's config with the
    command line's ``overrides`` (other than ``resume`` and Hydra's own) applied on top, before
    its interpolations are resolved (checkpoints older than ``config_unresolved``: after)."""
    try:
        state = load_checkpoint(resume)
    except ValueError as error:
        raise ValueError(f"resume: {error}") from None
    path = Path(resume)
    saved = OmegaConf.create(state.get("config_unresolved", state["config"]))
    for override in overrides:
        key = override.split("=", 1)[0].lstrip("+~")
        if key != "resume" and not key.startswith("hydra"):
            OmegaConf.update(saved, key, OmegaConf.select(cfg, key), force_add=True)
    return saved, path if path.is_dir() else path.parent, state


def train(cfg: DictConfig, run_dir: Path, state: dict | None) -> None:
    """Run ``cfg``'s trainer in ``run_dir`` (resumed from ``state``), recording to its ``.rrd``;
    print the result, or on Ctrl-C how to continue."""
    training = trainer_class(cfg.algo.trainer)(cfg, run_dir, state)
    if state is not None:
        print(f"resuming {run_dir} at {training.position()}")
    try:
        with RerunLogger.from_config(
            cfg.logger, run_dir, recording_id=training.recording_id
        ) as logger:
            training.recording_id = logger.recording_id
            if state is None:
                logger.log_hparams(cfg)
            metrics = training.run(logger, progress=cfg.progress)
    except KeyboardInterrupt:
        sys.exit(
            f"interrupted at {training.position()}: checkpoint in {run_dir / CHECKPOINT};"
            f" continue with: python scripts/train.py resume={run_dir}"
        )
    finally:
        training.close()
    print(training.summary(metrics))
    files = sorted(p.name for p in run_dir.iterdir() if p.suffix in (".pt", ".yaml", ".json"))
    print(f"-> {run_dir}: {', '.join(files)}, {logger.path.name}")
