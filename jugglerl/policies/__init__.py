"""Policies: everything that juggles, as one concept.

A ``Policy`` maps an observation of ``JuggleEnv`` and the episode time (s) to a normalised action,
and forgets its episode on ``reset()``. The kinds:

- ``command.CommandPolicy``: an open-loop via-point command (``jugglerl.commands``);
- ``feedback.FeedbackPolicy``: a command locked to the ball by feedback (the closed loop);
- ``throw_catch.ThrowCatchPolicy``: throws from rest and catches where the ball comes down;
- ``actor.ActorPolicy``: a trained network (torch, imported only when one is loaded).

``loading.load_policy`` turns a ``policy=`` argument into one: a shipped name (the YAML files of
``assets/policies/``), a policy file, or a training run (its directory or ``checkpoint.pt``,
which says what it holds).
"""

from typing import Protocol

import numpy as np


class Policy(Protocol):
    """Maps an observation and the episode time (s) to a normalised action."""

    def reset(self) -> None: ...

    def act(self, observation: np.ndarray, time: float) -> np.ndarray: ...
