"""Stages of an off-policy run: what acts, what learns and from what, frame range by frame range.

Learning from a teacher goes through stages (``configs/algo/apprentice.yaml``): behaviour cloning
while the teacher acts, DAgger while the student acts and the teacher labels what it visits,
then RL from the cloned actor (``+experiment=apprentice_rl``). ``algo.stages`` maps each stage's
name (shown on the progress bar and in the history) to its settings, in the order they run, so
that a config adds a stage as a key and drops one by setting it to ``null``. A stage's settings:

| key | meaning |
| --- | --- |
| ``until`` | frame count at which the stage ends (the last: ``collector.total_frames``, which
  also cuts a stage short or leaves the later ones for a resume to reach) |
| ``loss`` | the ``algo.loss`` the stage updates with (``bc``, ``ddpg``, ``td3``) |
| ``acts`` | who acts: ``teacher`` (the student watches: behaviour cloning) or ``student`` (the
  actor acts, a teacher in the loop labels what it visits: DAgger, RL), through
  ``jugglerl.offpolicy.who_acts.WhoActs``; without it the ``exploration`` group's module acts |
| ``noise`` | with ``acts``: σ of the white noise on whoever acts (normalised action units) |
| ``exploration``, ``optim`` | keys of those groups replaced in this stage (a learning rate; an
  exploration key of a stage without ``acts``) |
| ``bc_weight``, ``bc_weight_end`` | the RL losses' cloning weight, linear over the stage |
| ``demonstrations`` | the stage's frames are kept as demonstrations too (a buffer of their own) |
| ``demo_fraction`` | fraction of each sampled batch drawn from the demonstrations |
| ``warmup_frames`` | the actor stays still for the stage's first frames (its critic learns first) |
| ``trains`` | the part of the actor the stage's updates train: ``base`` (default), or the
  ``correction`` on top of a frozen base (``actor.correction``) |
| ``n_steps`` | RL stages: critic targets from this many steps of rewards (default 1) |
| ``perturbed`` | name: env arguments (as ``eval.perturbed``, whose ``seeds`` it ignores); the
  stage's envs are split evenly among the nominal env and these, so it trains under what
  evaluations judge |
| ``stop`` | end the stage early, at one of its evaluations (``StopRule``): ``throws``, once an
  evaluation catches the ball and its score's throws (the nominal and perturbed episodes averaged,
  ``jugglerl.batch.evaluations.score``) reach it; ``patience``, after that many evaluations in a
  row without a better score than the stage's best. The later stages keep their lengths: they
  start and end earlier by the frames saved (``stopped_early``) |

Without ``algo.stages`` a run is one stage made of ``algo.loss`` and the exploration group.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass

from omegaconf import DictConfig, OmegaConf

from jugglerl.batch.evaluations import env_arguments, score
from jugglerl.offpolicy.losses import LOSSES
from jugglerl.offpolicy.who_acts import check_who_acts
from jugglerl_envs.validation import check_number

STAGE_KEYS = {
    "until",
    "loss",
    "acts",
    "noise",
    "exploration",
    "optim",
    "bc_weight",
    "bc_weight_end",
    "demonstrations",
    "demo_fraction",
    "warmup_frames",
    "trains",
    "n_steps",
    "perturbed",
    "stop",
}


@dataclass(frozen=True)
class StopRule:
    """When a stage ends at an evaluation before its ``until`` (the ``stop`` key)."""

    throws: float | None = None
    patience: int | None = None

    def reason(self, records: list[dict]) -> str | None:
        """Why the stage ends after the last of its evaluation ``records``, or ``None``."""
        scores = [score(record) for record in records]
        caught, throws = scores[-1][0] == 1, scores[-1][1]
        if self.throws is not None and caught and throws >= self.throws:
            return f"its evaluation scored {throws:.1f} throws (stop.throws={self.throws:g})"
        best = max(range(len(scores)), key=lambda k: (scores[k], -k))  # the first best
        if self.patience is not None and len(scores) - 1 - best >= self.patience:
            return f"{self.patience} evaluations without a better one (stop.patience)"
        return None

    @classmethod
    def from_spec(cls, spec, where: str) -> StopRule | None:
        if spec is None:
            return None
        if not isinstance(spec, Mapping) or not spec or set(spec) - {"throws", "patience"}:
            raise ValueError(f"{where}.stop: a mapping of throws and/or patience, not {spec}")
        throws, patience = spec.get("throws"), spec.get("patience")
        if throws is not None:
            check_number(f"{where}.stop.throws", throws, 0, low_open=True)
        if patience is not None:
            check_number(f"{where}.stop.patience", patience, 1, integer=True)
        return cls(throws=throws, patience=patience)


@dataclass(frozen=True)
class Stage:
    """One stage: frames ``[start, end)``, and the config its loss and exploration are built
    from (``cfg`` with the stage's loss, cloning weight, exploration and optim keys in place)."""

    index: int
    name: str
    start: int
    end: int
    cfg: DictConfig
    bc_weight: tuple[float, float]
    demonstrations: bool
    demo_fraction: float
    warmup_frames: int
    #: env arguments the stage's envs are split among (``[{}]``: all nominal)
    variants: tuple[dict, ...] = ({},)
    stop: StopRule | None = None
    #: who acts (``teacher`` or ``student``, with white noise of σ ``noise``), or ``None``: the
    #: exploration group's module
    acts: str | None = None
    noise: float = 0.0

    def bc_weight_at(self, frames: int) -> float:
        """The cloning weight after ``frames`` frames of the run."""
        progress = min(1.0, max(0.0, (frames - self.start) / max(1, self.end - self.start)))
        start, end = self.bc_weight
        return start + (end - start) * progress

    def actor_frozen(self, frames: int) -> bool:
        """Whether the updates made once ``frames`` frames are collected leave the actor still."""
        return self.warmup_frames > 0 and frames <= self.start + self.warmup_frames


def stages_from_config(cfg: DictConfig) -> list[Stage]:
    """The run's stages (module docstring); bad stage settings raise ``ValueError`` naming them."""
    total = cfg.collector.total_frames
    specs = cfg.algo.get("stages")
    if specs is not None and not isinstance(specs, Mapping):
        raise ValueError(f"algo.stages must map stage names to their settings, not {specs}")
    specs = {name: spec for name, spec in (specs or {}).items() if spec is not None}
    named = bool(specs)  # errors name the stage, or the algorithm's keys of a one-stage run
    if not specs:
        specs = {cfg.algo.name: {"loss": cfg.algo.loss}}
    _check_optim(cfg.optim, {}, "algo")  # also where every stage sets its own
    stages, start = [], 0
    for index, (name, spec) in enumerate(specs.items()):
        where = f"algo.stages.{name}"
        if not isinstance(spec, Mapping):
            raise ValueError(f"{where} must map setting names to values (or be null), not {spec}")
        unknown = set(spec) - STAGE_KEYS
        if unknown:
            raise ValueError(
                f"{where}: unknown keys {sorted(unknown)}; allowed: {sorted(STAGE_KEYS)}"
            )
        last = index == len(specs) - 1
        end = max(total, start) if last else spec.get("until")
        if not last and (end is None or end <= start):
            raise ValueError(
                f"{where}.until={end} must be above the previous stage's end ({start})"
            )
        stage_cfg = copy.deepcopy(cfg)
        OmegaConf.set_struct(stage_cfg, False)
        stage_cfg.algo.loss = spec.get("loss", cfg.algo.loss)
        bc_weight = float(spec.get("bc_weight", cfg.algo.get("bc_weight", 0.0)))
        stage_cfg.algo.bc_weight = bc_weight
        acts, noise = _who_acts(spec, cfg, where)
        if acts is None:
            stage_cfg.exploration = OmegaConf.merge(cfg.exploration, spec.get("exploration", {}))
        stage_cfg.optim = OmegaConf.merge(cfg.optim, spec.get("optim", {}))
        _check_optim(stage_cfg.optim, spec.get("optim", {}), where)
        stage_cfg.optim.trains = str(spec.get("trains", "base"))
        stage_cfg.algo.n_steps = int(spec.get("n_steps", cfg.algo.get("n_steps", 1)))
        if stage_cfg.algo.n_steps < 1:
            raise ValueError(f"{where}.n_steps={stage_cfg.algo.n_steps} must be >= 1")
        try:
            LOSSES.get(stage_cfg.algo.loss).check_config(stage_cfg)
        except ValueError as error:
            raise ValueError(f"{where}: {error}" if named else str(error)) from None
        fraction = float(spec.get("demo_fraction", 0.0))
        if not 0 <= fraction < 1:
            raise ValueError(f"{where}.demo_fraction={fraction} must be in [0, 1)")
        stages.append(
            Stage(
                index=index,
                name=str(name),
                start=start,
                end=int(end),
                cfg=stage_cfg,
                bc_weight=(bc_weight, float(spec.get("bc_weight_end", bc_weight))),
                demonstrations=bool(spec.get("demonstrations", False)),
                demo_fraction=fraction,
                warmup_frames=int(spec.get("warmup_frames", 0)),
                variants=_variants(spec.get("perturbed"), where),
                stop=StopRule.from_spec(spec.get("stop"), where),
                acts=acts,
                noise=noise,
            )
        )
        start = int(end)
    if any(stage.demo_fraction for stage in stages) and not any(
        stage.demonstrations for stage in stages
    ):
        raise ValueError("algo.stages: a demo_fraction needs a stage with demonstrations: true")
    # a shorter run ends before the stages past its budget (checked all the same: a resume with
    # a larger collector.total_frames reaches them)
    return [dataclasses.replace(s, end=min(s.end, total)) for s in stages if s.start < total]


def stopped_early(stages: list[Stage], stops: Mapping[int, int]) -> list[Stage]:
    """``stages`` with each stage of ``stops`` (index: the frame it stopped at) ending there and
    the stages after it shifted earlier by the frames it saved."""
    stages = list(stages)
    for index, frame in sorted(stops.items()):
        saved = stages[index].end - frame
        stages[index] = dataclasses.replace(stages[index], end=frame)
        for later in range(index + 1, len(stages)):
            stage = stages[later]
            stages[later] = dataclasses.replace(
                stage, start=stage.start - saved, end=stage.end - saved
            )
    return stages


def _check_optim(optim: DictConfig, stage_optim: Mapping, where: str) -> None:
    """Positive learning rates, a whole number of updates per batch (0: the stage only
    collects); an error names the stage's key where the stage sets it."""

    def name(key: str) -> str:
        return f"{where}.optim.{key}" if key in stage_optim else f"optim.{key}"

    for key in ("lr_actor", "lr_critic"):
        if optim.get(key) is not None:
            check_number(name(key), optim[key], 0, low_open=True)
    check_number(name("updates_per_batch"), optim.get("updates_per_batch"), 0, integer=True)


def _who_acts(spec: Mapping, cfg: DictConfig, where: str) -> tuple[str | None, float]:
    """A stage's ``acts`` and ``noise`` (``None``, 0 without ``acts``: the exploration group
    acts), checked: a teacher to act, no exploration keys beside them."""
    acts, noise = spec.get("acts"), spec.get("noise", 0.0)
    if acts is None:
        if "noise" in spec:
            raise ValueError(f"{where}.noise is the σ of who acts: it needs {where}.acts")
        if cfg.get("exploration") is None:
            raise ValueError(f"{where}: without acts the stage needs an exploration group")
        return None, 0.0
    try:
        check_who_acts(acts, noise)
    except ValueError as error:
        raise ValueError(f"{where}.{error}") from None
    if acts == "teacher" and cfg.teacher.policy is None:
        raise ValueError(f"{where}.acts=teacher needs a teacher.policy")
    if spec.get("exploration"):
        raise ValueError(f"{where}: a stage with acts does not explore (exploration keys given)")
    return str(acts), float(noise)


def _variants(perturbed, where: str) -> tuple[dict, ...]:
    """The nominal env and each condition of a stage's ``perturbed`` mapping."""
    if not perturbed:
        return ({},)
    if not isinstance(perturbed, Mapping):
        raise ValueError(f"{where}.perturbed must map names to env arguments")
    conditions = OmegaConf.to_container(OmegaConf.create(dict(perturbed)), resolve=True)
    return ({}, *(env_arguments(condition) for condition in conditions.values()))
