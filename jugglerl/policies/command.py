"""``CommandPolicy``: an open-loop via-point command as a policy.

A command file is a policy file of ``kind: command`` (format and ``load_command`` in
``jugglerl.commands``); the shipped ones (``expert``, ``dps_best``) live in ``assets/policies/``.
"""

from __future__ import annotations

import numpy as np

from jugglerl.commands import ViaPointCommand
from jugglerl_envs.actions import ctrl_to_action


class CommandPolicy:
    """Plays an open-loop ``ViaPointCommand``: ignores the observation, reads the time."""

    def __init__(self, command: ViaPointCommand):
        self.command = command

    def reset(self) -> None:
        """Open loop: nothing to forget between episodes."""

    def act(self, observation: np.ndarray, time: float) -> np.ndarray:
        return ctrl_to_action(self.command.setpoints(time))
