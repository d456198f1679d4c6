"""Disturbances the robustness benchmark applies to the juggling env (all off by default).

A closed-loop policy earns its keep when the world is not as planned. Besides the ball's start
offset (``reset_noise``) and its mass and radius (env arguments), the env can

- scale the arm servos' proportional gain (``servo_gain``: 1 is nominal; below 1 the arm lags
  its setpoints and sags under load, as a worn or badly tuned drive would), and
- kick the ball in free flight (``BallKicks``): at random times, ``rate`` kicks per second of
  flight on average, each a horizontal velocity change of ``speed`` m/s in a uniformly random
  direction — a gust, or a throw gone slightly wrong;
- add noise to the actions (``ActionNoise``: white or temporally correlated), as an imprecise
  controller or a network imitating a teacher would;
- show the policy a tracked ball instead of the true one (``BallTracker``: position noise,
  velocities from noisy differences, latency), as a camera gives a real robot.
"""

from __future__ import annotations

import math

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


class BallKicks:
    """Random horizontal velocity kicks of ``speed`` m/s, ``rate`` per second of free flight."""

    def __init__(self, rate: float, speed: float):
        self.rate = rate
        self.speed = speed

    @property
    def active(self) -> bool:
        return self.rate > 0 and self.speed > 0

    def draw(self, rng: np.random.Generator, seconds: float) -> np.ndarray | None:
        """The velocity change (x, y, z) of a kick in the next ``seconds`` of flight, or None.

        A Poisson process of ``rate``: a kick happens with probability ``1 - exp(-rate dt)``.
        """
        if not self.active or rng.random() >= -math.expm1(-self.rate * seconds):
            return None
        angle = rng.uniform(0.0, 2 * math.pi)
        return np.array([math.cos(angle), math.sin(angle), 0.0]) * self.speed


class ActionNoise:
    """Gaussian noise of std ``sigma`` (normalised action units) added to every action.

    ``correlation`` (s) is the time constant of the noise: 0 draws it afresh every env step
    (white); otherwise it is an AR(1) (discrete Ornstein-Uhlenbeck) process with the same
    stationary std, ``n ← a n + σ √(1 - a²) ε`` with ``a = exp(-dt / correlation)``, like the slow
    drift of a real servo's setpoint.
    """

    def __init__(self, sigma: float, correlation: float, dt: float, size: int = 3):
        self.sigma = sigma
        self.decay = math.exp(-dt / correlation) if correlation > 0 else 0.0
        self.size = size  # the action's length
        self.value = np.zeros(size)

    @property
    def active(self) -> bool:
        return self.sigma > 0

    def reset(self, rng: np.random.Generator) -> None:
        self.value = (
            rng.normal(0.0, self.sigma, size=self.size) if self.active else np.zeros(self.size)
        )

    def draw(self, rng: np.random.Generator) -> np.ndarray:
        """The noise of the next step (call once per step, after ``reset``)."""
        if not self.active:
            return self.value
        innovation = rng.normal(0.0, self.sigma * math.sqrt(1 - self.decay**2), size=self.size)
        self.value = self.decay * self.value + innovation
        return self.value


class BallTracker:
    """What a camera tracker tells the policy about the ball, instead of the simulator's state.

    Positions carry Gaussian noise of std ``noise`` (m); with noise, the velocities are the finite
    differences of those noisy positions over the control period (what a tracker running at the
    control rate, 50 Hz by default, gives), not the true ones; and the whole ball observation
    arrives ``latency`` env steps late. With ``noise = 0`` and ``latency = 0`` it is the true state.
    """

    def __init__(self, noise: float, latency: int, dt: float):
        self.noise = noise
        self.latency = latency
        self.dt = dt
        self._history: list[np.ndarray] = []
        self._last_position = np.zeros(3)

    @property
    def active(self) -> bool:
        return self.noise > 0 or self.latency > 0

    def reset(self, position: np.ndarray, velocity: np.ndarray, rng: np.random.Generator):
        """Start from the true first state (the ball at rest over the cup); return what is seen."""
        seen = position + rng.normal(0.0, self.noise, size=3) if self.noise > 0 else position
        self._last_position = seen
        first = np.concatenate([seen, velocity])
        self._history = [first] * (self.latency + 1)
        return first

    def observe(self, position: np.ndarray, velocity: np.ndarray, rng: np.random.Generator):
        """The ball observation (position, velocity; 6 values) after a step."""
        if self.noise > 0:
            seen = position + rng.normal(0.0, self.noise, size=3)
            velocity = (seen - self._last_position) / self.dt
            self._last_position = seen
            position = seen
        self._history.append(np.concatenate([position, velocity]))
        self._history.pop(0)
        return self._history[0]
