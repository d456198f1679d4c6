"""Clear one-line errors for off-policy settings that cannot work together."""

from __future__ import annotations

from omegaconf import DictConfig

from jugglerl.batch.env_stack import check_collector
from jugglerl.batch.evaluations import check_evaluations
from jugglerl.networks.actors import recurrent_state
from jugglerl.state.observation_parts import observed_parts


def check_config(cfg: DictConfig) -> None:
    """Raise ``ValueError`` naming the keys of a budget, buffer or evaluation that cannot work."""
    check_collector(cfg)
    observed_parts(cfg.state)
    collect = cfg.collector
    steps = collect.frames_per_batch // collect.num_envs
    if recurrent_state(cfg.actor) and cfg.replay_buffer.slice_len > steps:
        # the buffer stores each batch env by env: a trajectory's steps are contiguous only
        # within one batch, and sub-trajectories are sampled from contiguous runs
        raise ValueError(
            f"replay_buffer.slice_len={cfg.replay_buffer.slice_len} must be at most the steps"
            f" per env in a batch, collector.frames_per_batch / collector.num_envs = {steps}"
        )
    episode = round(cfg.env.duration / (cfg.env.timestep * cfg.env.frame_skip))
    if recurrent_state(cfg.actor) and cfg.replay_buffer.slice_len > episode:
        raise ValueError(
            f"replay_buffer.slice_len={cfg.replay_buffer.slice_len} must be at most the steps"
            f" of an episode, env.duration={cfg.env.duration:g} s = {episode} steps"
        )
    check_evaluations(cfg)
