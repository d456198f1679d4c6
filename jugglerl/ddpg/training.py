"""The DDPG training loop, read top to bottom: collect -> store -> update -> log -> evaluate.

``DDPGTraining`` is built from the Hydra config (``configs/train.yaml`` with ``algo=ddpg``, the
default) and a run directory, where it writes

- ``checkpoint.pt`` every ``checkpoint_every_frames``, at the end and on Ctrl-C (atomically):
  actor, critic and their targets, optimisers, the observation normalisation, the exploration
  state, RNG states, counters, history and config, and the deployed actor's weights
  (``policy``: what ``scripts/evaluate.py`` runs) (the replay buffer is not saved: a resumed
  run refills it);
- ``metrics.json`` at the end: the final evaluation over ``eval.seeds`` full-length episodes, the
  periodic evaluations and the per-batch history.

Metrics go to the rerun logger under ``train/`` (per collected batch) and ``eval/`` (each
evaluation) on the ``step`` timeline (env frames); with ``eval.record`` the first episode of
each evaluation is recorded under ``eval/<frames>``.
"""

from __future__ import annotations

import copy
import json
import time
from pathlib import Path

import numpy as np
import torch
from omegaconf import DictConfig, OmegaConf
from torchrl.collectors import Collector
from tqdm import tqdm

from jugglerl.checkpoints import CHECKPOINT, save_checkpoint
from jugglerl.config import action_mapping, make_juggle_env
from jugglerl.ddpg.actors import is_recurrent, lstm_primer, make_actor, make_critic
from jugglerl.ddpg.buffer import ReplayBuffer
from jugglerl.ddpg.env_stack import ACTION_SIZE, make_env, normalisation, observation_transforms
from jugglerl.ddpg.exploration import make_exploration
from jugglerl.ddpg.policy import ActorPolicy
from jugglerl.ddpg.update import DDPGUpdate
from jugglerl.evaluation import run_episode, summarise_episodes
from jugglerl.recording.blueprint import DDPG_CURVES, training_blueprint
from jugglerl.recording.episode import EpisodeRecorder
from jugglerl.recording.logger import RerunLogger
from jugglerl.recording.names import EVAL, TRAIN, join

METRICS = "metrics.json"


class DDPGTraining:
    """One DDPG run; ``run()`` trains to ``collector.total_frames``. Pass the ``state`` of
    ``load_checkpoint(path)`` to resume (it also supplies the observation normalisation)."""

    def __init__(self, cfg: DictConfig, run_dir: str | Path, state: dict | None = None):
        _check(cfg)
        self.cfg = cfg
        self.run_dir = Path(run_dir)
        torch.manual_seed(cfg.seed)
        norm = state["normalisation"] if state is not None else {"loc": None, "scale": None}
        self.env = make_env(cfg, cfg.collector.num_envs, norm["loc"], norm["scale"])
        observation_size = self.env.observation_spec["observation"].shape[-1]
        to_action = action_mapping(cfg.env)
        self.actor = make_actor(cfg.actor, observation_size, self.env.action_spec, to_action)
        primer = lstm_primer(self.actor)
        if primer is not None:
            self.env.append_transform(primer)
        critic = make_critic(cfg.critic, observation_size, ACTION_SIZE)
        self.policy, self.noise = make_exploration(
            cfg.exploration, self.actor, self.env.action_spec, to_action
        )
        self.recurrent = is_recurrent(self.actor)
        self.update = DDPGUpdate(self.actor, critic, cfg.algo, cfg.optim, self.recurrent)
        self.buffer = ReplayBuffer.from_config(cfg.replay_buffer, self.recurrent)
        self.frames = 0
        self.updates = 0
        self.wall_seconds = 0.0  # collecting, updating, evaluating; summed over resumed sessions
        self.history: list[dict] = []  # one record per collected batch
        self.evaluations: list[dict] = []
        #: with ``eval.keep_best``: frames, score and weights of the best periodic evaluation
        self.best: dict | None = None
        self.recording_id: str | None = None
        if state is not None:
            self.load_state_dict(state)

    # --- the loop -------------------------------------------------------------------------
    def run(self, logger: RerunLogger, progress: bool = True) -> dict:
        """Train until the frame budget is spent, evaluate in full; returns the final metrics.

        On Ctrl-C the checkpoint is brought up to date before ``KeyboardInterrupt`` propagates.
        """
        self.run_dir.mkdir(parents=True, exist_ok=True)
        logger.send_blueprint(training_blueprint(DDPG_CURVES))
        collect = self.cfg.collector
        bar = tqdm(
            total=collect.total_frames,
            initial=self.frames,
            desc=f"DDPG {self.cfg.actor.name}",
            unit="frame",
            disable=not progress,
        )
        started = time.monotonic()
        try:
            with bar:
                self._train(logger, bar)
        except KeyboardInterrupt:
            self.wall_seconds += time.monotonic() - started
            self.save()
            raise
        self.wall_seconds += time.monotonic() - started
        final = self.evaluate(logger, self.cfg.env.duration, self.deployed_actor())
        if self.best is not None:
            final["policy_frames"] = self.best["frames"]
        self.save()
        metrics = {
            "actor": self.cfg.actor.name,
            "exploration": self.cfg.exploration.name,
            "reward": self.cfg.env.reward,
            "seed": self.cfg.seed,
            "wall_seconds": round(self.wall_seconds, 1),
            "frames": self.frames,
            "updates": self.updates,
            "final_evaluation": final,
            "evaluations": self.evaluations,
            "history": self.history,
        }
        (self.run_dir / METRICS).write_text(json.dumps(metrics, indent=2) + "\n")
        return metrics

    def _train(self, logger: RerunLogger, bar: tqdm) -> None:
        collect = self.cfg.collector
        remaining = collect.total_frames - self.frames
        if remaining <= 0:
            return
        self.env.set_seed(self.cfg.seed + self.frames)  # a resumed run meets new episodes
        collector = Collector(
            self.env,
            self.policy,
            frames_per_batch=collect.frames_per_batch,
            total_frames=remaining,
            init_random_frames=max(0, collect.init_random_frames - self.frames),
        )
        try:
            for batch in collector:
                self.buffer.extend(batch)
                self.frames += batch.numel()
                self.noise.step(batch.numel())
                record = self._learn() | self._episode_stats(batch)
                self.history.append(record)
                logger.log_metrics({join(TRAIN, k): v for k, v in record.items()}, self.frames)
                bar.set_postfix(
                    {k: f"{record[k]:.3g}" for k in ("return", "throws") if k in record}
                )
                bar.update(batch.numel())
                if _crossed(self.frames, batch.numel(), self.cfg.eval.every_frames):
                    self._keep_if_best(self.evaluate(logger, self.cfg.eval.duration))
                if _crossed(self.frames, batch.numel(), self.cfg.checkpoint_every_frames):
                    self.save()
        finally:
            collector.shutdown(close_env=False)

    def _learn(self) -> dict:
        """``optim.updates_per_batch`` updates once the buffer holds a batch; mean losses."""
        ready = (
            self.frames >= self.cfg.collector.init_random_frames
            and len(self.buffer) >= self.cfg.replay_buffer.batch_size
        )
        if not ready:
            return {}
        losses = [
            self.update(self.buffer.sample()) for _ in range(self.cfg.optim.updates_per_batch)
        ]
        self.updates += len(losses)
        return {key: float(np.mean([loss[key] for loss in losses])) for key in losses[0]}

    def _episode_stats(self, batch) -> dict:
        """Mean reward per step, and the return, throws, catches and length of finished episodes."""
        stats = {"frames": self.frames, "reward": float(batch["next", "reward"].mean())}
        done = batch["next", "done"].squeeze(-1)
        if done.any():
            finished = batch["next"][done]
            stats["return"] = float(finished["episode_reward"].mean())
            stats["throws"] = float(finished["throws"].double().mean())
            stats["catches"] = float(finished["catches"].double().mean())
            stats["episode_seconds"] = float(finished["time"].double().mean())
        return stats

    def position(self) -> str:
        """How far the run has got, for messages."""
        return f"frame {self.frames}"

    def summary(self, metrics: dict) -> str:
        """One line on what the run reached."""
        final = metrics["final_evaluation"]
        return (
            f"DDPG ({self.cfg.actor.name} actor, {self.cfg.exploration.name} exploration,"
            f" reward {self.cfg.env.reward}) after {metrics['frames']} frames: catch rate"
            f" {final['catch_rate']:.0%}, {final['mean_throws']:.1f} throws, ball up"
            f" {final['mean_time_to_drop']:.1f} s on average over {len(final['episodes'])}"
            f" episodes of {final['duration']:g} s"
        )

    # --- evaluation -----------------------------------------------------------------------
    def current_actor(self):
        """The actor as trained so far: the target (Polyak-averaged) actor with
        ``eval.target_actor``, else the online one. The online actor can swing between
        updates; its average moves by ``algo.tau`` per update and holds on to what worked."""
        return self.update.target_actor() if self.cfg.eval.target_actor else self.actor

    def deployed_actor(self):
        """The actor the final evaluation, the checkpoint's ``policy`` and ``evaluate.py`` run:
        with ``eval.keep_best``, the one of the best periodic evaluation; else the current one."""
        actor = self.current_actor()
        if self.best is None:
            return actor
        best = copy.deepcopy(actor)
        best.load_state_dict(self.best["policy"])
        return best

    def _keep_if_best(self, record: dict) -> None:
        """With ``eval.keep_best``, keep the current actor if this evaluation is the best so far
        (catch rate, then throws, then time up; a tie goes to the later one)."""
        if not self.cfg.eval.keep_best:
            return
        score = [record["catch_rate"], record["mean_throws"], record["mean_time_to_drop"]]
        if self.best is None or score >= self.best["score"]:
            weights = copy.deepcopy(self.current_actor().state_dict())
            self.best = {"frames": self.frames, "score": score, "policy": weights}

    def actor_policy(self, actor) -> ActorPolicy:
        """``actor`` as a deterministic ``Policy`` on plain Gymnasium envs."""
        norm = normalisation(self.env)
        transforms = observation_transforms(
            self.cfg.state, self.cfg.env.duration, norm.loc.clone(), norm.scale.clone()
        )
        return ActorPolicy(actor, transforms)

    def evaluate(self, logger: RerunLogger, duration: float, actor=None) -> dict:
        """Deterministic episodes of ``actor`` (default: the current one) of ``duration`` s from
        env seeds ``0..eval.seeds-1``; with ``eval.record`` the first is recorded under
        ``eval/<frames>``."""
        check = self.cfg.eval
        policy = self.actor_policy(actor if actor is not None else self.current_actor())
        seeds = list(range(check.seeds))
        envs = [make_juggle_env(self.cfg.env, duration=duration)] * len(seeds)
        root = join(EVAL, f"{self.frames:08d}")
        if check.record:
            envs[0] = EpisodeRecorder(
                make_juggle_env(self.cfg.env, duration=duration),
                logger.recording,
                root,
                self.cfg.logger.scene_fps,
            )
        episodes = [
            run_episode(env, policy, seed=seed) for env, seed in zip(envs, seeds, strict=True)
        ]
        if check.record:
            envs[0].close()  # sends the recorded episode
            logger.send_blueprint(training_blueprint(DDPG_CURVES, root, self.cfg.env.threshold))
        summary = summarise_episodes(episodes, check.catch_time)
        record = {"frames": self.frames, "duration": duration, **summary}
        record["episodes"] = [episode.to_dict() for episode in episodes]
        self.evaluations.append(record)
        logger.log_metrics({join(EVAL, key): value for key, value in summary.items()}, self.frames)
        return record

    # --- checkpoints ----------------------------------------------------------------------
    def state_dict(self) -> dict:
        norm = normalisation(self.env)
        return {
            "config": OmegaConf.to_container(self.cfg, resolve=True),
            "actor": self.actor.state_dict(),
            "policy": self.deployed_actor().state_dict(),
            "update": self.update.state_dict(),
            "normalisation": {"loc": norm.loc.clone(), "scale": norm.scale.clone()},
            "exploration": self.noise.state_dict(),
            "rng": {"torch": torch.get_rng_state(), "numpy": np.random.get_state()},
            "counters": {
                "frames": self.frames,
                "updates": self.updates,
                "wall_seconds": self.wall_seconds,
            },
            "history": self.history,
            "evaluations": self.evaluations,
            "best": self.best,
            "recording_id": self.recording_id,
        }

    def load_state_dict(self, state: dict) -> None:
        self.actor.load_state_dict(state["actor"])
        self.update.load_state_dict(state["update"])
        self.noise.load_state_dict(state["exploration"])
        torch.set_rng_state(state["rng"]["torch"])
        np.random.set_state(state["rng"]["numpy"])
        self.frames = state["counters"]["frames"]
        self.updates = state["counters"]["updates"]
        self.wall_seconds = state["counters"]["wall_seconds"]
        self.history = list(state["history"])
        self.evaluations = list(state["evaluations"])
        self.best = state.get("best")  # absent in checkpoints written before eval.keep_best
        self.recording_id = state["recording_id"]

    def save(self) -> None:
        save_checkpoint(self.state_dict(), self.run_dir / CHECKPOINT)

    def close(self) -> None:
        self.env.close()


def _crossed(frames: int, batch: int, every: int) -> bool:
    """True when the last ``batch`` frames passed a multiple of ``every``."""
    return every > 0 and frames // every > (frames - batch) // every


def _check(cfg: DictConfig) -> None:
    """Clear errors for budget settings that cannot work together."""
    collect = cfg.collector
    if collect.frames_per_batch < collect.num_envs or collect.frames_per_batch % collect.num_envs:
        raise ValueError(
            f"collector.frames_per_batch={collect.frames_per_batch} must be a multiple of"
            f" collector.num_envs={collect.num_envs}"
        )
    if collect.total_frames < collect.frames_per_batch:
        raise ValueError(
            f"collector.total_frames={collect.total_frames} must be at least"
            f" collector.frames_per_batch={collect.frames_per_batch}"
        )
    if cfg.eval.seeds < 1 or cfg.eval.duration < cfg.eval.catch_time:
        raise ValueError(
            f"eval.seeds={cfg.eval.seeds} must be >= 1 and eval.duration={cfg.eval.duration}"
            f" at least eval.catch_time={cfg.eval.catch_time}"
        )
