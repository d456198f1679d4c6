"""Open-loop cyclic via-point commands.

The paper's policy θ = (d, (t_1, a2_1, a3_1), …, (t_p, a2_p, a3_p)).

A command repeats every ``cycle`` seconds (d). At cycle time t_i the servo setpoints of
``shoulder_lift_joint`` (a2) and ``elbow_joint`` (a3) jump to the via-point's angles (radians) and
stay there until the next via-point; MuJoCo's position servos make the motion. Before the first
via-point of a cycle the last one's setpoints hold (the cycle wraps). ``shoulder_pan_joint`` stays
at ``pan`` (radians).

``lead_in`` (seconds, default 0) holds the pose the cycle starts in for that long before the first
cycle. The ball is dropped into the cup at the start; without a lead-in the first throw comes as
soon as the cycle says, before the dropped ball has settled, and an off-centre drop then often
loses it in the first throws even where the cycle itself is stable.

File format (a policy file of ``kind: command``, YAML or JSON: ``load_command``, ``save_command``)::

    kind: command
    name: expert
    cycle: 3.0            # d, seconds
    pan: 0.0              # optional, radians
    lead_in: 0.0          # optional, seconds
    via_points:           # [t (s), a2 (rad), a3 (rad)], t strictly increasing in [0, cycle)
      - [0.0, -1.5708, 2.2]
      - [1.5, -1.5708, 1.5]
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np

from jugglerl.runs.policy_files import PolicyFileError, read_policy_file, write_policy_file

KIND = "command"
KEYS = ("kind", "name", "cycle", "pan", "lead_in", "via_points")


class CommandError(PolicyFileError):
    """A command file or value that cannot be used; the message says what and where."""


@dataclass(frozen=True)
class ViaPointCommand:
    """A cyclic via-point command. Times in seconds, angles in radians."""

    cycle: float
    via_points: tuple[tuple[float, float, float], ...]
    pan: float = 0.0
    lead_in: float = 0.0
    name: str = field(default="command", compare=False)

    def __post_init__(self):
        if not np.isfinite(self.cycle) or self.cycle <= 0:
            raise CommandError(f"cycle={self.cycle!r} must be a positive number of seconds")
        if not np.isfinite(self.lead_in) or self.lead_in < 0:
            raise CommandError(f"lead_in={self.lead_in!r} must be a number of seconds >= 0")
        if not self.via_points:
            raise CommandError("via_points is empty: a command needs at least one via-point")
        if any(len(point) != 3 for point in self.via_points):
            raise CommandError("via_points must be a list of [t, a2, a3] finite numbers")
        points = np.asarray(self.via_points, dtype=float)
        if not np.isfinite(points).all():
            raise CommandError("via_points must be a list of [t, a2, a3] finite numbers")
        times = points[:, 0]
        if times[0] < 0 or times[-1] >= self.cycle or np.any(np.diff(times) <= 0):
            raise CommandError(
                f"via-point times {times.tolist()} must increase strictly"
                f" within [0, cycle={self.cycle})"
            )

    def setpoints(self, time: float | np.ndarray) -> np.ndarray:
        """Setpoints (pan, lift, elbow) in radians at ``time`` seconds after the command starts
        (its lead-in included).

        ``time`` may be an array of times: the result then has one row of 3 per time.
        """
        return self.cycle_setpoints(np.subtract(time, self.lead_in))

    def cycle_setpoints(self, cycle_time: float | np.ndarray) -> np.ndarray:
        """Setpoints at ``cycle_time`` seconds after the first cycle starts; before it (negative
        times: the lead-in) the pose the cycle starts in."""
        phase = np.mod(np.maximum(cycle_time, 0.0), self.cycle)
        index = np.searchsorted(self._times, phase, side="right") - 1  # -1 wraps to the last
        lift_elbow = self._angles[index]
        pan = np.full(np.shape(phase) + (1,), self.pan)
        return np.concatenate([pan, lift_elbow], axis=-1)

    @cached_property
    def _times(self) -> np.ndarray:
        return np.array([t for t, _, _ in self.via_points])

    @cached_property
    def _angles(self) -> np.ndarray:
        return np.array([(lift, elbow) for _, lift, elbow in self.via_points])

    def shorten_hold(self, index: int, cut: float) -> ViaPointCommand:
        """This command with via-point ``index`` held ``cut`` seconds less: every later via-point
        and the cycle's end move ``cut`` earlier, so the rest of the motion keeps its shape and
        timing (a negative ``cut`` holds longer). Used to measure how short a wait, e.g. the
        ball's settling in the cup between catch and throw, a command tolerates."""
        if not 0 <= index < len(self.via_points):
            raise CommandError(
                f"via-point {index} does not exist: the command has {len(self.via_points)}"
            )
        times = self._times
        hold_end = times[index + 1] if index + 1 < len(times) else self.cycle + times[0]
        hold = hold_end - times[index]
        if cut >= hold:
            raise CommandError(f"cannot cut {cut} s from via-point {index}'s hold of {hold:.3f} s")
        points = tuple(
            (t - cut if i > index else t, lift, elbow)
            for i, (t, lift, elbow) in enumerate(self.via_points)
        )
        return replace(self, cycle=self.cycle - cut, via_points=points)

    def to_dict(self) -> dict:
        """The file format's mapping (``kind: command``)."""
        return {
            "kind": KIND,
            "name": self.name,
            "cycle": self.cycle,
            "pan": self.pan,
            "lead_in": self.lead_in,
            "via_points": [list(p) for p in self.via_points],
        }


def command_from_dict(data: dict, source: str = "command") -> ViaPointCommand:
    """Build a command from the file format's mapping; errors name ``source`` and the key."""
    if not isinstance(data, dict):
        raise CommandError(
            f"{source}: expected a mapping with keys cycle, via_points (and pan, lead_in)"
        )
    unknown = set(data) - set(KEYS)
    if unknown:
        raise CommandError(f"{source}: unknown keys {sorted(unknown)}; valid: {', '.join(KEYS)}")
    for key in ("cycle", "via_points"):
        if key not in data:
            raise CommandError(f"{source}: missing key '{key}'")
    try:
        points = tuple(tuple(float(v) for v in point) for point in data["via_points"])
        cycle = float(data["cycle"])
        pan = float(data.get("pan", 0.0))
        lead_in = float(data.get("lead_in", 0.0))
    except (TypeError, ValueError) as error:
        raise CommandError(
            f"{source}: cycle, pan, lead_in and via_points must be numbers ({error})"
        ) from None
    name = str(data.get("name", Path(source).stem))
    try:
        return ViaPointCommand(cycle, points, pan, lead_in, name=name)
    except CommandError as error:
        raise CommandError(f"{source}: {error}") from None


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
