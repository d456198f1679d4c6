"""A closed-loop juggler for fast flights: throw from rest, catch where the ball comes down, carry
it back.

Why: at real gravity (``env=earth``) with the UR5e's speed limit of π rad/s, no throw of the
three actuated joints goes straight up high enough (the elbow alone flicks too slowly; shoulder
and elbow together give the ball a sideways speed too), so the ball comes down some 0.4 m from
where it left. A cyclic command cannot meet it there by timing alone; this policy does not cycle
but reacts to the ball, in four modes:

- **settle**: hold the pose until the ball has rested in the cup for ``settle`` seconds (within
  ``REST_RADIUS`` of the cone's axis, ``REST_HEIGHT`` of its throat, its velocity relative to the
  cup, smoothed over a few steps by ``SLOSH_FILTER``, below ``REST_SPEED``), so a sloshing ball
  does not start a throw. At the ``rest`` pose, with every joint within ``POSE_TOLERANCE`` of it,
  throw; elsewhere (the env's home, at the start), carry the ball to ``rest`` first;
- **throw**: step the lift and elbow setpoints through ``knots`` (each ``[duration s, lift rad,
  elbow rad]`` held for its duration; the env's rate limit, if any, turns the jumps into ramps).
  If the ball has not left after the knots and ``THROW_TIMEOUT``, carry back. With an ``apex``
  (m), the throw holds its height: after a caught flight that topped out below ``apex``, the next
  throws push one control step longer (the second-to-last knot: the last one brakes); after one
  that topped out more than ``APEX_BAND`` above it, one step shorter; at most ``MAX_PUSH_STEPS``
  either way. A weaker arm lags its setpoints more and throws lower (``earth_juggler``: 1.02 m
  at the servos' nominal kp, 0.94 m at 0.95 × kp, under the 1 m a throw must reach), and a
  longer push makes that up. Whole steps, because a knot's end acts only at a control step;
- **catch**: once the ball is ``CLEAR_HEIGHT`` above the throat and the cup has stopped rising
  (switching earlier lets the follow-through lift the cup higher), predict where the ball's
  ballistic flight crosses ``catch_height`` (the env's gravity; while the ball is clear of the
  cup, its horizontal course is a line fitted to the positions seen, ``jugglerl.policies.
  flight_fit``, which averages a tracker's noise away) and put the cup's throat there by inverse
  kinematics (``jugglerl.policies.cup_ik``: pan, lift and elbow; the wrist stays locked),
  re-predicted every step;
- **carry**: once the ball has rested ``CAUGHT_REST`` seconds in the cup, move the setpoints to
  ``rest`` along a smoothstep over ``carry`` seconds, then settle.

A throw is repeatable because it starts from a settled ball; a catch forgives because the cup
goes where the ball is.

**Low gravity** (the paper preset, g = -2 m/s²): the ball sits loosely in the cone and bounces
out of a tilted one. With ``level`` (rad) the catch holds lift + elbow at that sum, which keeps
the cup's tilt (upright, for the paper's wrist lock, at 0.429), and places only the throat's
horizontal position (its height is where that pose puts it); once the ball is down in the cup the
cup stays where it is, where a bouncing ball comes back down, rather than following it. With
``still`` (s) the arm holds still at ``rest`` that long before a throw, so that a ball carried
there stops rolling first.

**Several balls** (``env.balls`` > 1, with ``lead``): the cup deals with one ball at a time,
holding, throwing, catching or carrying it; every other ball is in flight. A held ball is thrown
once the next ball down is at most ``lead`` seconds from its catch, so the throws alternate, each
landing timing the throw of the other. The throw hands the catch to the ball that comes down
first, and the cup must be empty when it arrives: a ball caught but not yet back at rest when the
next one is due is thrown from where it is, the knots shifted by the setpoints' offset from
``rest``. The episode starts in catch (the second ball is only 0.9 s behind the first at the
paper preset: no time to settle at home first). With one ball, or without ``lead``, the rules
above are the one-ball rules, and ``earth_juggler`` plays exactly as before.

The throw's knots assume the wrist lock they were made with, so the env's ``wrist_angles`` must
be the policy's (a one-line error otherwise). A policy file is YAML of ``kind: throw_catch`` with
the ``ThrowCatch`` fields and, optionally, ``env``: the env preset it was made for
(``configs/env/``), which that error names, and ``balls``, the number it juggles, which the env
must then have. Shipped: ``earth_expert`` (made by hand) and ``earth_juggler`` (searched from it
by ``algo=throw_catch``), both ``env: earth``; ``two_balls_throw`` (``env: paper``, two balls;
searched from ``two_balls_throw_start``).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import gymnasium as gym
import numpy as np

from jugglerl.commands import CommandError
from jugglerl.policies.cup_ik import CupIK
from jugglerl.policies.flight_fit import FlightFit
from jugglerl.runs.policy_files import check_balls, write_policy_file
from jugglerl_envs.actions import ctrl_to_action

KIND = "throw_catch"
#: m: a ball centred within this of the cone's axis ...
REST_RADIUS = 0.02
#: m: ... and at most this far above the throat rests in the cup (it sits ≈ 0.04 m above it).
REST_HEIGHT = 0.06
#: m/s: ... and moves with the cup slower than this, smoothed (1 mm of tracking noise makes the
#: ball's differenced velocity ≈ 0.07 m/s noisy per axis, half that once smoothed).
REST_SPEED = 0.25
#: per step, how far the filtered relative velocity moves towards the latest (a tracker's noise
#: on it shrinks to a half: sloshing still shows, 2 mm of tracking noise no longer does).
SLOSH_FILTER = 0.4
#: rad: a throw starts only once every actuated joint is this close to its rest angle.
POSE_TOLERANCE = 0.1
#: m above the throat at which a rising ball has left the cup.
CLEAR_HEIGHT = 0.12
#: m: the ball's centre above the throat when caught (what the landing prediction aims at).
SEAT_HEIGHT = 0.04
#: per sample, the weight old flight samples keep in the fit (50 Hz: a memory of ≈ 0.4 s), so a
#: kicked ball's new course takes over.
FLIGHT_FORGET = 0.95
#: s a caught ball rests in the cup before it is carried back.
CAUGHT_REST = 0.1
#: s after the last knot ends that a ball still in the cup counts as a failed throw.
THROW_TIMEOUT = 0.5
#: m above ``apex`` that a flight may top out before the push shortens: more than one control
#: step of push adds (``earth_juggler``: 0.1-0.13 m at 0.9-1.05 × the servos' kp), so that
#: a throw held just over ``apex`` stays there.
APEX_BAND = 0.2
#: control steps the push may lengthen or shorten: 3 more lift ``earth_juggler``'s cup to about
#: 0.74 m (the limit is 0.76) and its joints to 2.9 rad/s, and its catches start to miss.
MAX_PUSH_STEPS = 2


@dataclass(frozen=True)
class ThrowCatch:
    """The parameters of a ``ThrowCatchPolicy``. Angles in radians, times in seconds, heights in
    metres."""

    rest: tuple[float, float, float]  # pan, lift, elbow: where the ball settles before a throw
    wrist_angles: tuple[float, float, float]  # the env's wrist lock the throw was made for
    knots: tuple[tuple[float, float, float], ...]  # the throw: [duration, lift, elbow] each
    catch_height: float  # the throat's height at the catch
    settle: float  # rest of the ball in the cup before each throw
    carry: float  # duration of the move from the catch back to rest
    apex: float | None = None  # the flight's top the throw holds (ball centre, m); None: open loop
    lead: float | None = None  # s before the next ball's catch a held ball is thrown (balls > 1)
    level: float | None = None  # rad: lift + elbow held at the catch (None: the catch may tilt)
    still: float | None = None  # s the arm holds still at rest before a throw (None: no wait)

    def __post_init__(self):
        for name in ("rest", "wrist_angles"):
            value = getattr(self, name)
            if len(value) != 3 or not np.isfinite(value).all():
                raise CommandError(f"{name} must be 3 finite angles (rad)")
        knots = np.asarray(self.knots, dtype=float)
        if knots.ndim != 2 or knots.shape[1] != 3 or not np.isfinite(knots).all():
            raise CommandError("knots must be a non-empty list of [duration, lift, elbow]")
        if (knots[:, 0] <= 0).any():
            raise CommandError("every knot's duration must be > 0 s")
        for name in ("catch_height", "settle", "carry"):
            if not math.isfinite(getattr(self, name)) or getattr(self, name) <= 0:
                raise CommandError(f"{name} must be a positive number")
        if self.apex is not None:
            if not math.isfinite(self.apex) or self.apex <= 0:
                raise CommandError("apex must be a positive height (m) or absent")
            if len(knots) < 2:
                raise CommandError("apex needs a throw of at least 2 knots (push, then brake)")
        if self.lead is not None and not (math.isfinite(self.lead) and self.lead > 0):
            raise CommandError("lead must be a positive number of seconds or absent")
        if self.level is not None and not math.isfinite(self.level):
            raise CommandError("level must be an angle (rad) or absent")
        if self.still is not None and not (math.isfinite(self.still) and self.still >= 0):
            raise CommandError("still must be a number of seconds >= 0 or absent")


FIELD_NAMES = tuple(f.name for f in fields(ThrowCatch))
#: the fields a policy may leave out (``None``: not used)
OPTIONAL_FIELDS = tuple(f.name for f in fields(ThrowCatch) if f.default is None)
#: the fields that are one number each
SCALAR_KEYS = ("catch_height", "settle", "carry", *OPTIONAL_FIELDS)
#: what a file may leave out: ``env``, ``balls`` and the optional fields
OPTIONAL_KEYS = ("env", "balls", *OPTIONAL_FIELDS)


class ThrowCatchPolicy:
    """Plays ``params`` (see the module docstring) in envs like ``env``, whose control period,
    gravity, start pose and wrist lock it reads (it keeps no reference to the env)."""

    def __init__(
        self, params: ThrowCatch, env: gym.Env, name: str = KIND, preset: str | None = None
    ):
        unwrapped = env.unwrapped
        if not np.allclose(params.wrist_angles, unwrapped.wrist_angles, atol=1e-6):
            where = f"env={preset}" if preset else "the env it was made for"
            raise CommandError(
                f"policy {name} throws with wrist_angles={list(params.wrist_angles)} but the env"
                f" locks them at {np.round(unwrapped.wrist_angles, 6).tolist()}: run it in {where}"
            )
        self.params = params
        self._dt = unwrapped.dt
        self._gravity = -unwrapped.gravity
        self._rest = np.asarray(params.rest, dtype=float)
        self._home = np.array(unwrapped.home, dtype=float)
        self._knots = np.asarray(params.knots, dtype=float)
        self._ik = CupIK(params.wrist_angles)
        self._balls = [unwrapped.ball_slice(ball) for ball in range(unwrapped.balls)]
        self._flights = [FlightFit(FLIGHT_FORGET) for _ in self._balls]
        self.reset()

    def reset(self) -> None:
        self.mode = "catch" if len(self._balls) > 1 else "settle"
        self._clock = 0.0  # s in the current mode
        self._flight_clock = 0.0  # s since the flight fits were last reset
        for flight in self._flights:
            flight.reset()
        self._ball = 0  # the ball the cup deals with: held, thrown, caught or carried
        balls = len(self._balls)
        self._rested = np.zeros(balls)  # s each ball has rested in the cup without a break
        self._slosh = np.zeros((balls, 3))  # m/s, each ball relative to the cup, filtered
        self._target = self._home.copy()  # setpoints (pan, lift, elbow), rad
        self._carry_from = self._home.copy()
        self._shift = np.zeros(3)  # rad: the setpoints' offset from rest where the throw began
        self._set_push(0)
        self._top = np.full(balls, -math.inf)  # m: each ball's highest in its current flight

    def act(self, observation: np.ndarray, time: float) -> np.ndarray:
        cup, cup_velocity = observation[12:15], observation[15:18]
        seen = [observation[where] for where in self._balls]  # position, velocity per ball
        flying = [state[2] - cup[2] > CLEAR_HEIGHT for state in seen]
        for ball, state in enumerate(seen):
            relative = state[:3] - cup
            self._slosh[ball] += SLOSH_FILTER * (state[3:] - cup_velocity - self._slosh[ball])
            resting = (
                math.hypot(relative[0], relative[1]) < REST_RADIUS
                and 0.0 < relative[2] < REST_HEIGHT
                and np.linalg.norm(self._slosh[ball]) < REST_SPEED
            )
            self._rested[ball] = self._rested[ball] + self._dt if resting else 0.0
        self._clock += self._dt
        self._flight_clock += self._dt
        coming = self._next_catch(seen, flying)
        due = coming <= (self.params.lead if self.params.lead is not None else -math.inf)
        if self.mode in ("catch", "carry") and due and self._rested[self._ball] >= CAUGHT_REST:
            self._switch("throw")  # from where it is: the next ball must find the cup empty
        if self.mode == "settle" and self._rested[self._ball] >= self.params.settle:
            if not np.array_equal(self._target, self._rest):
                self._switch("carry")
            elif (
                np.abs(observation[:3] - self._rest).max() < POSE_TOLERANCE
                and self._clock >= (self.params.still or 0.0)
                and (due or self.params.lead is None or coming == math.inf)
            ):
                self._switch("throw")
        if self.mode == "throw":
            knot = np.searchsorted(self._knot_ends, self._clock, side="right")
            lift, elbow = self._knots[min(knot, len(self._knots) - 1), 1:]
            self._target = np.array([self._rest[0], lift, elbow]) + self._shift
            if flying[self._ball] and cup_velocity[2] <= 0.0:
                self._switch("catch")
                self._target = self._rest.copy()  # the IK's first guess: the throw ends far off
                self._top[self._ball] = -math.inf
                self._ball = min(  # the next ball down: the one thrown, if no other flies
                    (ball for ball in range(len(seen)) if flying[ball]),
                    key=lambda ball: self._landing(seen[ball], None)[0],
                )
                for flight in self._flights:
                    flight.reset()
                self._flight_clock = 0.0
            elif self._clock > self._knot_ends[-1] + THROW_TIMEOUT:
                self._switch("carry")
        for ball, state in enumerate(seen):
            if flying[ball]:
                self._flights[ball].add(self._flight_clock, state[:2])
                self._top[ball] = max(self._top[ball], float(state[2]))
        if self.mode == "catch" and (flying[self._ball] or self.params.level is None):
            fit = self._flights[self._ball] if flying[self._ball] else None
            _, landing = self._landing(seen[self._ball], fit)
            self._target = self._ik.solve(landing, self._target, self.params.level)
        if self.mode == "catch" and self._rested[self._ball] >= CAUGHT_REST:
            self._hold_apex()
            self._switch("carry")
        if self.mode == "carry":
            s = min(self._clock / self.params.carry, 1.0)
            s = s * s * (3.0 - 2.0 * s)
            self._target = self._carry_from + s * (self._rest - self._carry_from)
            if s >= 1.0:
                self._target = self._rest.copy()
                self._switch("settle")
        return ctrl_to_action(self._target)

    def _next_catch(self, seen: list[np.ndarray], flying: list[bool]) -> float:
        """s until the next ball in flight, other than the one the cup deals with, comes down to
        ``catch_height`` (inf if none flies)."""
        return min(
            (
                self._landing(state, None)[0]
                for ball, state in enumerate(seen)
                if ball != self._ball and flying[ball]
            ),
            default=math.inf,
        )

    def _hold_apex(self) -> None:
        """Lengthen the next throws' push by a control step if the last flight topped out below
        ``apex``, shorten it if above ``apex + APEX_BAND``."""
        apex = self.params.apex
        top = float(self._top[self._ball])
        if apex is None or not math.isfinite(top):
            return
        step = (top < apex) - (top > apex + APEX_BAND)
        self._set_push(int(np.clip(self.push_steps + step, -MAX_PUSH_STEPS, MAX_PUSH_STEPS)))

    def _set_push(self, steps: int) -> None:
        """Add ``steps`` control steps to the throw's push (the second-to-last knot) and time
        the knots' ends from that."""
        self.push_steps = steps
        durations = self._knots[:, 0].copy()
        if steps:  # only with an apex, which needs a push and a brake
            durations[-2] += steps * self._dt
        self._knot_ends = np.cumsum(durations)

    def _switch(self, mode: str) -> None:
        if mode == "carry":
            self._carry_from = self._target.copy()
        if mode == "throw":  # the knots, made for rest, shifted to where the throw starts
            self._shift = self._target - self._rest
        self.mode = mode
        self._clock = 0.0

    def _landing(self, ball: np.ndarray, fit: FlightFit | None) -> tuple[float, np.ndarray]:
        """(s until, where: m, world frame) the throat must be for ``ball`` (its observed position
        and velocity), in ballistic flight, to come down into it at ``catch_height``; its
        horizontal course from ``fit``, the line fitted to its flight, if given, else from the
        latest sample (as it lands: the cup then follows the ball in)."""
        drop = max(ball[2] - self.params.catch_height - SEAT_HEIGHT, 0.0)
        rise = ball[5]
        flight = (rise + math.sqrt(rise * rise + 2.0 * self._gravity * drop)) / self._gravity
        position, course = ball[:2], ball[3:5]
        if fit is not None:
            position, course = fit.state(self._flight_clock, position, course)
        x, y = position + course * flight
        return flight, np.array([x, y, self.params.catch_height])


# --- files ----------------------------------------------------------------------------------
def throw_catch_from_dict(data: dict, source: str) -> ThrowCatch:
    """The ``ThrowCatch`` of a policy file's mapping; ``CommandError`` names a malformed one."""
    expected = {"kind", "name", *FIELD_NAMES} - set(OPTIONAL_KEYS)
    if not expected <= set(data) <= expected | set(OPTIONAL_KEYS):
        raise CommandError(
            f"{source}: expected the keys {', '.join(sorted(expected))} (and optionally"
            f" {', '.join(OPTIONAL_KEYS)})"
        )
    values = {}
    for key in FIELD_NAMES:
        if data.get(key) is None and key in OPTIONAL_KEYS:
            continue
        try:
            values[key] = np.asarray(data[key], dtype=float)
        except (TypeError, ValueError):
            raise CommandError(f"{source}: {key} must be numbers, not {data[key]!r}") from None
    try:
        return ThrowCatch(
            rest=tuple(values["rest"].ravel().tolist()),
            wrist_angles=tuple(values["wrist_angles"].ravel().tolist()),
            knots=tuple(map(tuple, np.atleast_2d(values["knots"]).tolist())),
            **{key: float(values[key]) for key in SCALAR_KEYS if key in values},
        )
    except (TypeError, ValueError) as error:
        raise CommandError(f"{source}: {error}") from None


def throw_catch_policy_from_dict(data: dict, source: str, env: gym.Env) -> ThrowCatchPolicy:
    """A ``ThrowCatchPolicy`` from a policy file's mapping; ``CommandError`` names a malformed
    one, ``PolicyFileError`` one that states ``balls`` other than the env's."""
    params = throw_catch_from_dict(data, source)
    check_balls(data, env.unwrapped.balls)
    return ThrowCatchPolicy(params, env, str(data["name"]), data.get("env"))


def save_throw_catch_policy(
    path: str | Path, params: ThrowCatch, name: str, balls: int = 1
) -> Path:
    """Write a throw_catch policy file; ``balls`` > 1 is stated in it (``balls: N``)."""
    data = {"kind": KIND, "name": name, **asdict(params)}
    for key in OPTIONAL_FIELDS:
        if data[key] is None:
            del data[key]
    if balls > 1:
        data["balls"] = balls
    data["knots"] = [list(knot) for knot in params.knots]
    for key in ("rest", "wrist_angles"):
        data[key] = list(data[key])
    return write_policy_file(data, path)
