"""Turn a ``policy=...`` argument into a runnable policy."""

from __future__ import annotations

import gymnasium as gym

from jugglerl.commands import load_command
from jugglerl.evaluation import CommandPolicy, Policy


def load_policy(spec: str, env: gym.Env) -> Policy:
    """A policy from a shipped command name (``expert``) or a command file path.

    Raises ``CommandError`` (a ``ValueError``) with a one-line reason when ``spec`` is unusable.
    """
    return CommandPolicy(load_command(spec), env)
