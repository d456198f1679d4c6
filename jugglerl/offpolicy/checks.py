"""Clear one-line errors for off-policy settings that cannot work together."""

from __future__ import annotations

from omegaconf import DictConfig

from jugglerl.config import make_juggle_env
from jugglerl.networks.actors import recurrent_state
from jugglerl.offpolicy.evaluation import perturbed_conditions
from jugglerl.state.observation_parts import observed_parts


def check_config(cfg: DictConfig) -> None:
    """Raise ``ValueError`` naming the keys of a budget, buffer or evaluation that cannot work."""
    if cfg.env.balls != 1:
        raise ValueError(
            f"env.balls={cfg.env.balls}: the networks' state observes one ball (jugglerl/state);"
            " off-policy training runs with env.balls=1"
        )
    collect = cfg.collector
    if collect.num_envs < 1:
        raise ValueError(f"collector.num_envs={collect.num_envs} must be >= 1")
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
    observed_parts(cfg.state)
    steps = collect.frames_per_batch // collect.num_envs
    if recurrent_state(cfg.actor) and cfg.replay_buffer.slice_len > steps:
        # the buffer stores each batch env by env: a trajectory's steps are contiguous only
        # within one batch, and sub-trajectories are sampled from contiguous runs
        raise ValueError(
            f"replay_buffer.slice_len={cfg.replay_buffer.slice_len} must be at most the steps"
            f" per env in a batch, collector.frames_per_batch / collector.num_envs = {steps}"
        )
    if cfg.eval.seeds < 1 or cfg.eval.duration < cfg.eval.catch_time:
        raise ValueError(
            f"eval.seeds={cfg.eval.seeds} must be >= 1 and eval.duration={cfg.eval.duration}"
            f" at least eval.catch_time={cfg.eval.catch_time}"
        )
    check, conditions = cfg.eval, perturbed_conditions(cfg)
    if conditions and (check.perturbed_seeds < 1 or check.perturbed_duration <= 0):
        raise ValueError(
            f"eval.perturbed_seeds={check.perturbed_seeds} must be >= 1 and"
            f" eval.perturbed_duration={check.perturbed_duration} > 0"
        )
    make_juggle_env(cfg.env).close()  # the nominal env first: its keys blamed as env.KEY
    for name, overrides in conditions.items():  # fail now, not at the first evaluation
        try:
            make_juggle_env(cfg.env, **overrides).close()
        except (ValueError, TypeError) as error:
            raise ValueError(f"eval.perturbed.{name}: {error}") from None
