"""What counts as a throw and a catch.

One definition, shared by the env, batched roll-outs and recorders.

A **throw** is the ball crossing the height threshold going up *in free flight*: between two
consecutive samples its height goes from below the threshold to at or above it, and at the later
sample it touches nothing. A ball carried over the line in the cup is in contact, so it never
counts, and the reward cannot be farmed by lifting the ball.

The contact flag is MuJoCo's ``ball_contact`` sensor, which is evaluated at the start of the
physics step that produced the sample (2 ms stale at the default timestep). The env and the
batched roll-outs read the same sensor the same way, so they agree.

A **catch** is the ball entering the cup's cone (the volume inside the plates) after having been
clear of it (more than a ball radius outside), so a ball sloshing up to the rim is not caught
twice. A streak of catches ends when the ball, out of the cup, falls below the cup's throat: it was
missed, even if it later bounces back in.
"""

from __future__ import annotations

import numpy as np


def crossed_upward(prev_height, height, in_flight, threshold: float):
    """Elementwise: does the ball cross ``threshold`` going up in free flight between two samples?

    Works on scalars and on arrays of any matching shape (e.g. a batch of whole trajectories,
    with ``prev_height = heights[..., :-1]``, ``height = heights[..., 1:]``).
    """
    return (prev_height < threshold) & (height >= threshold) & in_flight


def count_throws(heights: np.ndarray, in_flight: np.ndarray, threshold: float) -> np.ndarray:
    """Number of throws along the last axis of sampled ball ``heights`` (metres).

    ``in_flight[..., k]`` says whether sample ``k`` has no ball contact. Sample 0 is the start
    state, which cannot complete a crossing.
    """
    crossings = crossed_upward(heights[..., :-1], heights[..., 1:], in_flight[..., 1:], threshold)
    return crossings.sum(axis=-1)


class JuggleEvents:
    """Running counts of ``[envs, balls]`` episodes, updated once per sample (env step).

    ``throws``, ``catches``, ``streak`` (the catches of a ball since it was last missed) and
    ``max_streak`` are integer arrays of that shape; ``threshold`` (m) is one per env.
    """

    def __init__(self, threshold: np.ndarray, balls: int):
        envs = len(threshold)
        self.threshold = np.asarray(threshold, dtype=np.float64)[:, None]
        self.throws = np.zeros((envs, balls), dtype=np.int64)
        self.catches = np.zeros((envs, balls), dtype=np.int64)
        self.streak = np.zeros((envs, balls), dtype=np.int64)
        self.max_streak = np.zeros((envs, balls), dtype=np.int64)
        self._prev_height = np.full((envs, balls), np.nan)
        self._catchable = np.zeros((envs, balls), dtype=bool)

    def reset(self, envs: np.ndarray, heights: np.ndarray, clear_of_cup: np.ndarray) -> None:
        """Start episodes of ``envs`` from their balls' first samples (``[len(envs), balls]``)."""
        for counts in (self.throws, self.catches, self.streak, self.max_streak):
            counts[envs] = 0
        self._prev_height[envs] = heights
        self._catchable[envs] = clear_of_cup

    def update(
        self,
        envs: np.ndarray,
        heights: np.ndarray,
        in_flight: np.ndarray,
        in_cup: np.ndarray,
        clear_of_cup: np.ndarray,
        below_cup: np.ndarray,
    ) -> np.ndarray:
        """Take the next sample of ``envs`` (each argument ``[len(envs), balls]``); return the
        throws it completes per ball (0 or 1).

        ``below_cup``: a ball is lower than the cup's throat (a missed ball, when not in the cup).
        """
        new_throws = crossed_upward(
            self._prev_height[envs], heights, in_flight, self.threshold[envs]
        ).astype(np.int64)
        self.throws[envs] += new_throws
        catchable = self._catchable[envs]
        caught = in_cup & catchable
        streak = self.streak[envs] + caught
        missed = ~caught & clear_of_cup & below_cup
        streak[missed] = 0
        self.catches[envs] += caught
        self.max_streak[envs] = np.maximum(self.max_streak[envs], streak)
        self.streak[envs] = streak
        self._catchable[envs] = np.where(caught, False, catchable | clear_of_cup)
        self._prev_height[envs] = heights
        return new_throws

    def state_dict(self) -> dict:
        names = ("throws", "catches", "streak", "max_streak", "_prev_height", "_catchable")
        return {name: getattr(self, name).copy() for name in names}

    def load_state_dict(self, state: dict) -> None:
        for name, value in state.items():
            getattr(self, name)[:] = value
