"""``CommandPolicy``: an open-loop via-point command as a policy, and command files.

A command file is a policy file of ``kind: command`` (format in ``jugglerl.commands``); the
shipped ones (``expert``, ``dps_best``) live in ``assets/policies/``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from jugglerl.commands import KIND, CommandError, ViaPointCommand, command_from_dict
from jugglerl.policies.files import read_policy_file, write_policy_file
from jugglerl_envs.actions import ctrl_to_action


class CommandPolicy:
    """Plays an open-loop ``ViaPointCommand``: ignores the observation, reads the time."""

    def __init__(self, command: ViaPointCommand):
        self.command = command

    def reset(self) -> None:
        """Open loop: nothing to forget between episodes."""

    def act(self, observation: np.ndarray, time: float) -> np.ndarray:
        return ctrl_to_action(self.command.setpoints(time))


def load_command(name_or_path: str | Path) -> ViaPointCommand:
    """A command by shipped name (``expert``) or from a ``.yaml``/``.yml``/``.json`` file (a
    policy file of ``kind: command``; the kind may be left out)."""
    data, source = read_policy_file(name_or_path)
    if data.get("kind", KIND) != KIND:
        raise CommandError(f"{source}: kind={data.get('kind')!r} is not a command (kind: {KIND})")
    return command_from_dict(data, source)


def save_command(command: ViaPointCommand, path: str | Path) -> Path:
    """Write ``command`` as a policy file (YAML, or JSON for a ``.json`` path)."""
    return write_policy_file(command.to_dict(), path)
