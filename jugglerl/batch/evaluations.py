"""Periodic evaluation of a trained actor, and the choice of the actor a run deploys.

``Evaluations`` runs ``eval.seeds`` deterministic episodes of an actor from env seeds
``0..eval.seeds-1`` (the first recorded under ``eval/<frames>`` with ``eval.record``: ``true`` at
every evaluation, ``final`` at the run's last), and with ``eval.perturbed`` (name: env arguments)
``eval.perturbed_seeds`` episodes (or the condition's own ``seeds``) of ``eval.perturbed_duration``
s (or the condition's own ``duration``) under each of those conditions, from env seeds
``eval.perturbed_first_seed`` on: away from the seeds ``scripts/robustness.py`` measures on, so
that a run is not selected on its benchmark. All the episodes, the recorded one too, run as one
``JuggleBatch``, the actor acting on every env in one forward pass per step. It keeps every
evaluation's record, and with ``eval.keep_best`` the weights of the best one, which the run then
deploys instead of its last actor. An evaluation's score is the nominal episodes' catch rate (an
actor must catch the ball from the standard start), then throws, then time up, each averaged over
the nominal episodes and the perturbed conditions, a condition's throws and time scaled to the
nominal episode's length (a tie goes to the later one): an actor that juggles only the nominal
episode ranks below one that also juggles through noise and kicks. The run's final evaluation of a
kept best repeats that evaluation's record when it ran the same episodes (they are deterministic).
The off-policy and the on-policy trainers share it.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Sequence

import numpy as np
from omegaconf import DictConfig, OmegaConf

from jugglerl.batch.episodes import batch_policy, per_env_arguments, run_episodes
from jugglerl.config.envs import make_juggle_env
from jugglerl.policies.actor import ActorPolicy
from jugglerl.policies.episodes import SUMMARY_KEYS, EpisodeMetrics, summarise_episodes
from jugglerl.recording.blueprint import offpolicy_curves, training_blueprint
from jugglerl.recording.episode import BatchEnvRecorder
from jugglerl.recording.logger import RerunLogger
from jugglerl.recording.names import EVAL, join
from jugglerl_envs import JuggleBatch
from jugglerl_envs.validation import check_number


class Evaluations:
    """The evaluations of one run (``records``) and, with ``eval.keep_best``, the ``best``;
    ``curves`` gives the learning curves of the run's recording (``jugglerl.recording.blueprint``)
    from the perturbed conditions' names."""

    def __init__(
        self, cfg: DictConfig, curves: Callable[[Sequence[str]], tuple] = offpolicy_curves
    ):
        self.cfg = cfg
        self.conditions = perturbed_conditions(cfg)
        #: the learning curves of ``train.rrd`` (``curves`` of the perturbed conditions' names)
        self.curves = curves(list(self.conditions))
        self.records: list[dict] = []
        #: with ``eval.keep_best``: frames, score and weights of the best periodic evaluation
        self.best: dict | None = None

    def evaluate(
        self,
        policy: ActorPolicy,
        frames: int,
        logger: RerunLogger,
        duration: float,
        final: bool = False,
    ):
        """Deterministic episodes of ``policy`` of ``duration`` s, and the perturbed ones;
        returns their record. ``final``: the run's last evaluation, recorded with
        ``eval.record=final`` too; it repeats the record of the kept best (``policy``'s weights)
        when that evaluation ran the same episodes, instead of running them again."""
        if final and (kept := self._kept_record(duration)) is not None:
            record = {**copy.deepcopy(kept), "frames": frames}
            if self.cfg.eval.record is True:  # the episode was recorded at that evaluation
                root = join(EVAL, f"{kept['frames']:08d}")
                logger.send_blueprint(training_blueprint(self.curves, root, self.cfg.env.threshold))
            return self._keep(record, logger)
        check = self.cfg.eval
        plan = [(None, {"duration": duration}, seed) for seed in range(check.seeds)]
        first = check.perturbed_first_seed
        for name, condition in self.conditions.items():
            overrides = {"duration": check.perturbed_duration, **env_arguments(condition)}
            seeds = condition.get("seeds", check.perturbed_seeds)
            plan += [(name, overrides, first + k) for k in range(seeds)]
        root = None
        if check.record is True or (final and check.record == "final"):  # into the recording
            root = join(EVAL, f"{frames:08d}")
        episodes = self._episodes(policy, plan, logger, root)
        if root is not None:
            logger.send_blueprint(training_blueprint(self.curves, root, self.cfg.env.threshold))
        nominal = [m for (name, _, _), m in zip(plan, episodes, strict=True) if not name]
        summary = summarise_episodes(nominal, check.catch_time)
        record = {"frames": frames, "duration": duration, **summary}
        record["episodes"] = [episode.to_dict() for episode in nominal]
        if self.conditions:
            record["perturbed"] = {}
            for name, condition in self.conditions.items():
                runs = [m for (n, _, _), m in zip(plan, episodes, strict=True) if n == name]
                seconds = self._seconds(condition)
                perturbed = {"duration": seconds, **summarise_episodes(runs, check.catch_time)}
                record["perturbed"][name] = perturbed
        return self._keep(record, logger)

    def _keep(self, record: dict, logger: RerunLogger) -> dict:
        """Append ``record`` to ``records`` and log its summaries at its frames."""
        metrics = {join(EVAL, key): record[key] for key in SUMMARY_KEYS}
        for name, perturbed in record.get("perturbed", {}).items():
            metrics |= {join(EVAL, name, key): perturbed[key] for key in SUMMARY_KEYS}
        self.records.append(record)
        logger.log_metrics(metrics, record["frames"])
        return record

    def _kept_record(self, duration: float) -> dict | None:
        """The kept best's record if it ran the final evaluation's episodes (``duration`` s
        from the standard starts, the same perturbed ones) and, with ``eval.record=final``,
        recorded its episode; else ``None``."""
        if self.best is None or self.cfg.eval.record == "final":
            return None
        kept = next(r for r in self.records if r["frames"] == self.best["frames"])
        conditions = {name: self._seconds(c) for name, c in self.conditions.items()}
        ran = {name: p["duration"] for name, p in kept.get("perturbed", {}).items()}
        return kept if kept["duration"] == duration and ran == conditions else None

    def _seconds(self, condition) -> float:
        """How long a perturbed condition's episodes last: its own ``duration`` or
        ``eval.perturbed_duration``."""
        return float(condition.get("duration", self.cfg.eval.perturbed_duration))

    def _episodes(
        self, policy: ActorPolicy, plan: list[tuple], logger: RerunLogger, root: str | None
    ) -> list[EpisodeMetrics]:
        """The episodes of ``plan`` (condition, env arguments, seed), as one batch; with
        ``root``, the first recorded there."""
        base = OmegaConf.to_container(self.cfg.env, resolve=True)
        envs = [{**base, **overrides} for _, overrides, _ in plan]
        batch = JuggleBatch(len(plan), autoreset=False, **per_env_arguments(envs))
        recorder = None
        if root is not None:
            fps = self.cfg.logger.scene_fps
            recorder = BatchEnvRecorder(batch, 0, logger.recording, root, fps)
        try:
            policies = batch_policy(policy, len(plan))
            return run_episodes(batch, policies, [s for *_, s in plan], recorder)
        finally:
            if recorder is not None:
                recorder.track.end()
            batch.close()

    def keep_if_best(self, record: dict, actor) -> None:
        """With ``eval.keep_best``, keep ``actor``'s weights if ``record`` is the best so far."""
        if not self.cfg.eval.keep_best:
            return
        ranked = score(record)
        if self.best is None or ranked >= self.best["score"]:
            weights = copy.deepcopy(actor.state_dict())
            self.best = {"frames": record["frames"], "score": ranked, "policy": weights}

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


def check_evaluations(cfg: DictConfig) -> None:
    """``ValueError`` naming the ``eval`` or ``env`` keys of evaluations that cannot run."""
    if cfg.eval.seeds < 1 or cfg.eval.duration < cfg.eval.catch_time:
        raise ValueError(
            f"eval.seeds={cfg.eval.seeds} must be >= 1 and eval.duration={cfg.eval.duration}"
            f" at least eval.catch_time={cfg.eval.catch_time}"
        )
    if cfg.eval.record not in (True, False, "final"):
        raise ValueError(f"eval.record={cfg.eval.record}: true, false or final")
    check, conditions = cfg.eval, perturbed_conditions(cfg)
    if conditions and (check.perturbed_seeds < 1 or check.perturbed_duration <= 0):
        raise ValueError(
            f"eval.perturbed_seeds={check.perturbed_seeds} must be >= 1 and"
            f" eval.perturbed_duration={check.perturbed_duration} > 0"
        )
    make_juggle_env(cfg.env).close()  # the nominal env first: its keys blamed as env.KEY
    for name, condition in conditions.items():  # fail now, not at the first evaluation
        if "seeds" in condition:
            check_number(f"eval.perturbed.{name}.seeds", condition["seeds"], 1, integer=True)
        try:
            make_juggle_env(cfg.env, **env_arguments(condition)).close()
        except (ValueError, TypeError) as error:
            raise ValueError(f"eval.perturbed.{name}: {error}") from None


def perturbed_conditions(cfg: DictConfig) -> dict:
    """``eval.perturbed``: condition name -> env arguments (and, for evaluations, ``seeds``);
    none when the key is deleted (``~eval.perturbed``) or empty."""
    return dict(cfg.eval.get("perturbed") or {})


def env_arguments(condition) -> dict:
    """A perturbed condition's env arguments: all its keys but ``seeds``, the number of
    evaluation episodes under it (envs that train under the condition ignore that)."""
    return {key: value for key, value in condition.items() if key != "seeds"}


def score(record: dict) -> list[float]:
    """What ``keep_best`` ranks (compared as a list): the nominal catch rate, then throws and
    time up, each the mean over the nominal summary and every perturbed condition's, whose
    throws and time up count as in an episode of the nominal length (``record["duration"]``).
    The nominal catch rate comes first so that lucky perturbed draws cannot lift an actor that
    drops the ball from the standard start (an MLP run shipped 1 throw over a 46-throw actor)."""
    rows = [[record["mean_throws"], record["mean_time_to_drop"]]]
    for summary in record.get("perturbed", {}).values():
        stretch = record["duration"] / summary["duration"]
        rows.append([summary["mean_throws"] * stretch, summary["mean_time_to_drop"] * stretch])
    throws, time_up = np.mean(rows, axis=0)
    return [float(record["catch_rate"]), float(throws), float(time_up)]
