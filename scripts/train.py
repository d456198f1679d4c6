"""Train a juggling policy; everything lands in the run directory.

python scripts/train.py algo=dps                              # eREPS from the expert, 500 roll-outs
python scripts/train.py algo=dps algo.update=greedy seed=1    # the paper's keep-best search
python scripts/train.py algo=dps env=earth                    # real gravity, UR5e speed limit
python scripts/train.py resume=outputs/train/dps/<run>        # continue from its checkpoint
python scripts/evaluate.py policy=outputs/train/dps/<run>/best_command.yaml
rerun outputs/train/dps/<run>/train.rrd                       # learning curves, best episodes
"""

from __future__ import annotations

import sys
from pathlib import Path

import hydra
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf

from jugglerl.dps.training import (
    BEST_COMMAND,
    CHECKPOINT,
    METRICS,
    DPSTraining,
    load_checkpoint,
)
from jugglerl.recording.logger import RerunLogger


def resumed_config(cfg: DictConfig, state: dict) -> DictConfig:
    """The checkpoint's config with this command line's overrides (other than ``resume``)."""
    saved = OmegaConf.create(state["config"])
    for override in HydraConfig.get().overrides.task:
        key = override.split("=", 1)[0].lstrip("+~")
        if key != "resume" and not key.startswith("hydra"):
            OmegaConf.update(saved, key, OmegaConf.select(cfg, key), force_add=True)
    return saved


def train_dps(cfg: DictConfig, run_dir: Path, state: dict | None) -> None:
    training = DPSTraining(cfg, run_dir)
    if state is not None:
        training.load_state_dict(state)
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
            f"interrupted after {training.collector.iteration} episodes: checkpoint in"
            f" {run_dir / CHECKPOINT}; continue with: python scripts/train.py resume={run_dir}"
        )
    finally:
        training.close()
    check = metrics.get("noise_check")
    print(
        f"DPS ({cfg.algo['update']}): best {metrics['best_throws']} throws in"
        f" {cfg.env.duration:g} s after {metrics['rollouts']} roll-outs"
        f" (found at roll-out {metrics['best_found_at_rollout']})"
        + (
            f"; with {check['reset_noise']} m start noise: {check['mean_throws']:.1f} on average"
            f" over {len(check['seeds'])} seeds"
            if check
            else ""
        )
    )
    print(f"-> {run_dir / BEST_COMMAND}, {run_dir / METRICS}, {logger.path}")


@hydra.main(version_base="1.3", config_path="../configs", config_name="train")
def main(cfg: DictConfig) -> None:
    run_dir = Path(HydraConfig.get().runtime.output_dir)
    try:
        state = None
        if cfg.resume is not None:
            state = load_checkpoint(cfg.resume)
            resume = Path(cfg.resume)
            run_dir = resume if resume.is_dir() else resume.parent
            cfg = resumed_config(cfg, state)
            print(f"resuming {run_dir} at episode {state['collector']['iteration']}")
        if cfg.algo.name != "dps":
            raise ValueError(f"algo={cfg.algo.name} is not available; choose dps")
        train_dps(cfg, run_dir, state)
    except ValueError as error:
        sys.exit(f"error: {error}")


if __name__ == "__main__":
    main()
