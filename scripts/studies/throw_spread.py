"""How far a policy's throws scatter sideways, and how much of it the cup's own motion sets.

    python scripts/studies/throw_spread.py [--policy two_balls] [--balls 2] \
        [--action-noise 0,0.003] [--seeds 10] [--duration 120]

A ball thrown sideways lands away from where it left: at the paper's gravity a two-ball flight
lasts ≈ 1.7 s, so 0.1 m/s sideways is 0.17 m at the catch. For every throw (the ball crossing the
threshold in free flight) this records the ball's horizontal velocity, the same as when it left
the cup, and the cup's horizontal velocity at the control step the ball rose ``CLEAR_HEIGHT``
above its throat. Per action-noise level, over ``--seeds`` episodes (env seeds 0 on): the throws,
the spread (std) of the balls' x and y speeds and of the cup's x speed, the correlation of the
ball's x speed with the cup's, and for each episode that dropped a ball the x speed of that
ball's last throw.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from jugglerl.commands import CommandError
from jugglerl.policies.loading import load_policy
from jugglerl_envs import JuggleEnv

#: m above the cup's throat at which a rising ball has left it (as the feedback policy's tracking).
CLEAR_HEIGHT = 0.12


def throw_velocities(
    env: JuggleEnv, policy, seed: int
) -> tuple[np.ndarray, np.ndarray, float | None]:
    """One episode: per throw, the ball's (x, y) speed and the cup's (x, y) speed as it cleared
    the cup (``[throws, 2]`` each), and if a ball was dropped, the x speed of its last throw."""
    observation, info = env.reset(seed=seed)
    policy.reset()
    balls = [env.ball_slice(ball) for ball in range(env.balls)]
    counted = [0] * env.balls
    clearing_cup = [np.zeros(2)] * env.balls
    ball_speeds, cup_speeds = [], []
    last_throw: list[float | None] = [None] * env.balls
    done = False
    while not done:
        below = [observation[seen][2] - observation[14] < CLEAR_HEIGHT for seen in balls]
        action = policy.act(observation, info["time"])
        observation, _, terminated, truncated, info = env.step(action)
        done = terminated or truncated
        for ball, seen in enumerate(balls):
            if below[ball] and observation[seen][2] - observation[14] >= CLEAR_HEIGHT:
                clearing_cup[ball] = observation[15:17].copy()
            if info["throws_per_ball"][ball] > counted[ball]:
                counted[ball] = info["throws_per_ball"][ball]
                ball_speeds.append(observation[seen][3:5].copy())
                cup_speeds.append(clearing_cup[ball])
                last_throw[ball] = float(observation[seen][3])
    dropped = None
    if terminated and not info["physics_error"]:
        dropped = last_throw[int(np.argmin([observation[seen][2] for seen in balls]))]
    return np.reshape(ball_speeds, (-1, 2)), np.reshape(cup_speeds, (-1, 2)), dropped


def noise_levels(text: str) -> list[float]:
    try:
        return [float(value) for value in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r}: expected numbers separated by commas"
        ) from None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--policy", default="two_balls", help="a policy: name or file")
    parser.add_argument("--balls", type=int, default=2)
    parser.add_argument("--action-noise", type=noise_levels, default=noise_levels("0,0.003"))
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--duration", type=float, default=120.0)
    args = parser.parse_args()
    if args.seeds < 1:
        parser.error("--seeds must be at least 1")

    print(f"{args.policy}, {args.balls} ball(s), {args.duration:g} s, env seeds 0-{args.seeds - 1}")
    print(
        f"{'noise':>6} {'throws':>7} {'ball x std':>10} {'ball y std':>10} {'cup x std':>9}"
        f" {'corr x':>6}  x speeds of the dropped balls' last throws"
    )
    for noise in args.action_noise:
        env = JuggleEnv(balls=args.balls, duration=args.duration, action_noise=noise)
        try:
            policy = load_policy(args.policy, env)
        except (CommandError, ValueError) as error:
            sys.exit(f"throw_spread.py: {error}")
        episodes = [throw_velocities(env, policy, seed) for seed in range(args.seeds)]
        ball = np.concatenate([speeds for speeds, _, _ in episodes])
        cup = np.concatenate([speeds for _, speeds, _ in episodes])
        drops = [f"{x:+.2f}" for *_, x in episodes if x is not None]
        correlation = np.corrcoef(ball[:, 0], cup[:, 0])[0, 1] if len(ball) > 1 else np.nan
        spread = ball.std(axis=0)
        print(
            f"{noise:6.3f} {len(ball) / args.seeds:7.1f} {spread[0]:10.3f} {spread[1]:10.3f}"
            f" {cup[:, 0].std():9.3f} {correlation:6.2f}  {' '.join(drops) or '-'}"
        )
        env.close()


if __name__ == "__main__":
    main()
