"""``FlightFit``: the ball's horizontal position and velocity in flight, fitted to every sample.

In free flight the ball's horizontal velocity is constant, so its horizontal positions lie on a
line in time. A tracked ball's velocity is a difference of noisy positions (``ball_noise``: 1 mm
over a 20 ms step is ≈ 0.07 m/s of noise), and a landing point predicted from it over a flight
of a second misses by centimetres; a least-squares line through all the positions seen since
the ball left the cup averages that noise away (its error shrinks with the number of samples).
``forget`` (per sample, 1 = never) discounts old samples, so that a kicked ball's new course
takes over.
"""

from __future__ import annotations

import numpy as np


class FlightFit:
    """Weighted least-squares line ``position = a + b t`` through horizontal samples."""

    def __init__(self, forget: float = 1.0):
        self.forget = forget
        self.reset()

    def reset(self) -> None:
        self._weight = self._t = self._tt = 0.0
        self._x = np.zeros(2)
        self._tx = np.zeros(2)

    def add(self, time: float, position: np.ndarray) -> None:
        """One sample: ``time`` (s) and the horizontal position (x, y; m)."""
        f = self.forget
        self._weight = f * self._weight + 1.0
        self._t = f * self._t + time
        self._tt = f * self._tt + time * time
        self._x = f * self._x + position
        self._tx = f * self._tx + time * position

    def state(self, time: float, position: np.ndarray, velocity: np.ndarray) -> tuple:
        """(position, velocity) at ``time`` from the line; the sample given (the latest) until
        the samples span a time."""
        spread = self._weight * self._tt - self._t * self._t
        if spread <= 1e-12 * max(self._weight, 1.0) ** 2:
            return position, velocity
        slope = (self._weight * self._tx - self._t * self._x) / spread
        intercept = (self._x - slope * self._t) / self._weight
        return intercept + slope * time, slope
