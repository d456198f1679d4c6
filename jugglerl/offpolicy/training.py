"""The off-policy trainer (``trainer: offpolicy``), read top to bottom: collect -> store ->
update -> log -> evaluate -> checkpoint, stage by stage (``algo.stages``,
``jugglerl.offpolicy.stages``; one stage unless the algorithm lists several), each stage with its
loss a plug-in (``algo.loss``: ``ddpg``, ``td3``, ``bc``; ``jugglerl.offpolicy.losses``).

``OffPolicyTraining`` is built from the Hydra config (``configs/train.yaml``; ``algo=apprentice``
is the default) and a run directory, where it writes

- ``checkpoint.pt`` every ``checkpoint_every_frames``, at the end and on Ctrl-C (atomically):
  the stage (and the stages that stopped early), its loss's networks, targets and optimisers,
  the normalisation, the exploration state, RNG states, counters, wall time (and where it went),
  the throw-rate window, history, config, the deployed actor (``policy``: what
  ``scripts/evaluate.py policy=<run dir>`` runs), the envs' running episodes and the teacher's
  (``jugglerl.batch.collector``) and how far the replay buffers have filled: a resumed run
  repeats an uninterrupted one, or says in a ``note:`` what it could not restore
  (``jugglerl.offpolicy.resume``);
- ``buffers/``: the replay buffers' frames, memory-mapped (``jugglerl.offpolicy.buffer``);
- ``metrics.json`` at the end: the final evaluation over ``eval.seeds`` full-length episodes, the
  periodic evaluations and the per-batch history.

With ``teacher.policy`` set, a teacher runs in the loop beside the actor (``teacher``): its actions
land in the replay buffer for behaviour cloning, and a stage's ``acts`` says whether they or the
actor's move the envs (``jugglerl.offpolicy.who_acts``); a stage with
``demonstrations`` also keeps its frames apart, for the later stages' ``demo_fraction``. Metrics
go to rerun under ``train/`` (per batch) and ``eval/`` (each evaluation) on the ``step`` timeline
(frames).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import torch
from omegaconf import DictConfig
from tensordict.nn import TensorDictSequential
from tqdm import tqdm

from jugglerl.batch.actor_training import ActorTraining
from jugglerl.batch.batch_stats import BatchStats
from jugglerl.batch.collector import BatchCollector
from jugglerl.batch.env_stack import make_env, normalisation
from jugglerl.batch.evaluations import Evaluations
from jugglerl.config.envs import make_juggle_env
from jugglerl.networks.actors import ACTION_SIZE, build_actor, recurrent_state
from jugglerl.offpolicy.buffer import ReplayBuffer
from jugglerl.offpolicy.checks import check_config
from jugglerl.offpolicy.exploration import make_exploration
from jugglerl.offpolicy.init_actor import initial_weights, load_base_weights
from jugglerl.offpolicy.losses import LOSSES
from jugglerl.offpolicy.n_step import n_step_returns
from jugglerl.offpolicy.resume import resume_notes
from jugglerl.offpolicy.stages import Stage, stages_from_config, stopped_early
from jugglerl.offpolicy.teacher import TeacherModule, teacher_period
from jugglerl.offpolicy.who_acts import WhoActs
from jugglerl.policies.loading import load_named_policy
from jugglerl.recording.logger import RerunLogger
from jugglerl.recording.names import TRAIN, join
from jugglerl.runs.files import BUFFERS
from jugglerl.runs.interrupts import deferred_interrupt
from jugglerl.state.transforms import state_size
from jugglerl.training import crossed

#: The history entries the progress bar shows.
POSTFIX = ("throws_per_minute", "return", "throws")


class OffPolicyTraining(ActorTraining):
    """One off-policy run; ``run()`` trains to ``collector.total_frames``. Pass the ``state`` of
    ``load_checkpoint(path)`` to resume (it also supplies the observation normalisation)."""

    def __init__(self, cfg: DictConfig, run_dir: str | Path, state: dict | None = None):
        check_config(cfg)
        self.cfg = cfg
        self.run_dir = Path(run_dir)
        teacher = None
        if cfg.teacher.policy is not None:
            with make_juggle_env(cfg.env) as env:  # what the teacher reads, where it is timed
                teacher = load_named_policy("teacher.policy", cfg.teacher.policy, env)
                if cfg.state.period == "teacher":  # resolved here: checkpoints keep the number
                    cfg.state.period = teacher_period(teacher, env)
        if cfg.state.period == "teacher":
            raise ValueError("state.period=teacher needs a teacher.policy")
        torch.manual_seed(cfg.seed)
        start = initial_weights(cfg) if state is None and cfg.get("init_actor") else None
        norm = (state or start or {}).get("normalisation", {"loc": None, "scale": None})
        #: stage index -> the frame it stopped at, before its ``until`` (its ``stop`` rule)
        self.stops: dict[int, int] = dict(state.get("stopped_early", {})) if state else {}
        self.stages = stopped_early(stages_from_config(cfg), self.stops)
        first = self.stages[state.get("stage", 0)] if state else self.stages[0]
        self.env = make_env(
            cfg, cfg.collector.num_envs, norm["loc"], norm["scale"], list(first.variants)
        )
        self.actor = build_actor(cfg.actor, state_size(cfg.state), ACTION_SIZE)
        if start is not None:
            load_base_weights(self.actor, start["policy"], cfg.init_actor)
        self.recurrent = bool(recurrent_state(cfg.actor))
        self.collector = BatchCollector(self.env)
        self.teacher = [] if teacher is None else [TeacherModule(teacher, cfg.collector.num_envs)]
        folder = self.run_dir / BUFFERS
        self.buffer = ReplayBuffer.from_config(cfg.replay_buffer, self.recurrent, folder / "replay")
        self.demonstrations = ReplayBuffer.from_config(
            cfg.replay_buffer, self.recurrent, folder / "demonstrations"
        )
        self.evaluations = Evaluations(cfg)
        self.frames = 0
        self.updates = 0
        self.wall_seconds = 0.0  # collecting, updating, evaluating; summed over resumed sessions
        self.seconds: dict[str, dict[str, float]] = {}  # the same, by part and by stage
        self._session_start: float | None = None  # while run() trains
        self.history: list[dict] = []  # one record per collected batch
        self.batch_stats = BatchStats(cfg.env.timestep * cfg.env.frame_skip)
        self.recording_id: str | None = None
        self._waiting = False  # told the user that the updates wait for a sliceable buffer
        # a checkpoint holds the loss and exploration of the stage it was saved in
        self._enter(first)
        if state is not None:
            self.load_state_dict(state)

    def _enter(self, stage: Stage) -> None:
        """Build ``stage``'s loss (on the same actor), who acts (``acts``, else the exploration
        group's module) and the acting policy."""
        self.stage = stage
        self.update = LOSSES.get(stage.cfg.algo.loss)(
            self.actor, state_size(self.cfg.state), self.env.action_spec, stage.cfg, self.recurrent
        )
        if stage.acts is not None:
            self.noise = WhoActs(stage.acts, stage.noise)
        else:
            self.noise = make_exploration(stage.cfg.exploration, self.env.action_spec)
        self.policy = TensorDictSequential(*self.teacher, self.actor, self.noise)

    # --- the loop -------------------------------------------------------------------------
    def _train(self, logger: RerunLogger, bar: tqdm) -> None:
        """Each stage from the current one, each collected to its end. A stage starts from the
        actor the one before would deploy (``current_actor``: with ``eval.target_actor`` its
        average or target), not from its last online weights."""
        for index in range(self.stage.index, len(self.stages)):
            stage = self.stages[index]  # looked up each time: a stage that stops moves the rest
            if stage is not self.stage:
                self.actor.load_state_dict(self.current_actor().state_dict())
                if stage.variants != self.stage.variants:
                    self._perturb(stage.variants)
                self._enter(stage)
            if self.frames < stage.end:
                with self.timed(stage.name, "stages"):
                    self._train_stage(logger, bar)

    def _perturb(self, variants: tuple[dict, ...]) -> None:
        """New envs split among ``variants`` (a stage's ``perturbed``), same normalisation."""
        norm = normalisation(self.env)
        self.env.close()
        collect = self.cfg.collector
        loc, scale = norm.loc.clone(), norm.scale.clone()
        self.env = make_env(self.cfg, collect.num_envs, loc, scale, list(variants))
        self.collector = BatchCollector(self.env)

    def _train_stage(self, logger: RerunLogger, bar: tqdm) -> None:
        collect = self.cfg.collector
        bar.set_description(f"{self.stage.name.upper()} {self.cfg.actor.name}")
        if self.frames == self.stage.start or self.collector.carried is None:
            self.collector.restart(self.cfg.seed + self.frames)  # new episodes
        algo = self.stage.cfg.algo
        steps = collect.frames_per_batch // collect.num_envs
        while self.frames < self.stage.end:
            with self.timed("collect"):  # the envs, the teacher, the acting actor
                random = self.frames < collect.init_random_frames
                batch = self.collector.collect(self.policy, steps, random)
            stats = self.batch_stats(batch)  # of the steps as played
            batch = n_step_returns(batch, algo.n_steps, algo.get("gamma", 1.0))
            self.buffer.extend(batch)
            if self.stage.demonstrations:
                self.demonstrations.extend(batch)
            self.frames += batch.numel()
            self.noise.step(batch.numel())
            record = {"frames": self.frames, "stage": self.stage.index}
            with deferred_interrupt(), self.timed("update"):  # a Ctrl-C inside a loss is
                record |= self._learn()  # not a clean stop
            record |= stats
            self.history.append(record)
            logger.log_metrics({join(TRAIN, k): v for k, v in record.items()}, self.frames)
            bar.set_postfix({k: f"{record[k]:.3g}" for k in POSTFIX if k in record})
            bar.update(batch.numel())
            stop = None
            if crossed(self.frames, batch.numel(), self.cfg.eval.every_frames):
                record = self.evaluate(logger, self.cfg.eval.duration)
                self.evaluations.keep_if_best(record, self.current_actor())
                stop = self._stop_reason()
            if stop:
                self._stop_stage(stop, bar)  # the stage's end is now: the loop ends
            if stop or crossed(self.frames, batch.numel(), self.cfg.checkpoint_every_frames):
                self.save()

    def _stop_reason(self) -> str | None:
        """Why the stage ends at the evaluation just made (its ``stop`` rule), or ``None``."""
        if self.stage.stop is None:
            return None
        stage = self.stage
        records = [r for r in self.evaluations.records if stage.start < r["frames"] <= stage.end]
        return stage.stop.reason(records)

    def _stop_stage(self, reason: str, bar: tqdm) -> None:
        """End the stage here: the later stages start now and keep their lengths."""
        saved = self.stage.end - self.frames
        self.stops[self.stage.index] = self.frames
        self.stages = stopped_early(self.stages, {self.stage.index: self.frames})
        self.stage = self.stages[self.stage.index]
        bar.total -= saved
        bar.refresh()
        tqdm.write(
            f"note: stage {self.stage.name} ends at frame {self.frames}, {saved} frames early:"
            f" {reason}",
            file=sys.stderr,
        )

    def _learn(self) -> dict:
        """The stage's ``optim.updates_per_batch`` updates once the buffer holds a batch; mean
        losses."""
        if self.frames < self.cfg.collector.init_random_frames:
            return {}
        if not self.buffer.ready:
            if len(self.buffer) >= self.cfg.replay_buffer.batch_size and not self._waiting:
                self._waiting = True
                print(
                    f"note: no episode piece of replay_buffer.slice_len={self.buffer.slice_len}"
                    " steps collected yet; the updates wait for one",
                    file=sys.stderr,
                )
            return {}
        self.update.bc_weight = self.stage.bc_weight_at(self.frames)
        self.update.actor_frozen = self.stage.actor_frozen(self.frames)
        updates = self.stage.cfg.optim.updates_per_batch
        losses = [self.update(self._sample()) for _ in range(updates)]
        self.updates += len(losses)
        keys = dict.fromkeys(key for loss in losses for key in loss)
        return {key: float(np.mean([loss[key] for loss in losses if key in loss])) for key in keys}

    def _sample(self):
        """A batch from the replay buffer, ``demo_fraction`` of it from the demonstrations."""
        fraction, keys = self.stage.demo_fraction, self.update.reads
        if fraction == 0 or not self.demonstrations.sliceable:
            return self.buffer.sample(keys=keys)
        demos = self.demonstrations.sample(fraction, keys)
        return torch.cat([self.buffer.sample(1 - fraction, keys), demos], dim=0)

    def frame_budget(self) -> int:
        return self.stages[-1].end  # collector.total_frames less what stopped stages saved

    def label(self) -> str:
        exploration = self.cfg.get("exploration")
        explores = f" {exploration.name} exploration," if exploration is not None else ""
        return (
            f"{self.cfg.algo.name.upper()} ({self.cfg.actor.name} actor,{explores}"
            f" reward {self.cfg.env.reward})"
        )

    # --- evaluation -----------------------------------------------------------------------
    def current_actor(self):
        """The actor as trained so far: the target (Polyak-averaged) actor with
        ``eval.target_actor``, else the online one. The online actor can swing between
        updates; its average moves by ``algo.tau`` per update and holds on to what worked."""
        return self.update.target_actor() if self.cfg.eval.target_actor else self.actor

    # --- checkpoints ----------------------------------------------------------------------
    def state_dict(self) -> dict:
        return {
            **self.common_state(),
            "actor": self.actor.state_dict(),
            "update": self.update.state_dict(),
            "stage": self.stage.index,
            "stopped_early": dict(self.stops),
            "exploration": self.noise.state_dict(),
            "collector": self.collector.state_dict(),
            "teacher": [teacher.episode_state() for teacher in self.teacher],
            "buffers": {
                "replay": self.buffer.state_dict(),
                "demonstrations": self.demonstrations.state_dict(),
            },
        }

    def load_state_dict(self, state: dict) -> None:
        """Back to a checkpoint: networks, optimisers, exploration, the envs' running episodes,
        the teacher's and the replay buffers (reopened from the run folder); one ``note:`` line
        for each thing it cannot restore."""
        self.actor.load_state_dict(state["actor"])
        self.update.load_state_dict(state["update"])
        self.noise.load_state_dict(state["exploration"])
        self.load_common_state(state)
        continued = self.collector.load_state_dict(state.get("collector", {}))
        if continued:  # the teacher's episodes are the envs'
            for teacher, episodes in zip(self.teacher, state["teacher"], strict=True):
                teacher.load_episode_state(episodes)
        buffers = state.get("buffers")  # absent from checkpoints written before they were kept
        restored = buffers is not None and all(
            buffer.load_state_dict(buffers[name])
            for buffer, name in ((self.buffer, "replay"), (self.demonstrations, "demonstrations"))
        )
        mid_stage = self.stage.start < self.frames < self.stage.end
        episodes = continued or not mid_stage  # a new stage starts new ones anyway
        for note in resume_notes(self.stages, self.frames, self.buffer, restored, episodes):
            print(note, file=sys.stderr)
