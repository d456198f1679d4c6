"""Run one episode of a policy in the juggling env and summarise it as the metrics we report."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import gymnasium as gym
import numpy as np

from jugglerl.policies import Policy


@dataclass
class EpisodeMetrics:
    """What one episode achieved. Times in seconds of simulated time."""

    throws: int
    catches: int
    max_consecutive_catches: int
    time_to_drop: float | None  # None when the ball was never dropped
    duration: float  # simulated seconds the episode lasted
    seed: int | None
    physics_error: str = ""
    max_cup_height: float = 0.0  # m, the cup's throat at its highest
    peak_joint_speed: tuple[float, ...] = ()  # rad/s, per actuated joint
    throws_per_ball: tuple[int, ...] = ()  # in the env's ball order; sums to ``throws``
    max_balls_in_cup: int = 0  # the most balls inside the cup at once (several share it: > 1)

    def to_dict(self) -> dict:
        return asdict(self)

    def scalars(self) -> dict[str, float]:
        """The numeric metrics, for loggers; ``time_to_drop`` only when the ball was dropped."""
        values = {
            "throws": self.throws,
            "catches": self.catches,
            "max_consecutive_catches": self.max_consecutive_catches,
            "duration": self.duration,
            "max_cup_height": self.max_cup_height,
        }
        if self.time_to_drop is not None:
            values["time_to_drop"] = self.time_to_drop
        return {key: float(value) for key, value in values.items()}


def run_episode(env: gym.Env, policy: Policy, seed: int | None = None) -> EpisodeMetrics:
    """Reset ``env`` with ``seed`` and step ``policy`` until the episode ends."""
    observation, info = env.reset(seed=seed)
    policy.reset()
    terminated = truncated = False
    while not (terminated or truncated):
        action = policy.act(observation, info["time"])
        observation, _, terminated, truncated, info = env.step(action)
    return episode_metrics(info, terminated, seed)


def episode_metrics(info: dict, terminated: bool, seed: int | None) -> EpisodeMetrics:
    """The metrics of an episode that ended (``terminated``, or else at its time limit) with
    the env's ``info``."""
    dropped = terminated and not info["physics_error"]
    return EpisodeMetrics(
        throws=int(info["throws"]),
        catches=int(info["catches"]),
        max_consecutive_catches=int(info["max_consecutive_catches"]),
        time_to_drop=round(info["time"], 6) if dropped else None,
        duration=round(info["time"], 6),
        seed=seed,
        physics_error=info["physics_error"],
        max_cup_height=round(info["max_cup_height"], 6),
        peak_joint_speed=tuple(round(float(v), 6) for v in info["peak_joint_speed"]),
        throws_per_ball=tuple(int(n) for n in info["throws_per_ball"]),
        max_balls_in_cup=int(info["max_balls_in_cup"]),
    )


def caught(metrics: EpisodeMetrics, catch_time: float) -> bool:
    """The ball was caught and stayed up (in the cup or juggled) for ``catch_time`` seconds."""
    return metrics.catches >= 1 and metrics.duration >= catch_time


#: The keys of ``summarise_episodes``.
SUMMARY_KEYS = ("catch_rate", "mean_throws", "mean_catches", "mean_time_to_drop")


def summarise_episodes(episodes: list[EpisodeMetrics], catch_time: float) -> dict[str, float]:
    """``catch_rate`` (fraction ``caught``), ``mean_throws``, ``mean_catches`` and
    ``mean_time_to_drop`` (s; an episode that kept the ball counts its full duration)."""
    return {
        "catch_rate": float(np.mean([caught(m, catch_time) for m in episodes])),
        "mean_throws": float(np.mean([m.throws for m in episodes])),
        "mean_catches": float(np.mean([m.catches for m in episodes])),
        "mean_time_to_drop": float(np.mean([m.duration for m in episodes])),
    }
