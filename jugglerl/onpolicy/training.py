"""The on-policy trainer (``trainer: onpolicy``, ``algo=ppo``), read top to bottom: collect a batch
from every env -> advantages -> clipped PPO updates -> log -> evaluate -> checkpoint.

``PPOTraining`` is built from the Hydra config (``configs/algo/ppo.yaml``) and a run directory.
The envs are one ``JuggleBatch`` (``collector.env=batch``) of ``collector.num_envs`` envs, each
under its own perturbation (``variants``), under the state transforms of ``jugglerl.state``; the
observation normalisation is fitted on the untrained policy's mean, i.e. the reference's own
roll-outs, and kept for the run. Each batch is ``collector.frames_per_batch / num_envs`` steps of
every env; the last step's state is carried to the next batch (``jugglerl.batch.collector``), so
episodes run across batches (a drop is ``terminated``, the time limit ``truncated``: GAE
bootstraps through it). The updates are ``jugglerl.onpolicy.update.PPOUpdate``: TorchRL's ``GAE``
(once per batch) and ``ClipPPOLoss`` (advantages normalised, an L2 critic) over ``algo.epochs``
passes of minibatches of ``algo.minibatch_size``.

It writes to the run directory

- ``checkpoint.pt`` every ``checkpoint_every_frames``, at the end and on Ctrl-C (atomically): the
  networks and optimiser, the normalisation, the batch of envs (physics, generators,
  perturbations, counts) and the carried state, RNG states, counters, wall time, history,
  evaluations, config and the deployed actor (``policy``: the mean of the best evaluated policy
  with ``eval.keep_best``): a resumed run repeats an uninterrupted one;
- ``metrics.json`` at the end: the final evaluation, the periodic ones and the per-batch history.

Metrics go to rerun under ``train/`` (per batch: throws, return, reward, σ, KL, clip fraction,
losses, frames/s) and ``eval/`` (each evaluation) on the ``step`` timeline (frames).
"""

from __future__ import annotations

import time
from pathlib import Path

import torch
from omegaconf import DictConfig
from tensordict import TensorDict
from tqdm import tqdm

from jugglerl.batch.actor_training import ActorTraining
from jugglerl.batch.batch_stats import BatchStats
from jugglerl.batch.collector import BatchCollector
from jugglerl.batch.env_stack import fit_normalisation_on, make_env
from jugglerl.batch.evaluations import Evaluations
from jugglerl.onpolicy.agent import make_agent, policy_sigma
from jugglerl.onpolicy.checks import check_config
from jugglerl.onpolicy.update import PPOUpdate
from jugglerl.onpolicy.variants import training_variants
from jugglerl.recording.blueprint import onpolicy_curves
from jugglerl.recording.logger import RerunLogger
from jugglerl.recording.names import TRAIN, join
from jugglerl.runs.interrupts import deferred_interrupt
from jugglerl.state.observation_parts import observed_parts
from jugglerl.state.transforms import normalised_size, state_size
from jugglerl.training import crossed
from jugglerl_envs.batch import usable_cores

#: The history entries the progress bar shows.
POSTFIX = ("throws_per_minute", "throws", "sigma")


class PPOTraining(ActorTraining):
    """One PPO run; ``run()`` trains to ``collector.total_frames``. Pass the ``state`` of
    ``load_checkpoint(path)`` to resume it exactly."""

    def __init__(self, cfg: DictConfig, run_dir: str | Path, state: dict | None = None):
        check_config(cfg)
        self.cfg = cfg
        self.run_dir = Path(run_dir)
        torch.manual_seed(cfg.seed)
        collect = cfg.collector
        size = normalised_size(cfg.state)
        norm = (
            state["normalisation"]
            if state
            else {"loc": torch.zeros(size), "scale": torch.ones(size)}
        )
        variants = training_variants(cfg, collect.num_envs)
        self.env = make_env(cfg, collect.num_envs, norm["loc"], norm["scale"], variants)
        self.collector = BatchCollector(self.env)
        self.collector.restart(cfg.seed)
        self.agent = make_agent(cfg, state_size(cfg.state))
        self.update = PPOUpdate(self.agent, cfg.algo, cfg.optim)
        self.evaluations = Evaluations(cfg, onpolicy_curves)
        self.batch_stats = BatchStats(cfg.env.timestep * cfg.env.frame_skip)
        self.frames = 0
        self.updates = 0
        self.wall_seconds = 0.0  # collecting, updating, evaluating; summed over resumed sessions
        self.seconds: dict[str, dict[str, float]] = {}  # the same, by part
        self._session_start: float | None = None
        self.history: list[dict] = []
        self.recording_id: str | None = None
        if state is not None:
            self.load_state_dict(state)
        else:
            parts = observed_parts(cfg.state)
            fit_normalisation_on(self.env, self.agent.actor, cfg.state.norm_frames, parts)

    # --- the loop -------------------------------------------------------------------------
    def _train(self, logger: RerunLogger, bar: tqdm) -> None:
        bar.set_description(f"PPO {self.cfg.actor.name}")
        while self.frames < self.cfg.collector.total_frames:
            self._iteration(logger, bar)

    def _iteration(self, logger: RerunLogger, bar: tqdm) -> None:
        record = self._collect_and_learn()
        logger.log_metrics({join(TRAIN, k): v for k, v in record.items()}, self.frames)
        bar.set_postfix({k: f"{record[k]:.3g}" for k in POSTFIX if k in record})
        frames = self.cfg.collector.frames_per_batch
        bar.update(frames)
        if crossed(self.frames, frames, self.cfg.eval.every_frames):
            evaluation = self.evaluate(logger, self.cfg.eval.duration)
            self.evaluations.keep_if_best(evaluation, self.current_actor())
        if crossed(self.frames, frames, self.cfg.checkpoint_every_frames):
            self.save()

    def _collect_and_learn(self) -> dict[str, float]:
        """One batch collected and learnt from; its record, added to the history."""
        started = time.monotonic()
        batch = self._collect()
        collected = time.monotonic()
        self.spent("collect", started)
        self.frames += batch.numel()
        record = {"frames": self.frames, **self.batch_stats(batch), **reward_terms(batch)}
        with deferred_interrupt(), self.timed("update"):  # a Ctrl-C inside an update is not a
            record |= self._learn(batch)  # clean stop
        record["sigma"] = float(policy_sigma(self.agent).mean())
        record["frames_per_second"] = batch.numel() / (collected - started)
        record["update_seconds"] = time.monotonic() - collected
        self.history.append(record)
        return record

    def _collect(self) -> TensorDict:
        """``frames_per_batch / num_envs`` steps of every env under the sampling policy: a
        tensordict ``[num_envs, steps]``."""
        steps = self.cfg.collector.frames_per_batch // self.cfg.collector.num_envs
        torch.set_num_threads(1)  # the physics has the cores
        return self.collector.collect(self.agent.policy, steps)

    def _learn(self, batch: TensorDict) -> dict[str, float]:
        """The PPO updates of ``batch`` (``update``); their mean losses."""
        torch.set_num_threads(usable_cores())
        done = (self.frames - batch.numel()) / self.cfg.collector.total_frames
        record, steps = self.update(batch, done)
        self.updates += steps
        return record

    def label(self) -> str:
        return f"PPO ({self.cfg.actor.name} actor, reward {self.cfg.env.reward})"

    def current_actor(self):
        return self.agent.actor

    # --- checkpoints ----------------------------------------------------------------------
    def state_dict(self) -> dict:
        return {
            **self.common_state(),
            "agent": {
                "policy": self.agent.policy.state_dict(),
                "critic": self.agent.critic.state_dict(),
            },
            "optimizer": self.update.state_dict(),
            "collector": self.collector.state_dict(),
        }

    def load_state_dict(self, state: dict) -> None:
        self.agent.policy.load_state_dict(state["agent"]["policy"])
        self.agent.critic.load_state_dict(state["agent"]["critic"])
        self.update.load_state_dict(state["optimizer"])
        self.collector.load_state_dict(state["collector"])
        self.load_common_state(state)


def reward_terms(batch: TensorDict) -> dict[str, float]:
    """The reward per step split into its throws and the rest (the dense terms)."""
    thrown = (batch["next", "throws"] - batch["throws"]).clamp(min=0).double().mean()
    reward = batch["next", "reward"].double().mean()
    return {"reward_throws": float(thrown), "reward_dense": float(reward - thrown)}
