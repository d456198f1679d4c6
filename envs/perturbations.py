"""Disturbances that robustness tests and training apply to the juggling env (off by default).

A closed-loop policy earns its keep when the world is not as planned. Besides the ball's start
offset (``reset_noise``) and its mass and radius (env arguments), the env can

- scale the arm servos' proportional gain (``servo_gain``: 1 is nominal; below 1 the arm lags
  its setpoints and sags under load, as a worn or badly tuned drive would), and
- kick the ball in free flight (``draw_kick``): at random times, ``kick_rate`` kicks per second
  of flight on average, each a horizontal velocity change of ``kick_speed`` m/s in a uniformly
  random direction — a gust, or a throw gone slightly wrong;
- add noise to the actions (``ActionNoise``: white or temporally correlated), as an imprecise
  controller or a network imitating a teacher would;
- show the policy a tracked ball instead of the true one (``BallTracker``: position noise,
  velocities from noisy differences, latency), as a camera gives a real robot.

Each works on a batch of envs (``jugglerl_envs.batch``) with its own settings per env; the random
draws come from each env's own generator, env by env, in the order a lone env makes them, so an
env of a batch plays exactly as the same env alone.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco
import numpy as np


def scale_servo_gains(model: mujoco.MjModel, actuators: slice, gain: float) -> None:
    """Multiply the proportional gain ``kp`` of the position servos in ``actuators``.

    A MuJoCo position servo's force is ``kp (ctrl - q) - kv q̇`` (``gainprm[0] = kp``,
    ``biasprm[1] = -kp``, ``biasprm[2] = -kv``). The arm's servos are overdamped, so they follow
    a setpoint with a time constant of about ``kv / kp`` (0.2 s nominal): scaling ``kp`` alone
    (not ``kv``, which would keep that ratio) makes the arm slower by ``1 / gain``.
    """
    model.actuator_gainprm[actuators, 0] *= gain
    model.actuator_biasprm[actuators, 1] *= gain


def kick_probability(rate: float, seconds: float) -> float:
    """Chance of a kick in ``seconds`` of flight for a Poisson process of ``rate`` per second."""
    return -math.expm1(-rate * seconds)


def draw_kick(rng: np.random.Generator, probability: float, speed: float) -> np.ndarray | None:
    """The velocity change (x, y, z) of a kick in the next env step, or None (no kick)."""
    if rng.random() >= probability:
        return None
    angle = rng.uniform(0.0, 2 * math.pi)
    return np.array([math.cos(angle), math.sin(angle), 0.0]) * speed


class ActionNoise:
    """Gaussian noise of std ``sigma[i]`` (normalised action units) added to env ``i``'s actions.

    ``correlation[i]`` (s) is the time constant of the noise: 0 draws it afresh every env step
    (white); otherwise it is an AR(1) (discrete Ornstein-Uhlenbeck) process with the same
    stationary std, ``n ← a n + σ √(1 - a²) ε`` with ``a = exp(-dt / correlation)``, like the slow
    drift of a real servo's setpoint.
    """

    def __init__(self, sigma: np.ndarray, correlation: np.ndarray, dt: np.ndarray, size: int):
        self.sigma = [float(s) for s in sigma]
        decay = [math.exp(-t / c) if c > 0 else 0.0 for t, c in zip(dt, correlation, strict=True)]
        self.innovation = [s * math.sqrt(1 - a**2) for s, a in zip(self.sigma, decay, strict=True)]
        self.decay = np.array(decay)
        self.active = np.asarray(sigma) > 0
        self.value = np.zeros((len(self.sigma), size))

    def reset(self, envs: Sequence[int], rngs: Sequence[np.random.Generator]) -> None:
        """Start the noise of ``envs`` afresh (a draw from its stationary distribution)."""
        size = self.value.shape[1]
        for env in envs:
            noisy = self.active[env]
            self.value[env] = rngs[env].normal(0.0, self.sigma[env], size) if noisy else 0.0

    def draw(self, envs: np.ndarray, rngs: Sequence[np.random.Generator]) -> np.ndarray:
        """The noise of the next step of each of ``envs`` (once per step, after ``reset``)."""
        noisy = envs[self.active[envs]]
        if len(noisy):
            size = self.value.shape[1]
            innovations = np.array([rngs[e].normal(0.0, self.innovation[e], size) for e in noisy])
            self.value[noisy] = self.decay[noisy, None] * self.value[noisy] + innovations
        return self.value[envs]

    def state_dict(self) -> dict:
        return {"value": self.value.copy()}

    def load_state_dict(self, state: dict) -> None:
        self.value[:] = state["value"]


class BallTracker:
    """What a camera tracker tells the policy about the balls, instead of the simulator's state.

    Env ``i``'s ball positions carry Gaussian noise of std ``noise[i]`` (m); with noise, the
    velocities are the finite differences of those noisy positions over the control period
    ``dt[i]`` (what a tracker running at the control rate, 50 Hz by default, gives), not the true
    ones; and the whole ball observation arrives ``latency[i]`` env steps late. With no noise and
    no latency it is the true state. Balls are tracked alike, each with its own history.
    """

    def __init__(self, noise: np.ndarray, latency: np.ndarray, dt: np.ndarray, balls: int):
        self.noise = [float(n) for n in noise]
        self.latency = np.asarray(latency, dtype=int)
        self.dt = np.asarray(dt, dtype=np.float64)
        self.active = (np.asarray(noise) > 0) | (self.latency > 0)
        envs = len(self.noise)
        depth = int(self.latency.max(initial=0)) + 1
        #: the last ``depth`` observations of each env's balls, oldest first
        self.history = np.zeros((envs, balls, depth, 6))
        self.last_position = np.zeros((envs, balls, 3))

    def _seen(self, env: int, positions: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Env ``env``'s ball positions ``[balls, 3]`` as its tracker measures them."""
        if self.noise[env] == 0:
            return positions
        return np.stack([p + rng.normal(0.0, self.noise[env], size=3) for p in positions])

    def reset(self, envs, positions, velocities, rngs) -> np.ndarray:
        """Start ``envs`` from the true first state (``positions``, ``velocities``:
        ``[len(envs), balls, 3]``); return what is seen, ``[len(envs), balls, 6]``."""
        seen = np.array([self._seen(e, p, rngs[e]) for e, p in zip(envs, positions, strict=True)])
        first = np.concatenate([seen, velocities], axis=-1)
        self.last_position[envs] = seen
        self.history[envs] = first[:, :, None, :]
        return first

    def observe(self, envs, positions, velocities, rngs) -> np.ndarray:
        """The ball observations ``[len(envs), balls, 6]`` of ``envs`` after a step."""
        seen = np.array([self._seen(e, p, rngs[e]) for e, p in zip(envs, positions, strict=True)])
        noisy = np.array([self.noise[e] > 0 for e in envs], dtype=bool)
        if noisy.any():
            rows = np.asarray(envs)[noisy]
            velocities = velocities.copy()
            velocities[noisy] = (seen[noisy] - self.last_position[rows]) / self.dt[rows, None, None]
            self.last_position[rows] = seen[noisy]
        history = self.history[envs]
        history[:, :, :-1] = history[:, :, 1:]
        history[:, :, -1] = np.concatenate([seen, velocities], axis=-1)
        self.history[envs] = history
        depth = self.history.shape[2]
        return history[np.arange(len(envs)), :, depth - 1 - self.latency[envs]]

    def state_dict(self) -> dict:
        return {"history": self.history.copy(), "last_position": self.last_position.copy()}

    def load_state_dict(self, state: dict) -> None:
        self.history[:] = state["history"]
        self.last_position[:] = state["last_position"]
