"""The DPS training loop: collect a batch, update the distribution, keep the best, log, checkpoint.

``DPSTraining`` is built from the Hydra config (``configs/train.yaml`` with ``algo=dps``) and a run
directory, where it writes

- ``checkpoint.pt`` after every episode (atomically): collector state (distribution, RNG,
  counters), update-rule state, best command, history, the config and the logger's recording id;
- ``best_command.yaml`` whenever the best improves (replay it with
  ``scripts/evaluate.py policy=<run dir>/best_command.yaml``);
- ``metrics.json``: the best command's score, roll-outs to reach given throw counts, the history
  per episode and, at the end, the best command under reset noise.

Metrics go to the rerun logger under ``dps/`` on the ``step`` timeline (roll-outs so far); each
time the best improves its episode is replayed in the env and recorded under
``best/<roll-outs>``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch
from omegaconf import DictConfig, OmegaConf
from tqdm import tqdm

from jugglerl.checkpoints import CHECKPOINT, save_checkpoint
from jugglerl.commands import ViaPointCommand, load_command, save_command
from jugglerl.config import make_juggle_env
from jugglerl.dps.collector import DPSCollector
from jugglerl.dps.distribution import SearchDistribution
from jugglerl.dps.params import (
    ViaPointConstraints,
    command_to_params,
    component_stds,
    params_to_command,
)
from jugglerl.dps.rollouts import CommandRollouts
from jugglerl.dps.updates import UpdateRule, make_update
from jugglerl.evaluation import CommandPolicy, run_episode
from jugglerl.recording.blueprint import SEARCH_CURVES, training_blueprint
from jugglerl.recording.episode import EpisodeRecorder
from jugglerl.recording.logger import RerunLogger
from jugglerl.recording.names import DPS, join
from jugglerl_envs.juggle import MAX_RESET_NOISE
from jugglerl_envs.validation import check_number

BEST_COMMAND = "best_command.yaml"
METRICS = "metrics.json"
#: Throw counts whose first roll-out is reported: the paper's DPS best, and this project's bar.
MILESTONES = (39, 60)


@dataclass
class BestCommand:
    """The best roll-out so far: its θ, throws, reset seed and when it was found (roll-outs)."""

    params: torch.Tensor
    throws: int = -1
    seed: int = 0
    rollout: int = 0
    time_to_drop: float = math.nan


class DPSTraining:
    """One DPS run. ``run()`` trains to ``algo.episodes``; to resume, ``load_state_dict`` the
    state of ``load_checkpoint(path)`` first."""

    def __init__(self, cfg: DictConfig, run_dir: str | Path):
        self.cfg = cfg
        self.run_dir = Path(run_dir)
        algo = cfg.algo
        if algo.episodes < 1 or algo.rollouts < 1:
            raise ValueError("algo.episodes and algo.rollouts must be >= 1")
        if algo["update"] == "elite" and not 2 <= algo.elite <= algo.rollouts:
            raise ValueError(
                f"algo.elite={algo.elite} must be in [2, algo.rollouts={algo.rollouts}]"
            )
        self.env = self._search_env()
        start_params, stds, self.constraints, rollouts, decode = self._search_space()
        self.update: UpdateRule = make_update(
            algo["update"],  # item access: DictConfig.update is a method
            stds,
            elite=algo.elite,
            epsilon=algo.epsilon,
            min_std_scale=algo.min_std_scale,
        )
        self.collector = DPSCollector(
            rollouts,
            SearchDistribution.diagonal(start_params, stds),
            self.constraints,
            frames_per_batch=algo.rollouts,
            total_frames=algo.episodes * algo.rollouts,
            seed=cfg.seed,
            decode=decode,
        )
        self.best = BestCommand(start_params)
        self.history: list[dict] = []  # one record per episode
        self.recording_id: str | None = None

    def _search_env(self) -> gym.Env:
        """The env of the search's roll-outs: ``env`` with the ball's start offset
        ``algo.reset_noise`` (each roll-out draws its own), so that the best command is one that
        also juggles from imperfect starts. Without the key (``algo=feedback``, runs checkpointed
        before it existed), ``env.reset_noise``."""
        reset_noise = self.cfg.algo.get("reset_noise")
        if reset_noise is not None:
            check_number("algo.reset_noise", reset_noise, 0.0, MAX_RESET_NOISE)
        return make_juggle_env(self.cfg.env, reset_noise=reset_noise)

    def _search_space(self):
        """What is searched: the start θ, its stds, the constraints, the roll-outs and how a θ
        becomes what they evaluate (None: ``params_to_command``). Here: via-point commands from
        ``algo.start``, with its pan and the lead-in ``algo.lead_in``, rolled out open loop in C."""
        algo = self.cfg.algo
        start = load_command(algo.start)
        lead_in = algo.get("lead_in", 0.0)  # runs checkpointed before lead-ins had none
        if not lead_in >= 0:
            raise ValueError(f"algo.lead_in={lead_in} must be a number of seconds >= 0")
        self.pan, self.lead_in = start.pan, float(lead_in)
        constraints = ViaPointConstraints.from_model(
            self.env.unwrapped.model, algo.min_cycle, algo.max_cycle, algo.min_gap
        )
        start_params = command_to_params(start)
        constraints.check(len(start.via_points))
        problems = constraints.violations(start_params)
        if problems:
            raise ValueError(
                f"algo.start={algo.start}: outside the constraints: {'; '.join(problems)}"
            )
        stds = component_stds(len(start.via_points), dict(algo.std))
        rollouts = CommandRollouts(self.env, algo.threads)
        return start_params, stds, constraints, rollouts, self.command_of

    # --- the loop -------------------------------------------------------------------------
    def run(self, logger: RerunLogger, progress: bool = True) -> dict:
        """Train until the roll-out budget is spent; returns the final metrics."""
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
                    self.save_best()
                    self._record_best(logger)
                self.save(self.run_dir / CHECKPOINT)
                bar.set_postfix(best=self.best.throws, mean=f"{batch['return'].mean():.1f}")
                bar.update()
        metrics = self.final_metrics()
        (self.run_dir / METRICS).write_text(_json(metrics))
        return metrics

    def _learn(self, batch) -> bool:
        """Update the distribution from ``batch``; keep the best roll-out. True if it improved."""
        distribution = self.update(self.collector.distribution, batch["params"], batch["return"])
        self.collector.update_policy_weights_(distribution.to_tensordict())
        first = self.collector.frames - len(batch)
        index = int(torch.argmax(batch["throws"]))
        improved = int(batch["throws"][index]) > self.best.throws
        if improved:
            self.best.params = batch["params"][index].clone()
            self.best.throws = int(batch["throws"][index])
            self.best.seed = int(batch["seed"][index])
            self.best.rollout = first + index + 1
            self.best.time_to_drop = float(batch["time_to_drop"][index])
        self.history.append(
            {
                "episode": self.collector.iteration,
                "rollouts": self.collector.frames,
                "best_throws": self.best.throws,
                "max_throws": int(batch["throws"].max()),
                "mean_throws": float(batch["return"].mean()),
                "dropped_fraction": float(torch.isfinite(batch["time_to_drop"]).double().mean()),
                **self._distribution_record(distribution),
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
        """Replay the new best command in the env and record it under ``best/<roll-outs>``."""
        if not self.cfg.record_best:
            return
        root = join("best", f"{self.best.rollout:05d}")
        recorder = EpisodeRecorder(
            self._search_env(), logger.recording, root, self.cfg.logger.scene_fps
        )
        run_episode(recorder, self.best_policy(recorder), seed=self.best.seed)
        recorder.close()
        logger.send_blueprint(training_blueprint(SEARCH_CURVES, root, self.cfg.env.threshold))

    def position(self) -> str:
        """How far the run has got, for messages."""
        return f"episode {self.collector.iteration}"

    def summary(self, metrics: dict) -> str:
        """One line on what the run reached."""
        check = metrics.get("noise_check")
        line = self._headline(metrics)
        if check:
            line += (
                f"; from the standard start: {check['nominal_throws']}; with"
                f" {check['reset_noise']} m start noise: {check['mean_throws']:.1f} on average"
                f" over {len(check['seeds'])} seeds ({check['fraction_of_best']:.0%})"
            )
        return line

    def _headline(self, metrics: dict) -> str:
        return (
            f"DPS ({self.cfg.algo['update']}): best {metrics['best_throws']} throws in"
            f" {self.cfg.env.duration:g} s after {metrics['rollouts']} roll-outs"
            f" (found at roll-out {metrics['best_found_at_rollout']})"
        )

    # --- results --------------------------------------------------------------------------
    def _distribution_record(self, distribution: SearchDistribution) -> dict[str, float]:
        """What the history keeps of the search distribution: its cycle's mean and std."""
        return {"mean_cycle": float(distribution.mean[0]), "std_cycle": float(distribution.stds[0])}

    def command_of(self, params: torch.Tensor, name: str = "dps") -> ViaPointCommand:
        """The via-point command of θ, with the parts that are not searched."""
        return params_to_command(params, self.pan, name, self.lead_in)

    def best_command(self) -> ViaPointCommand:
        return self.command_of(self.best.params, name=f"dps_best_{self.best.throws}")

    def best_policy(self, env) -> CommandPolicy:
        """The best θ as a policy playing in ``env``."""
        return CommandPolicy(self.best_command(), env)

    def save_best(self) -> None:
        """Write the best θ where ``scripts/evaluate.py policy=...`` can replay it."""
        save_command(self.best_command(), self.run_dir / BEST_COMMAND)

    def final_metrics(self) -> dict:
        """Best command, milestones, history, and the best command under reset noise."""
        reached = {}
        for record in self.history:
            for n, rollout in record["first_rollout_with"].items():
                reached.setdefault(n, rollout)
        metrics = {
            "update": self.cfg.algo["update"],
            "seed": self.cfg.seed,
            "best_throws": self.best.throws,
            "best_found_at_rollout": self.best.rollout,
            "best_time_to_drop": _finite_or_none(self.best.time_to_drop),
            "rollouts": self.collector.frames,
            "first_rollout_with": {n: reached.get(str(n)) for n in MILESTONES},
            **self._best_description(),
            "history": self.history,
        }
        if self.cfg.algo.noise_check.seeds > 0:
            metrics["noise_check"] = self.noise_check()
        return metrics

    def _best_description(self) -> dict:
        return {"best_command": self.best_command().to_dict()}

    def noise_check(self) -> dict:
        """The best θ's throws from ``noise_check.seeds`` starts with ball offset noise, and
        their fraction of its throws from the standard start."""
        check = self.cfg.algo.noise_check
        best = self.collector.decode(self.best.params)
        seeds = list(range(check.seeds))
        with self._rollouts_with_reset_noise(check.reset_noise) as rollouts:
            throws = rollouts.evaluate([best] * len(seeds), seeds).throws
        # the standard start is replayed: the best score came from one roll-out's own start
        # (algo.reset_noise) or sums several conditions (algo=feedback)
        with self._rollouts_with_reset_noise(0.0) as rollouts:
            nominal = int(rollouts.evaluate([best], [0]).throws[0])
        return {
            "reset_noise": check.reset_noise,
            "seeds": seeds,
            "throws": throws.tolist(),
            "mean_throws": float(np.mean(throws)),
            "nominal_throws": nominal,
            "fraction_of_best": float(np.mean(throws) / max(nominal, 1)),
        }

    def _rollouts_with_reset_noise(self, reset_noise: float) -> CommandRollouts:
        env = make_juggle_env(self.cfg.env, reset_noise=reset_noise)
        return CommandRollouts(env, nthread=self.cfg.algo.threads)

    # --- checkpoints ----------------------------------------------------------------------
    def state_dict(self) -> dict:
        return {
            "config": OmegaConf.to_container(self.cfg, resolve=True),
            "collector": self.collector.state_dict(),
            "update": self.update.state_dict(),
            "best": vars(self.best).copy(),
            "history": self.history,
            "recording_id": self.recording_id,
        }

    def load_state_dict(self, state: dict) -> None:
        self.collector.load_state_dict(state["collector"])
        self.update.load_state_dict(state["update"])
        self.best = BestCommand(**state["best"])
        self.history = list(state["history"])
        self.recording_id = state["recording_id"]

    def save(self, path: Path) -> None:
        save_checkpoint(self.state_dict(), path)

    def close(self) -> None:
        self.collector.shutdown()
        self.env.close()


def _json(data: dict) -> str:
    return json.dumps(data, indent=2) + "\n"


def _finite_or_none(value: float) -> float | None:
    return None if math.isnan(value) else value
