"""A closed-loop juggler: a via-point command locked to the ball, with the cup steered under it.

Why: an open-loop cycle in this scene is knife-edge (``scripts/robustness.py``). A ball that lands
a little late is thrown a little harder, lands later still, and is lost; a ball that lands a
centimetre off-centre hits the cone's wall. ``FeedbackPolicy`` closes both loops on the state:

- **Phase lock.** The command is played on its own phase clock. Each time the falling ball passes
  ``LOCK_HEIGHT`` above the cup (the moment is interpolated within the env step), the clock is
  pulled toward ``land_phase`` by ``phase_gain`` (1 = reset), so the catch and the next throw keep
  their timing relative to the ball, whatever its last flight took.
- **Landing tracking.** While the ball falls toward the cup, the landing point is predicted from
  its position and velocity (ballistic, the env's gravity), and the cup's horizontal offset from
  the command moves by ``land_gain`` × the error each step, up to ``MAX_OFFSET``. The pan joint
  moves the cup sideways (y); the shoulder lift and elbow turned by opposite angles move it
  along x without tilting it. Between flights the offset decays by ``decay`` per step, back to
  the command.

The four gains and the aim point ``(bias_x, bias_y)`` form the parameter vector ``θ`` that
``algo=feedback`` (the search space ``jugglerl.dps.spaces.feedback_gains``) searches; this module
needs no torch. A policy file is YAML of ``kind: feedback``: ``name``, ``command`` (a command
mapping) and ``feedback`` (the gains by name). Shipped: ``closed_loop_gains`` (gains searched for
``dps_best``), ``closed_loop_tolerant`` and ``closed_loop`` (command and gains searched together,
``algo=closed_loop``, under growing imprecision).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import gymnasium as gym
import numpy as np

from jugglerl.commands import CommandError, ViaPointCommand, command_from_dict
from jugglerl.policy_files import write_policy_file
from jugglerl_envs.actions import ctrl_to_action

#: m above the cup at which the falling ball locks the command's phase.
LOCK_HEIGHT = 0.2
#: m the ball must rise above ``LOCK_HEIGHT`` before it can lock the phase again.
LOCK_REARM = 0.05
#: m above the cup above which a ball that is not rising fast is tracked.
TRACK_HEIGHT = 0.12
#: m/s: a ball rising faster than this has just been thrown; its landing is not predicted yet.
TRACK_MAX_RISE = 0.5
#: m above the cup where the predicted landing point is taken.
LANDING_HEIGHT = 0.05
#: m, largest horizontal offset of the cup from the command.
MAX_OFFSET = 0.05
#: m of cup travel per rad: pan (y) and the lift/elbow pair (x), at the paper's home pose
#: (kinematic, from ``mj_jac``; the pair turns the upper arm, whose length is the UR5e's a2).
#: Through the position servos the cup goes 1.2-1.8x as far along x (their static deflection
#: under the arm's weight changes with the pose) and about as far along y; the learned gains
#: absorb the difference.
PAN_LEVER = 0.445
PAIR_LEVER = 0.425

KIND = "feedback"


@dataclass(frozen=True)
class FeedbackGains:
    """The searched parameters; ``θ`` is these fields in this order."""

    land_phase: float  # s of the command's cycle at which the falling ball should lock
    phase_gain: float  # fraction of the phase error removed at each lock (1 = reset)
    land_gain: float  # per env step, fraction of the landing error added to the cup offset
    decay: float  # per env step while not tracking, the offset's factor toward the command
    bias_x: float  # m, landing point (relative to the cup) the tracking aims for
    bias_y: float


PARAM_NAMES = tuple(f.name for f in fields(FeedbackGains))


class FeedbackPolicy:
    """Plays ``command`` closed loop with ``gains`` (see the module docstring) in envs like
    ``env``, whose control period and gravity it reads (it keeps no reference to the env)."""

    def __init__(self, command: ViaPointCommand, gains: FeedbackGains, env: gym.Env):
        self.command = command
        self.gains = gains
        unwrapped = env.unwrapped
        self._dt = unwrapped.dt
        self._gravity = -unwrapped.gravity
        self.reset()

    def reset(self) -> None:
        self.phase: float | None = None
        self._armed = True
        self.offset = np.zeros(2)

    def act(self, observation: np.ndarray, time: float) -> np.ndarray:
        g = self.gains
        if self.phase is None:  # the phase clock starts at the command's start, lead-in included
            self.phase = time - self.command.lead_in
        else:
            self.phase += self._dt
        ball, ball_velocity = observation[6:9], observation[9:12]
        cup, cup_velocity = observation[12:15], observation[15:18]
        height = ball[2] - cup[2]
        if self._armed and height < LOCK_HEIGHT and ball_velocity[2] < 0:
            since = (LOCK_HEIGHT - height) / max(cup_velocity[2] - ball_velocity[2], 1e-3)
            cycle = self.command.cycle
            error = (g.land_phase - (self.phase - since) + cycle / 2) % cycle - cycle / 2
            self.phase += g.phase_gain * error
            self._armed = False
        if height > LOCK_HEIGHT + LOCK_REARM:
            self._armed = True
        if height > TRACK_HEIGHT and ball_velocity[2] < TRACK_MAX_RISE:
            rise = ball_velocity[2]
            fall = max(height - LANDING_HEIGHT, 0.0)
            flight = (rise + math.sqrt(rise * rise + 2 * self._gravity * fall)) / self._gravity
            landing = ball[:2] + ball_velocity[:2] * flight
            error = landing - cup[:2] - (g.bias_x, g.bias_y)
            self.offset = np.clip(self.offset + g.land_gain * error, -MAX_OFFSET, MAX_OFFSET)
        else:
            self.offset *= g.decay
        return ctrl_to_action(self.command.cycle_setpoints(self.phase) + steer(self.offset))


def steer(offset: np.ndarray) -> np.ndarray:
    """Setpoint changes (pan, lift, elbow; rad) that move the cup by ``offset`` (x, y; m)."""
    pair = -offset[0] / PAIR_LEVER
    return np.array([-offset[1] / PAN_LEVER, pair, -pair])


# --- files ----------------------------------------------------------------------------------
def feedback_policy_from_dict(data: dict, source: str, env: gym.Env) -> FeedbackPolicy:
    """A ``FeedbackPolicy`` from a policy file's mapping; ``CommandError`` names a malformed one."""
    if set(data) != {"kind", "name", "command", "feedback"}:
        raise CommandError(f"{source}: expected the keys kind, name, command, feedback")
    command = command_from_dict(data["command"], f"{source}: command")
    gains = data["feedback"]
    if not isinstance(gains, dict) or set(gains) != set(PARAM_NAMES):
        raise CommandError(f"{source}: feedback needs exactly the keys {', '.join(PARAM_NAMES)}")
    try:
        values = FeedbackGains(**{key: float(value) for key, value in gains.items()})
    except (TypeError, ValueError) as error:
        raise CommandError(f"{source}: feedback gains must be numbers ({error})") from None
    return FeedbackPolicy(command, values, env)


def save_feedback_policy(
    path: str | Path, command: ViaPointCommand, gains: FeedbackGains, name: str
) -> Path:
    data = {"kind": KIND, "name": name, "command": command.to_dict(), "feedback": asdict(gains)}
    return write_policy_file(data, path)
