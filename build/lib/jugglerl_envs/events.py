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

from dataclasses import dataclass

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


@dataclass
class JuggleEvents:
    """Running counts for one episode, updated once per sample (env step)."""

    threshold: float
    throws: int = 0
    catches: int = 0
    streak: int = 0
    max_streak: int = 0
    _prev_height: float = float("nan")
    _catchable: bool = False

    def reset(self, height: float, clear_of_cup: bool) -> None:
        """Start a new episode from the ball's first sample."""
        self.throws = self.catches = self.streak = self.max_streak = 0
        self._prev_height = height
        self._catchable = clear_of_cup

    def update(
        self, height: float, in_flight: bool, in_cup: bool, clear_of_cup: bool, below_cup: bool
    ) -> int:
        """Take the next sample; return the number of throws it completes (0 or 1).

        ``below_cup``: the ball is lower than the cup's throat (a missed ball, when not in the cup).
        """
        new_throw = int(crossed_upward(self._prev_height, height, in_flight, self.threshold))
        self.throws += new_throw
        if in_cup and self._catchable:
            self.catches += 1
            self.streak += 1
            self.max_streak = max(self.max_streak, self.streak)
            self._catchable = False
        elif clear_of_cup:
            self._catchable = True
            if below_cup:
                self.streak = 0
        self._prev_height = height
        return new_throw
