"""The search loop (``trainer: search``): collect a batch, update the distribution, keep the best,
log, checkpoint.

``SearchTraining`` is built from the Hydra config (``configs/train.yaml`` with ``algo=dps`` or
``algo=feedback``) and a run directory; the search space is ``algo.space``
(``jugglerl.dps.spaces``), the update rule ``algo.update`` (``jugglerl.dps.updates``). It writes

- ``checkpoint.pt`` after every episode (atomically): collector state (distribution, RNG,
  counters), update-rule state, best θ, history, the config and the logger's recording id;
- the best θ as a policy file whenever the best improves (``best_command.yaml`` or
  ``best_policy.yaml``), and with ``algo.deploy=mean`` the search distribution's mean θ after
  every episode (``mean_command.yaml`` or ``mean_policy.yaml``); the run deploys the one
  ``algo.deploy`` names (``scripts/evaluate.py policy=<run dir>`` replays it). The best is the
  luckiest roll-out of the search; when every roll-out is noisy (action noise among
  ``algo.conditions``), the mean, which every batch moved, is the steadier policy;
- ``metrics.json``: the best θ's score, roll-outs to reach given throw counts, the history per
  episode and, at the end, the deployed θ under reset noise.

Metrics go to the rerun logger under ``dps/`` on the ``step`` timeline (roll-outs so far); each
time the best improves its episode is replayed in the env and recorded under ``best/<roll-outs>``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
from omegaconf import DictConfig
from tqdm import tqdm

from jugglerl.dps.collector import DPSCollector
from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.spaces import SPACES
from jugglerl.dps.updates import make_update
from jugglerl.recording.blueprint import SEARCH_CURVES, training_blueprint
from jugglerl.recording.episode import record_episode
from jugglerl.recording.logger import RerunLogger
from jugglerl.recording.names import DPS, join
from jugglerl.runs.checkpoints import CHECKPOINT, config_entries, save_checkpoint
from jugglerl.runs.files import METRICS, write_json

#: What a run may deploy (``algo.deploy``): its best roll-out's θ or the distribution's mean.
DEPLOYS = ("best", "mean")
#: Throw counts whose first roll-out is reported: the paper's DPS best, and this project's bar.
MILESTONES = (39, 60)


@dataclass
class Best:
    """The best roll-out so far: its θ, throws, reset seed and when it was found (roll-outs)."""

    params: torch.Tensor
    throws: int = -1
    seed: int = 0
    rollout: int = 0
    time_to_drop: float = math.nan


class SearchTraining:
    """One search run; ``run()`` searches to ``algo.episodes``. Pass the ``state`` of
    ``load_checkpoint(path)`` to resume."""

    def __init__(self, cfg: DictConfig, run_dir: str | Path, state: dict | None = None):
        self.cfg = cfg
        self.run_dir = Path(run_dir)
        algo = cfg.algo
        if algo.episodes < 1 or algo.rollouts < 1:
            raise ValueError("algo.episodes and algo.rollouts must be >= 1")
        if algo.deploy not in DEPLOYS:
            raise ValueError(f"algo.deploy={algo.deploy!r}: use {' or '.join(DEPLOYS)}")
        self.space = SPACES.get(algo.space)(cfg)
        self.update = make_update(algo, self.space.stds)
        self.collector = DPSCollector(
            self.space,
            self.space.rollouts(),
            SearchDistribution.diagonal(self.space.start, self.space.stds),
            frames_per_batch=algo.rollouts,
            total_frames=algo.episodes * algo.rollouts,
            seed=cfg.seed,
            common_seeds=algo.common_seeds,
        )
        self.best = Best(self.space.start)
        self.history: list[dict] = []  # one record per episode
        self.recording_id: str | None = None
        self.deploys: str | None = None  # the policy file algo.deploy names, once written
        if state is not None:
            self.load_state_dict(state)

    # --- the loop -------------------------------------------------------------------------
    def run(self, logger: RerunLogger, progress: bool = True) -> dict:
        """Search until the roll-out budget is spent; returns the final metrics."""
        self.run_dir.mkdir(parents=True, exist_ok=True)
        logger.send_blueprint(training_blueprint(SEARCH_CURVES))
        bar = tqdm(
            total=self.cfg.algo.episodes,
            initial=self.collector.iteration,
            desc=self.cfg.algo.name.upper(),
            unit="episode",
            disable=not progress,
        )
        with bar:
            for batch in self.collector:
                improved = self._learn(batch)
                self._log(logger, self.history[-1])
                if improved:
                    best = self.space.save(self.best.params, self.run_dir, self.best_name)
                    if self.cfg.algo.deploy == "best":
                        self.deploys = best
                    self._record_best(logger)
                if self.cfg.algo.deploy == "mean":
                    name = f"{self.cfg.algo.name}_mean_{self.collector.iteration}"
                    self.deploys = self.space.save(self.deployed, self.run_dir, name, "mean")
                save_checkpoint(self.state_dict(), self.run_dir / CHECKPOINT)
                bar.set_postfix(best=self.best.throws, mean=f"{batch['return'].mean():.1f}")
                bar.update()
        metrics = self.final_metrics()
        write_json(self.run_dir / METRICS, metrics)
        return metrics

    def _learn(self, batch) -> bool:
        """Update the distribution from ``batch``; keep the best roll-out. True if it improved."""
        distribution = self.update(self.collector.distribution, batch["params"], batch["return"])
        self.collector.update_policy_weights_(distribution.to_tensordict())
        first = self.collector.frames - len(batch)
        index = int(torch.argmax(batch["throws"]))
        improved = int(batch["throws"][index]) > self.best.throws
        if improved:
            self.best = Best(
                params=batch["params"][index].clone(),
                throws=int(batch["throws"][index]),
                seed=int(batch["seed"][index]),
                rollout=first + index + 1,
                time_to_drop=float(batch["time_to_drop"][index]),
            )
        self.history.append(
            {
                "episode": self.collector.iteration,
                "rollouts": self.collector.frames,
                "best_throws": self.best.throws,
                "max_throws": int(batch["throws"].max()),
                "mean_throws": float(batch["return"].mean()),
                "dropped_fraction": float(torch.isfinite(batch["time_to_drop"]).double().mean()),
                **self.space.record(distribution),
                "first_rollout_with": {
                    str(n): first + int(torch.nonzero(batch["throws"] >= n)[0]) + 1
                    for n in MILESTONES
                    if bool(torch.any(batch["throws"] >= n))
                },
            }
        )
        return improved

    def _log(self, logger: RerunLogger, record: dict) -> None:
        """The episode's record as ``dps/<key>`` scalars at step = roll-outs so far."""
        counters = ("episode", "rollouts")
        scalars = {
            join(DPS, key): value
            for key, value in record.items()
            if key not in counters and isinstance(value, (int, float))
        }
        logger.log_metrics(scalars, record["rollouts"])

    def _record_best(self, logger: RerunLogger) -> None:
        """Replay the new best θ in the search env and record it under ``best/<roll-outs>``."""
        if not self.cfg.record_best:
            return
        root = join("best", f"{self.best.rollout:05d}")
        env = self.space.search_env()
        policy = self.space.policy(self.best.params, env)
        fps = self.cfg.logger.scene_fps
        record_episode(env, policy, logger.recording, root, self.best.seed, fps)
        logger.send_blueprint(training_blueprint(SEARCH_CURVES, root, self.cfg.env.threshold))

    @property
    def deployed(self) -> torch.Tensor:
        """θ of the policy ``algo.deploy`` names: the best roll-out's or the (projected) mean."""
        if self.cfg.algo.deploy == "best":
            return self.best.params
        return self.space.project(self.collector.distribution.mean)

    @property
    def best_name(self) -> str:
        return f"{self.cfg.algo.name}_best_{self.best.throws}"

    def position(self) -> str:
        """How far the run has got, for messages."""
        return f"episode {self.collector.iteration}"

    def summary(self, metrics: dict) -> str:
        """One line on what the run reached."""
        check = metrics.get("noise_check")
        line = self.space.headline(metrics)
        if check:
            line += (
                f"; {metrics['deploys']} from the standard start: {check['nominal_throws']}; with"
                f" {check['reset_noise']} m start noise: {check['mean_throws']:.1f} on average"
                f" over {len(check['seeds'])} seeds ({check['fraction_of_best']:.0%})"
            )
        return line

    # --- results --------------------------------------------------------------------------
    def final_metrics(self) -> dict:
        """Best θ, milestones, history, and the deployed θ under reset noise."""
        reached = {}
        for record in self.history:
            for n, rollout in record["first_rollout_with"].items():
                reached.setdefault(n, rollout)
        drop = self.best.time_to_drop
        metrics = {
            "update": self.cfg.algo["update"],
            "seed": self.cfg.seed,
            "best_throws": self.best.throws,
            "best_found_at_rollout": self.best.rollout,
            "best_time_to_drop": None if math.isnan(drop) else drop,
            "rollouts": self.collector.frames,
            "deploys": self.deploys,
            "first_rollout_with": {n: reached.get(str(n)) for n in MILESTONES},
            **self.space.describe(self.best.params, self.best_name),
            "history": self.history,
        }
        if self.cfg.algo.noise_check.seeds > 0:
            metrics["noise_check"] = self.noise_check()
        return metrics

    def noise_check(self) -> dict:
        """The deployed θ's throws from ``noise_check.seeds`` starts with ball offset noise, and
        their fraction of its throws from the standard start."""
        check = self.cfg.algo.noise_check
        deployed = self.space.decode(self.deployed)
        seeds = list(range(check.seeds))
        with self.space.rollouts(check.reset_noise) as rollouts:
            throws = rollouts.evaluate([deployed] * len(seeds), seeds).throws
        # the standard start is replayed: the best score came from one roll-out's own start
        # (algo.reset_noise) or sums several conditions (algo=feedback)
        with self.space.rollouts(0.0) as rollouts:
            nominal = int(rollouts.evaluate([deployed], [0]).throws[0])
        return {
            "reset_noise": check.reset_noise,
            "seeds": seeds,
            "throws": throws.tolist(),
            "mean_throws": float(np.mean(throws)),
            "nominal_throws": nominal,
            "fraction_of_best": float(np.mean(throws) / max(nominal, 1)),
        }

    # --- checkpoints ----------------------------------------------------------------------
    def state_dict(self) -> dict:
        return {
            **config_entries(self.cfg),
            "deploys": self.deploys,
            "collector": self.collector.state_dict(),
            "update": self.update.state_dict(),
            "best": vars(self.best).copy(),
            "history": self.history,
            "recording_id": self.recording_id,
        }

    def load_state_dict(self, state: dict) -> None:
        self.collector.load_state_dict(state["collector"])
        self.update.load_state_dict(state["update"])
        self.best = Best(**state["best"])
        self.deploys = state["deploys"]
        self.history = list(state["history"])
        self.recording_id = state["recording_id"]

    def close(self) -> None:
        self.collector.shutdown()
