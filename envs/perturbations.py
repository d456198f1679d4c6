"""Disturbances the robustness benchmark applies to the juggling env (all off by default).

A closed-loop policy earns its keep when the world is not as planned. Besides the ball's start
offset (``reset_noise``) and its mass and radius (env arguments), the env can

- scale the arm servos' proportional gain (``servo_gain``: 1 is nominal; below 1 the arm lags
  its setpoints and sags under load, as a worn or badly tuned drive would), and
- kick the ball in free flight (``BallKicks``): at random times, ``rate`` kicks per second of
  flight on average, each a horizontal velocity change of ``speed`` m/s in a uniformly random
  direction — a gust, or a throw gone slightly wrong.
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
