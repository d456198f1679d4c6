"""closed_loop's first 30 s at the paper preset, env seed 0, with start offsets, ball kicks and
ball-tracking noise on (so the env's random draws are covered): observations, rewards, ends,
throws and catches at every step.

data/closed_loop_30s.npz was written by this module with the one-ball env, before the env took
``balls``; tests/test_balls.py plays the episode again and checks that ``balls=1`` reproduces it
exactly. To rewrite the file (only after a deliberate change of the env's behaviour):

python tests/closed_loop_episode.py
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np

import jugglerl  # noqa: F401  (registers the id)
from jugglerl.policies.loading import load_policy
from jugglerl_envs import ENV_ID

RECORDED = Path(__file__).with_name("data") / "closed_loop_30s.npz"
STEP_KEYS = ("reward", "terminated", "truncated", "throws", "catches")


def play(**env_options) -> tuple[dict[str, np.ndarray], dict]:
    """Play the episode; return its rows (``observation`` plus ``STEP_KEYS``) and the last info."""
    env = gym.make(
        ENV_ID,
        duration=30.0,
        reward="juggle",
        reset_noise=0.01,
        ball_noise=0.001,
        kick_rate=0.5,
        kick_speed=0.02,
        **env_options,
    )
    policy = load_policy("closed_loop", env.unwrapped)
    observation, info = env.reset(seed=0)
    policy.reset()
    rows = {key: [] for key in ("observation", *STEP_KEYS)}
    rows["observation"].append(observation)
    done = False
    while not done:
        observation, reward, terminated, truncated, info = env.step(
            policy.act(observation, info["time"])
        )
        rows["observation"].append(observation)
        for key, value in zip(
            STEP_KEYS,
            (reward, terminated, truncated, info["throws"], info["catches"]),
            strict=True,
        ):
            rows[key].append(value)
        done = terminated or truncated
    env.close()
    return {key: np.asarray(values) for key, values in rows.items()}, info


if __name__ == "__main__":
    rows, info = play()
    np.savez_compressed(RECORDED, **rows)
    print(len(rows["reward"]), info["throws"], info["kicks"])
