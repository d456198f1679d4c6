"""Periodic evaluation of the trained actor, and the choice of the actor a run deploys.

``Evaluations`` runs ``eval.seeds`` deterministic episodes of an actor from env seeds
``0..eval.seeds-1`` (the first recorded under ``eval/<frames>`` with ``eval.record``), keeps every
evaluation's record, and with ``eval.keep_best`` the weights of the best one (catch rate, then
throws, then time up; a tie goes to the later one), which the run then deploys instead of its
last actor.
"""

from __future__ import annotations

import copy

from omegaconf import DictConfig

from jugglerl.config import make_juggle_env
from jugglerl.evaluation import run_episode, summarise_episodes
from jugglerl.policies.actor import ActorPolicy
from jugglerl.recording.blueprint import OFFPOLICY_CURVES, training_blueprint
from jugglerl.recording.episode import record_episode
from jugglerl.recording.logger import RerunLogger
from jugglerl.recording.names import EVAL, join


class Evaluations:
    """The evaluations of one run (``records``) and, with ``eval.keep_best``, the ``best``."""

    def __init__(self, cfg: DictConfig):
        self.cfg = cfg
        self.records: list[dict] = []
        #: with ``eval.keep_best``: frames, score and weights of the best periodic evaluation
        self.best: dict | None = None

    def evaluate(self, policy: ActorPolicy, frames: int, logger: RerunLogger, duration: float):
        """Deterministic episodes of ``policy`` of ``duration`` s; returns their record."""
        check = self.cfg.eval
        seeds = list(range(check.seeds))
        root = join(EVAL, f"{frames:08d}")
        env = make_juggle_env(self.cfg.env, duration=duration)
        episodes = []
        for seed in seeds:
            if check.record and not episodes:
                recorded = make_juggle_env(self.cfg.env, duration=duration)
                stream, fps = logger.recording, self.cfg.logger.scene_fps
                episodes.append(record_episode(recorded, policy, stream, root, seed, fps))
                blueprint = training_blueprint(OFFPOLICY_CURVES, root, self.cfg.env.threshold)
                logger.send_blueprint(blueprint)
            else:
                episodes.append(run_episode(env, policy, seed=seed))
        env.close()
        summary = summarise_episodes(episodes, check.catch_time)
        record = {"frames": frames, "duration": duration, **summary}
        record["episodes"] = [episode.to_dict() for episode in episodes]
        self.records.append(record)
        logger.log_metrics({join(EVAL, key): value for key, value in summary.items()}, frames)
        return record

    def keep_if_best(self, record: dict, actor) -> None:
        """With ``eval.keep_best``, keep ``actor``'s weights if ``record`` is the best so far."""
        if not self.cfg.eval.keep_best:
            return
        score = [record["catch_rate"], record["mean_throws"], record["mean_time_to_drop"]]
        if self.best is None or score >= self.best["score"]:
            weights = copy.deepcopy(actor.state_dict())
            self.best = {"frames": record["frames"], "score": score, "policy": weights}

    def deployed(self, actor):
        """``actor``, or with a kept best, a copy of it carrying the best weights."""
        if self.best is None:
            return actor
        best = copy.deepcopy(actor)
        best.load_state_dict(self.best["policy"])
        return best

    def state_dict(self) -> dict:
        return {"evaluations": self.records, "best": self.best}

    def load_state_dict(self, state: dict) -> None:
        self.records = list(state["evaluations"])
        self.best = state["best"]
