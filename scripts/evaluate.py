"""Evaluate a policy for one episode: ``metrics.json`` and ``episode.rrd`` in the run directory.

python scripts/evaluate.py policy=closed_loop            # a shipped policy (assets/policies/)
python scripts/evaluate.py policy=outputs/train/ddpg/<run>  # what a training run deploys
python scripts/evaluate.py policy=path/to/command.yaml env=earth seed=3 duration=60
python scripts/evaluate.py policy=expert hydra.run.dir=outputs/my_eval
rerun outputs/my_eval/episode.rrd      # watch it: 3D scene, ball height, throws
python scripts/evaluate.py policy=closed_loop video=true   # also episode.mp4, rendered headless
python scripts/evaluate.py policy=closed_loop seeds=30 env.action_noise=0.003  # and 29 more starts
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import hydra
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf

from jugglerl.batch.episodes import batch_policy, per_env_arguments, run_episodes
from jugglerl.config.command_line import check_override_types, exit_on_bad_command_line
from jugglerl.config.envs import make_juggle_env
from jugglerl.policies.episodes import EpisodeMetrics, summarise_episodes
from jugglerl.policies.loading import load_named_policy
from jugglerl.recording.blueprint import episode_blueprint
from jugglerl.recording.episode import record_episode
from jugglerl.recording.logger import RerunLogger
from jugglerl.recording.names import SUMMARY
from jugglerl.recording.video import VideoOptionError, VideoRecorder, render_options
from jugglerl.runs.files import exits_on_run_file_errors, write_json
from jugglerl_envs import JuggleBatch
from jugglerl_envs.validation import check_number


@hydra.main(version_base="1.3", config_path="../configs", config_name="evaluate")
@exits_on_run_file_errors
def main(cfg: DictConfig) -> None:
    run_dir = Path(HydraConfig.get().runtime.output_dir)
    try:
        check_override_types()
        check_number("seeds", cfg.seeds, 1, 100000, integer=True)
        env = make_juggle_env(cfg.env, duration=cfg.duration)
        cfg.env.duration = env.unwrapped.duration  # the recorded config: the episode's length
        policy = load_named_policy("policy", cfg.policy, env)
        if cfg.video:
            env = VideoRecorder(env, run_dir / str(cfg.render.file), **render_options(cfg.render))
    except VideoOptionError as error:
        sys.exit(f"error: render.{error}")
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

    results = metrics.to_dict()
    if cfg.seeds > 1:
        try:
            further = more_starts(cfg, policy)
        except KeyboardInterrupt:
            sys.exit(f"interrupted: the first episode is in {logger.path}")
        episodes = [metrics, *further]
        results["starts"] = {
            "seeds": [episode.seed for episode in episodes],
            **summarise_episodes(episodes, catch_time=0.0),
            "throws": [episode.throws for episode in episodes],
        }
    write_json(run_dir / "metrics.json", results)
    print(json.dumps(results, indent=2))
    video = f", {env.path} ({env.frames} frames)" if cfg.video else ""
    starts = ""
    if cfg.seeds > 1:
        summary = results["starts"]
        starts = f"; {summary['mean_throws']:.1f} throws on average over {cfg.seeds} starts"
    print(
        f"policy {cfg.policy}: {metrics.throws} throws in {metrics.duration:g} s{starts}"
        f" -> {run_dir / 'metrics.json'}, {logger.path}{video}"
    )


def more_starts(cfg: DictConfig, policy) -> list[EpisodeMetrics]:
    """The episodes from seeds ``seed + 1`` to ``seed + seeds - 1``, as one batch."""
    seeds = [int(cfg.seed) + k for k in range(1, cfg.seeds)]
    env = {**OmegaConf.to_container(cfg.env, resolve=True), "duration": cfg.env.duration}
    batch = JuggleBatch(len(seeds), autoreset=False, **per_env_arguments([env] * len(seeds)))
    episodes = run_episodes(batch, batch_policy(policy, len(seeds)), seeds)
    batch.close()
    return episodes


if __name__ == "__main__":
    exit_on_bad_command_line("evaluate")
    main()
