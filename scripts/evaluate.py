"""Evaluate a policy for one episode: ``metrics.json`` and ``episode.rrd`` in the run directory.

python scripts/evaluate.py policy=closed_loop            # a shipped policy (assets/policies/)
python scripts/evaluate.py policy=outputs/train/ddpg/<run>  # what a training run deploys
python scripts/evaluate.py policy=path/to/command.yaml env=earth seed=3 duration=60
python scripts/evaluate.py policy=expert hydra.run.dir=outputs/my_eval
rerun outputs/my_eval/episode.rrd      # watch it: 3D scene, ball height, throws
python scripts/evaluate.py policy=closed_loop video=true   # also episode.mp4, rendered headless
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import hydra
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from jugglerl.config import make_juggle_env
from jugglerl.config_types import check_override_types
from jugglerl.policies.loading import load_policy
from jugglerl.recording.blueprint import episode_blueprint
from jugglerl.recording.episode import record_episode
from jugglerl.recording.logger import RerunLogger
from jugglerl.recording.names import SUMMARY
from jugglerl.recording.video import VideoRecorder, render_options
from jugglerl.run_files import write_json


@hydra.main(version_base="1.3", config_path="../configs", config_name="evaluate")
def main(cfg: DictConfig) -> None:
    run_dir = Path(HydraConfig.get().runtime.output_dir)
    try:
        check_override_types()
        env = make_juggle_env(cfg.env, duration=cfg.duration)
        cfg.env.duration = env.unwrapped.duration  # the recorded config: the episode's length
        policy = load_policy(str(cfg.policy), env)
        if cfg.video:
            env = VideoRecorder(env, run_dir / str(cfg.render.file), **render_options(cfg.render))
    except ValueError as error:
        sys.exit(f"error: {error}")

    with RerunLogger.from_config(cfg.logger, run_dir) as logger:
        logger.log_hparams(cfg)
        logger.send_blueprint(episode_blueprint(env.unwrapped.threshold))
        try:
            metrics = record_episode(
                env, policy, logger.recording, seed=int(cfg.seed), scene_fps=cfg.logger.scene_fps
            )
        except ValueError as error:
            sys.exit(f"error: logger.{error}")
        except KeyboardInterrupt:
            sys.exit(f"interrupted: the episode so far is in {logger.path}")
        logger.log_table(SUMMARY, metrics.scalars())

    write_json(run_dir / "metrics.json", metrics.to_dict())
    print(json.dumps(metrics.to_dict(), indent=2))
    video = f", {env.path} ({env.frames} frames)" if cfg.video else ""
    print(
        f"policy {cfg.policy}: {metrics.throws} throws in {metrics.duration:g} s"
        f" -> {run_dir / 'metrics.json'}, {logger.path}{video}"
    )


if __name__ == "__main__":
    main()
