"""Env steps per second with the ball in flight and resting in the cup.

    python scripts/benchmarks/bench_env.py [--frame-skip 10] [--steps 20000] [--repeats 3]

Prints the median of ``--repeats`` timings for each case, for the bare ``JuggleEnv`` and for
``gymnasium.make`` (which adds Gymnasium's checking wrappers).
"""

from __future__ import annotations

import argparse
import statistics
import time
from functools import partial

import gymnasium as gym

import jugglerl  # noqa: F401  (registers the id)
from jugglerl_envs import ENV_ID, JuggleEnv

FLIGHT_DROP = 2.0  # m: the ball falls freely for ~1.4 s at g = -2
FLIGHT_STEPS = 60  # steps per episode of free fall (1.2 s at 50 Hz), before it reaches the cup


def steps_per_second(env: gym.Env, steps: int, in_flight: bool) -> float:
    """Time ``steps`` env steps holding the home pose; in flight, reset before the ball lands."""
    base = env.unwrapped
    hold = base.ctrl_to_action(base.home)
    env.reset(seed=0)
    if not in_flight:  # let the ball land and settle first
        for _ in range(100):
            info = env.step(hold)[-1]
        assert info["in_cup"], "the ball did not settle in the cup"
    elapsed, done = 0.0, 0
    while done < steps:
        chunk = FLIGHT_STEPS if in_flight else steps - done
        start = time.perf_counter()
        for _ in range(chunk):
            env.step(hold)
        elapsed += time.perf_counter() - start
        done += chunk
        if in_flight:
            assert base.batch.in_flight[0, 0]
            env.reset()
    return done / elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frame-skip", type=int, default=10)
    parser.add_argument("--steps", type=int, default=20000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()

    print(f"frame_skip={args.frame_skip}, {args.steps} steps, median of {args.repeats}")
    for label, make in [("JuggleEnv", JuggleEnv), ("gymnasium.make", partial(gym.make, ENV_ID))]:
        for case, in_flight in [("in flight", True), ("in cup", False)]:
            drop = FLIGHT_DROP if in_flight else 0.5
            env = make(frame_skip=args.frame_skip, drop_height=drop, duration=1e5)
            rates = [steps_per_second(env, args.steps, in_flight) for _ in range(args.repeats)]
            physics = statistics.median(rates) * args.frame_skip
            print(
                f"{label:15s} {case:10s} {statistics.median(rates):9.0f} env steps/s"
                f"  ({physics:,.0f} physics steps/s)"
            )
            env.close()


if __name__ == "__main__":
    main()
