"""Clear one-line errors for on-policy settings that cannot work together."""

from __future__ import annotations

from omegaconf import DictConfig

from jugglerl.batch.env_stack import check_collector
from jugglerl.batch.evaluations import check_evaluations
from jugglerl.state.observation_parts import observed_parts


def check_config(cfg: DictConfig) -> None:
    """Raise ``ValueError`` naming the keys of a budget, an update or an evaluation that cannot
    work."""
    check_collector(cfg)
    if cfg.collector.env != "batch":
        raise ValueError(f"collector.env={cfg.collector.env}: algo=ppo collects from a batch")
    algo = cfg.algo
    if not 0 < algo.gamma <= 1 or not 0 <= algo.lmbda <= 1:
        raise ValueError(
            f"algo.gamma={algo.gamma} must be in (0, 1], algo.lmbda={algo.lmbda} in [0, 1]"
        )
    if algo.epochs < 1 or not 1 <= algo.minibatch_size <= cfg.collector.frames_per_batch:
        raise ValueError(
            f"algo.epochs={algo.epochs} must be >= 1 and algo.minibatch_size="
            f"{algo.minibatch_size} between 1 and collector.frames_per_batch="
            f"{cfg.collector.frames_per_batch}"
        )
    if algo.clip_epsilon <= 0 or algo.entropy_coeff < 0 or algo.critic_coeff <= 0:
        raise ValueError(
            f"algo.clip_epsilon={algo.clip_epsilon} and algo.critic_coeff={algo.critic_coeff}"
            f" must be > 0, algo.entropy_coeff={algo.entropy_coeff} >= 0"
        )
    if cfg.optim.lr <= 0 or cfg.optim.max_grad_norm <= 0:
        raise ValueError(
            f"optim.lr={cfg.optim.lr} and optim.max_grad_norm={cfg.optim.max_grad_norm} must be > 0"
        )
    observed_parts(cfg.state)
    check_evaluations(cfg)
