"""``ActorTraining``: what the trainers of a network (off- and on-policy) share around their loop.

A subclass trains in ``_train(logger, bar)`` to ``collector.total_frames`` and says which actor it
has trained so far (``current_actor``), how it names itself (``label``) and what its checkpoint
holds beyond ``common_state`` (``state_dict``, ``load_state_dict``); this base runs the loop with
its progress bar, saves on Ctrl-C, evaluates the deployed actor in full at the end
(``jugglerl.batch.evaluations``), writes ``metrics.json`` and keeps the wall time over resumed
sessions. It expects ``cfg``, ``run_dir``, ``env`` (the env stack), ``evaluations``,
``batch_stats``, ``frames``, ``updates``, ``wall_seconds``, ``seconds`` (``{}``: where the time
went, ``timed``), ``_session_start`` (``None`` unless ``run()`` trains), ``history`` and
``recording_id``.
"""

from __future__ import annotations

import copy
import time
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import torch
from omegaconf import DictConfig
from tqdm import tqdm

from jugglerl.batch.env_stack import normalisation
from jugglerl.policies.actor import ActorPolicy
from jugglerl.recording.blueprint import training_blueprint
from jugglerl.recording.logger import RerunLogger
from jugglerl.runs.checkpoints import CHECKPOINT, config_entries, save_checkpoint
from jugglerl.runs.files import METRICS, write_json
from jugglerl.runs.interrupts import deferred_interrupt


class ActorTraining:
    cfg: DictConfig

    def _train(self, logger: RerunLogger, bar: tqdm) -> None:
        raise NotImplementedError

    def current_actor(self):
        """The actor as trained so far."""
        raise NotImplementedError

    def label(self) -> str:
        """What trains what, for the summary line: ``PPO (residual actor, reward juggle)``."""
        raise NotImplementedError

    def state_dict(self) -> dict:
        raise NotImplementedError

    # --- the loop -------------------------------------------------------------------------
    def run(self, logger: RerunLogger, progress: bool = True) -> dict:
        """Train to the frame budget, evaluate in full, return the final metrics. On Ctrl-C the
        checkpoint is brought up to date before ``KeyboardInterrupt`` propagates."""
        self.run_dir.mkdir(parents=True, exist_ok=True)
        logger.send_blueprint(training_blueprint(self.evaluations.curves))
        bar = tqdm(
            total=self.frame_budget(), initial=self.frames, unit="frame", disable=not progress
        )
        self._session_start = time.monotonic()
        try:
            with bar:
                self._train(logger, bar)
        except KeyboardInterrupt:
            self.save()
            raise
        self.wall_seconds = self.wall_time()
        self._session_start = None
        final = self.evaluate(logger, self.cfg.env.duration, self.deployed_actor(), final=True)
        if self.evaluations.best is not None:
            final["policy_frames"] = self.evaluations.best["frames"]
        self.save()
        metrics = {
            "algo": self.cfg.algo.name,
            "actor": self.cfg.actor.name,
            **({"exploration": self.cfg.exploration.name} if "exploration" in self.cfg else {}),
            "reward": self.cfg.env.reward,
            "seed": self.cfg.seed,
            "wall_seconds": round(self.wall_seconds, 1),
            "seconds": {
                kind: {part: round(spent, 1) for part, spent in parts.items()}
                for kind, parts in self.seconds.items()
            },
            "frames": self.frames,
            "updates": self.updates,
            "final_evaluation": final,
            "evaluations": self.evaluations.records,
            "history": self.history,
        }
        write_json(self.run_dir / METRICS, metrics)
        return metrics

    @contextmanager
    def timed(self, part: str, kind: str = "parts") -> Iterator[None]:
        """Add the block's wall seconds to ``seconds[kind][part]`` (``parts``: collect, update,
        evaluate, checkpoint; ``stages``: the off-policy stages), kept in checkpoints and
        written to ``metrics.json``."""
        start = time.monotonic()
        try:
            yield
        finally:
            self.spent(part, start, kind)

    def spent(self, part: str, since: float, kind: str = "parts") -> None:
        """Add the wall seconds from ``since`` (``time.monotonic()``) to ``seconds[kind][part]``."""
        seconds = self.seconds.setdefault(kind, {})
        seconds[part] = seconds.get(part, 0.0) + time.monotonic() - since

    def frame_budget(self) -> int:
        """The frames the run trains for."""
        return self.cfg.collector.total_frames

    def position(self) -> str:
        return f"frame {self.frames}"

    def summary(self, metrics: dict) -> str:
        """One line on what the run reached."""
        final = metrics["final_evaluation"]
        return (
            f"{self.label()} after {metrics['frames']} frames: catch rate"
            f" {final['catch_rate']:.0%}, {final['mean_throws']:.1f} throws, ball up"
            f" {final['mean_time_to_drop']:.1f} s on average over {len(final['episodes'])}"
            f" episodes of {final['duration']:g} s"
        )

    def wall_time(self) -> float:
        """Seconds of training so far, this session's included."""
        running = 0.0 if self._session_start is None else time.monotonic() - self._session_start
        return self.wall_seconds + running

    # --- evaluation -----------------------------------------------------------------------
    def deployed_actor(self):
        """The actor the final evaluation, the checkpoint's ``policy`` and ``evaluate.py`` run:
        with ``eval.keep_best``, the one of the best periodic evaluation; else the current one."""
        return self.evaluations.deployed(self.current_actor())

    def actor_policy(self, actor) -> ActorPolicy:
        """``actor`` as a deterministic ``Policy`` on plain Gymnasium envs and batches."""
        norm = normalisation(self.env)
        return ActorPolicy.of_actor(
            actor, self.cfg.state, self.cfg.actor, self.cfg.env.duration, norm.loc, norm.scale
        )

    def evaluate(
        self, logger: RerunLogger, duration: float, actor=None, final: bool = False
    ) -> dict:
        """Deterministic episodes of ``actor`` (default: the current one) of ``duration`` s."""
        policy = self.actor_policy(actor if actor is not None else self.current_actor())
        with self.timed("final evaluation" if final else "evaluate"):
            return self.evaluations.evaluate(policy, self.frames, logger, duration, final)

    # --- checkpoints ----------------------------------------------------------------------
    def common_state(self) -> dict:
        """What every checkpoint of a trained actor holds: the config, the deployed actor
        (``policy``, which ``evaluate.py policy=RUN`` runs), the normalisation, RNG states,
        counters, wall time, the throw-rate window, history, evaluations and the recording."""
        norm = normalisation(self.env)
        return {
            **config_entries(self.cfg),
            "deploys": "actor",
            "policy": self.deployed_actor().state_dict(),
            "normalisation": {"loc": norm.loc.clone(), "scale": norm.scale.clone()},
            "rng": {"torch": torch.get_rng_state(), "numpy": np.random.get_state()},
            "counters": {
                "frames": self.frames,
                "updates": self.updates,
                "wall_seconds": self.wall_time(),
                "seconds": copy.deepcopy(self.seconds),
            },
            "batch_stats": self.batch_stats.state_dict(),
            "history": self.history,
            **self.evaluations.state_dict(),
            "recording_id": self.recording_id,
        }

    def load_common_state(self, state: dict) -> None:
        """Back to the ``common_state`` of a checkpoint (the normalisation is the env stack's,
        built from it)."""
        torch.set_rng_state(state["rng"]["torch"])
        np.random.set_state(state["rng"]["numpy"])
        self.frames = state["counters"]["frames"]
        self.updates = state["counters"]["updates"]
        self.wall_seconds = state["counters"]["wall_seconds"]
        self.seconds = copy.deepcopy(state["counters"].get("seconds", {}))
        self.history = list(state["history"])
        self.batch_stats.load_state_dict(state.get("batch_stats", {"recent": []}))
        self.evaluations.load_state_dict(state)
        self.recording_id = state["recording_id"]

    def save(self) -> None:
        """Write the checkpoint, a Ctrl-C during it held until it is written (``state_dict``
        syncs the memory-mapped replay buffers through tensordict, which an interrupt inside
        turns into another error: ``jugglerl.runs.interrupts``)."""
        with deferred_interrupt(), self.timed("checkpoint"):
            save_checkpoint(self.state_dict(), self.run_dir / CHECKPOINT)

    def close(self) -> None:
        self.env.close()
