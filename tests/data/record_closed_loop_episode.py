"""Record closed_loop's first 30 s at the paper preset, env seed 0, with start offsets, ball
kicks and ball-tracking noise on (so the env's random draws are covered): observations, rewards,
ends, throws. closed_loop_30s.npz was written by this script with the one-ball env, before the
env took ``balls``; tests/test_balls.py checks that ``balls=1`` still plays it back exactly.

python tests/data/record_closed_loop_episode.py
"""

from pathlib import Path

import gymnasium as gym
import numpy as np

import jugglerl  # noqa: F401  (registers the id)
from jugglerl.policies.loading import load_policy

env = gym.make(
    "JuggleRL/Juggle-v0",
    duration=30.0,
    reward="juggle",
    reset_noise=0.01,
    ball_noise=0.001,
    kick_rate=0.5,
    kick_speed=0.02,
)
policy = load_policy("closed_loop", env.unwrapped)
obs, info = env.reset(seed=0)
policy.reset()
rows = dict(observation=[obs], reward=[], terminated=[], truncated=[], throws=[], catches=[])
done = False
while not done:
    obs, r, term, trunc, info = env.step(policy.act(obs, info["time"]))
    rows["observation"].append(obs)
    rows["reward"].append(r)
    rows["terminated"].append(term)
    rows["truncated"].append(trunc)
    rows["throws"].append(info["throws"])
    rows["catches"].append(info["catches"])
    done = term or trunc
np.savez_compressed(
    Path(__file__).with_name("closed_loop_30s.npz"), **{k: np.asarray(v) for k, v in rows.items()}
)
print(len(rows["reward"]), info["throws"], info["kicks"])
