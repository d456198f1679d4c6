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
  the command moves by ``land_gain`` × the error each step, up to ``max_offset``. The pan joint
  moves the cup sideways (y); the shoulder lift and elbow turned by opposite angles move it
  along x without tilting it. Between flights the offset decays by ``decay`` per step, back to
  the command.
- **Centring in the cup** (``hold_gain``, ``hold_damping``; 0 unless a policy sets them). At the
  paper's gravity the ball sits loosely in the cone: the arm's small jitter rolls it off-centre,
  and a ball thrown off-centre leaves sideways. While a ball sits in the cup the offset also
  moves by ``hold_gain`` × the ball's horizontal offset from the aim point and ``hold_damping``
  × its horizontal velocity relative to the cup, so the cup follows the rolling ball and damps
  it before the throw.

**Several balls** (``env.balls`` > 1): each ball locks the phase as it comes down, so a command
whose cycle is one throw alternates the balls, the one landing setting the clock for the throw of
the next. The cup tracks the ball that lands soonest, and only while no ball sits in it (at most
``TRACK_HEIGHT`` above the throat): a held ball is thrown from the command's path (moved only by
the centring gains), not from a cup already moving toward the next catch. With one ball this is the
one-ball rule above.

The four gains and the aim point ``(bias_x, bias_y)`` form the parameter vector ``θ`` that
``algo=feedback`` (the search space ``jugglerl.dps.spaces.feedback_gains``) searches;
``max_offset`` (default ``MAX_OFFSET``) and the centring gains are the policy's own settings
(``FIXED_NAMES``), not searched: the searches keep their start's. This module needs no
torch. A policy file is YAML of ``kind: feedback``: ``name``, ``command`` (a command mapping),
``feedback`` (the gains by name, ``FIXED_NAMES`` optional) and optionally ``balls``, the number of
balls it juggles, which the env must then have (searches write it when ``env.balls`` > 1).
Shipped: ``closed_loop_gains`` (gains searched for ``dps_best``), ``closed_loop_tolerant`` and
``closed_loop`` (command and gains searched together, ``algo=closed_loop``, under growing
imprecision), ``closed_loop_centred`` (``closed_loop`` centring the ball it holds), and
``two_balls_searched`` (the same search with two balls, from ``two_balls_start``, centring too)
and ``two_balls`` (searched from it under more action noise).
"""

from __future__ import annotations

import math
from dataclasses import asdict, astuple, dataclass, fields
from pathlib import Path

import gymnasium as gym
import numpy as np

from jugglerl.commands import CommandError, ViaPointCommand, command_from_dict
from jugglerl.runs.policy_files import check_balls, write_policy_file
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
#: m, largest horizontal offset of the cup from the command unless a policy sets its own.
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
    max_offset: float = MAX_OFFSET  # m, largest horizontal offset of the cup
    hold_gain: float = 0.0  # per env step, fraction of a held ball's offset from the aim point
    hold_damping: float = 0.0  # s, times its velocity relative to the cup: both add to the offset


#: The policy's own settings, which the searches keep from their start.
FIXED_NAMES = ("max_offset", "hold_gain", "hold_damping")
#: The searched gains: ``θ`` of the feedback spaces (every field but ``FIXED_NAMES``).
PARAM_NAMES = tuple(f.name for f in fields(FeedbackGains) if f.name not in FIXED_NAMES)


class FeedbackPolicy:
    """Plays ``command`` closed loop with ``gains`` (see the module docstring) in envs like
    ``env``, whose control period and gravity it reads (it keeps no reference to the env)."""

    def __init__(self, command: ViaPointCommand, gains: FeedbackGains, env: gym.Env):
        self.command = command
        self.gains = gains
        unwrapped = env.unwrapped
        self._dt = unwrapped.dt
        self._gravity = -unwrapped.gravity
        self._balls = [unwrapped.ball_slice(ball) for ball in range(unwrapped.balls)]
        self.reset()

    def reset(self) -> None:
        self.phase: float | None = None
        self._armed = [True] * len(self._balls)
        self.offset = np.zeros(2)

    def act(self, observation: np.ndarray, time: float) -> np.ndarray:
        if self.phase is None:  # the phase clock starts at the command's start, lead-in included
            self.phase = time - self.command.lead_in
        else:
            self.phase += self._dt
        cup, cup_velocity = observation[12:15], observation[15:18]
        held = None  # (position, velocity) of the first ball sitting in the cup
        soonest = None  # (flight time, landing point) of the ball that lands first
        for ball, seen in enumerate(self._balls):
            position, velocity = observation[seen][:3], observation[seen][3:]
            height = position[2] - cup[2]
            self._lock_phase(ball, height, velocity[2], cup_velocity[2])
            if height <= TRACK_HEIGHT:
                if held is None:
                    held = (position, velocity)
            elif velocity[2] < TRACK_MAX_RISE:
                landing = self._landing(position, velocity, height)
                if soonest is None or landing[0] < soonest[0]:
                    soonest = landing
        g = self.gains
        aim = (g.bias_x, g.bias_y)
        if soonest is not None and held is None:
            step = g.land_gain * (soonest[1] - cup[:2] - aim)
            self.offset = np.clip(self.offset + step, -g.max_offset, g.max_offset)
        elif held is not None:
            position, velocity = held
            step = g.hold_gain * (position[:2] - cup[:2] - aim)
            step += g.hold_damping * (velocity[:2] - cup_velocity[:2])
            self.offset = np.clip(g.decay * self.offset + step, -g.max_offset, g.max_offset)
        else:
            self.offset *= g.decay
        return ctrl_to_action(self.command.cycle_setpoints(self.phase) + steer(self.offset))

    def _lock_phase(self, ball: int, height: float, rise: float, cup_rise: float) -> None:
        """Pull the phase clock toward ``land_phase`` as ``ball`` (``height`` above the cup,
        rising at ``rise`` m/s, the cup at ``cup_rise``) falls through ``LOCK_HEIGHT``, at the
        moment within the step it did so."""
        if self._armed[ball] and height < LOCK_HEIGHT and rise < 0:
            since = (LOCK_HEIGHT - height) / max(cup_rise - rise, 1e-3)
            cycle = self.command.cycle
            error = (self.gains.land_phase - (self.phase - since) + cycle / 2) % cycle - cycle / 2
            self.phase += self.gains.phase_gain * error
            self._armed[ball] = False
        if height > LOCK_HEIGHT + LOCK_REARM:
            self._armed[ball] = True

    def _landing(
        self, position: np.ndarray, velocity: np.ndarray, height: float
    ) -> tuple[float, np.ndarray]:
        """(s until the ball, ``height`` above the cup, comes down to ``LANDING_HEIGHT``; where it
        is then, horizontally), for ballistic flight under the env's gravity."""
        rise = velocity[2]
        fall = max(height - LANDING_HEIGHT, 0.0)
        flight = (rise + math.sqrt(rise * rise + 2 * self._gravity * fall)) / self._gravity
        return flight, position[:2] + velocity[:2] * flight


def steer(offset: np.ndarray) -> np.ndarray:
    """Setpoint changes (pan, lift, elbow; rad) that move the cup by ``offset`` (x, y; m)."""
    pair = -offset[0] / PAIR_LEVER
    return np.array([-offset[1] / PAN_LEVER, pair, -pair])


# --- files ----------------------------------------------------------------------------------
def feedback_policy_from_dict(data: dict, source: str, env: gym.Env) -> FeedbackPolicy:
    """A ``FeedbackPolicy`` from a policy file's mapping; ``CommandError`` names a malformed one,
    or one that states ``balls`` (the number it juggles) other than the env's."""
    required = {"kind", "name", "command", "feedback"}
    if not required <= set(data) <= required | {"balls"}:
        raise CommandError(
            f"{source}: expected the keys kind, name, command, feedback (and optionally balls)"
        )
    check_balls(data, env.unwrapped.balls)
    command = command_from_dict(data["command"], f"{source}: command")
    gains = data["feedback"]
    allowed = {*PARAM_NAMES, *FIXED_NAMES}
    if not isinstance(gains, dict) or not set(PARAM_NAMES) <= set(gains) <= allowed:
        raise CommandError(
            f"{source}: feedback needs exactly the keys {', '.join(PARAM_NAMES)} (and optionally"
            f" {', '.join(FIXED_NAMES)})"
        )
    try:
        values = FeedbackGains(**{key: float(value) for key, value in gains.items()})
    except (TypeError, ValueError) as error:
        raise CommandError(f"{source}: feedback gains must be numbers ({error})") from None
    if not 0 < values.max_offset < math.inf:
        raise CommandError(f"{source}: feedback max_offset must be a positive number of metres")
    if not all(map(math.isfinite, astuple(values))):
        raise CommandError(f"{source}: feedback gains must be finite numbers")
    return FeedbackPolicy(command, values, env)


def save_feedback_policy(
    path: str | Path, command: ViaPointCommand, gains: FeedbackGains, name: str, balls: int = 1
) -> Path:
    """Write a feedback policy file; ``balls`` > 1 is stated in it (``balls: N``)."""
    data = {"kind": KIND, "name": name, "command": command.to_dict(), "feedback": asdict(gains)}
    if balls > 1:
        data["balls"] = balls
    return write_policy_file(data, path)
