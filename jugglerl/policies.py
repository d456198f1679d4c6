"""Turn a ``policy=...`` argument into a runnable policy."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym

from jugglerl.commands import load_command
from jugglerl.evaluation import CommandPolicy, Policy
from jugglerl.feedback import feedback_policy_path, load_feedback_policy

#: File names that mark a trained checkpoint rather than a command file.
CHECKPOINT_SUFFIX = ".pt"


def load_policy(spec: str, env: gym.Env) -> Policy:
    """A policy from a shipped name (a command such as ``expert``, or a closed-loop policy of
    ``assets/policies/`` such as ``closed_loop``), a command or closed-loop policy file, or a DDPG
    checkpoint (a ``.pt`` file, or a run directory holding ``checkpoint.pt``).

    Raises ``ValueError`` with a one-line reason when ``spec`` is unusable.
    """
    path = Path(spec)
    if path.suffix == CHECKPOINT_SUFFIX or path.is_dir():
        return _checkpoint_policy(path)
    feedback = feedback_policy_path(spec)
    if feedback is not None:
        return load_feedback_policy(feedback, env)
    return CommandPolicy(load_command(spec), env)


def _checkpoint_policy(path: Path) -> Policy:
    # torch and torchrl load only when a checkpoint is asked for
    from jugglerl.checkpoints import checkpoint_algo, load_checkpoint
    from jugglerl.ddpg.policy import ActorPolicy

    state = load_checkpoint(path)
    algo = checkpoint_algo(state)
    if algo != "ddpg":
        best = "best_policy.yaml" if algo == "feedback" else "best_command.yaml"
        raise ValueError(f"{path} is a {algo} checkpoint; evaluate its {best} instead")
    return ActorPolicy.from_state(state)
