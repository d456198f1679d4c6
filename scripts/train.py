"""Train a juggling policy; everything lands in the run directory.

python scripts/train.py                                       # DDPG: MLP actor, expert noise
python scripts/train.py actor=lstm reward=contacts            # LSTM actor, the paper's reward 3
python scripts/train.py exploration=ou collector.total_frames=100000
python scripts/train.py algo=dps                              # eREPS from the expert, 500 roll-outs
python scripts/train.py algo=dps algo.update=greedy seed=1    # the paper's keep-best search
python scripts/train.py algo=feedback                         # closed loop: eREPS over its gains
python scripts/train.py resume=outputs/train/<algo>/<run>     # continue from its checkpoint
python scripts/evaluate.py policy=outputs/train/ddpg/<run>/checkpoint.pt
python scripts/evaluate.py policy=outputs/train/dps/<run>/best_command.yaml
rerun outputs/train/<algo>/<run>/train.rrd                    # learning curves, episodes
"""

from __future__ import annotations

import sys
from pathlib import Path

import hydra
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf

from jugglerl.checkpoints import CHECKPOINT, load_checkpoint
from jugglerl.config_types import check_override_types
from jugglerl.recording.logger import RerunLogger

ALGOS = ("ddpg", "dps", "feedback")


def resumed_config(cfg: DictConfig, state: dict) -> DictConfig:
    """The checkpoint's config with this command line's overrides (other than ``resume``)."""
    saved = OmegaConf.create(state["config"])
    for override in HydraConfig.get().overrides.task:
        key = override.split("=", 1)[0].lstrip("+~")
        if key != "resume" and not key.startswith("hydra"):
            OmegaConf.update(saved, key, OmegaConf.select(cfg, key), force_add=True)
    return saved


def make_training(cfg: DictConfig, run_dir: Path, state: dict | None):
    """The training loop of ``cfg.algo.name``, restored from ``state`` when resuming."""
    if cfg.algo.name in ("dps", "feedback"):
        from jugglerl.dps.training import DPSTraining
        from jugglerl.feedback_training import FeedbackTraining

        search = DPSTraining if cfg.algo.name == "dps" else FeedbackTraining
        training = search(cfg, run_dir)
        if state is not None:
            training.load_state_dict(state)
        return training
    if cfg.algo.name == "ddpg":
        from jugglerl.ddpg.training import DDPGTraining

        return DDPGTraining(cfg, run_dir, state)
    raise ValueError(f"algo={cfg.algo.name} is not available; choose one of {', '.join(ALGOS)}")


def train(cfg: DictConfig, run_dir: Path, state: dict | None) -> None:
    training = make_training(cfg, run_dir, state)
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


@hydra.main(version_base="1.3", config_path="../configs", config_name="train")
def main(cfg: DictConfig) -> None:
    run_dir = Path(HydraConfig.get().runtime.output_dir)
    try:
        check_override_types()
        state = None
        if cfg.resume is not None:
            try:
                state = load_checkpoint(cfg.resume)
            except ValueError as error:
                raise ValueError(f"resume: {error}") from None
            resume = Path(cfg.resume)
            run_dir = resume if resume.is_dir() else resume.parent
            cfg = resumed_config(cfg, state)
        train(cfg, run_dir, state)
    except ValueError as error:
        sys.exit(f"error: {error}")


if __name__ == "__main__":
    main()
