"""Milliseconds per step of a deployed network: ``ActorPolicy`` and its exported file.

    python scripts/benchmarks/bench_actor.py [--policies lstm_centred ppo_juggler mlp]
                                             [--batch 256] [--steps 2000] [--repeats 3]

For each policy (a shipped actor name, or ``mlp``: an untrained actor of ``configs/actor/mlp.yaml``
on ``algo=ddpg``'s state, the size the off-policy algorithms train), on one torch thread:

- ``ActorPolicy.act`` on one env, fed the observations and times of a 20-s episode of the
  policy itself (``--steps`` steps, the episode replayed as often as needed);
- the same ``DeployedActor`` traced to TorchScript (what ``scripts/export_policy.py`` writes);
- ``ActorPolicy.act`` on a batch of ``--batch`` envs, each row a different moment of the episode.

Prints the median of ``--repeats`` timings, in ms per call. The env's own step is not timed.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np
import torch
from hydra import compose, initialize_config_dir

from jugglerl.networks.actors import ACTION_SIZE, build_actor
from jugglerl.policies.actor import ActorPolicy
from jugglerl.policies.actor_file import read_actor_weights
from jugglerl.policies.export import trace
from jugglerl.state.transforms import normalised_size, state_size
from jugglerl_envs import JuggleEnv

EPISODE = 20.0  # s of observations to replay


def untrained_mlp() -> ActorPolicy:
    configs = Path(__file__).resolve().parents[2] / "configs"
    with initialize_config_dir(str(configs), version_base="1.3"):
        cfg = compose("train", overrides=["algo=ddpg", "actor=mlp"])
    actor = build_actor(cfg.actor, state_size(cfg.state), ACTION_SIZE)
    size = normalised_size(cfg.state)
    norm = {"loc": torch.zeros(size), "scale": torch.ones(size)}
    return ActorPolicy.from_config(cfg, actor.state_dict(), norm)


def policy_named(name: str) -> ActorPolicy:
    return untrained_mlp() if name == "mlp" else ActorPolicy.from_state(read_actor_weights(name))


def episode(policy: ActorPolicy) -> tuple[np.ndarray, np.ndarray]:
    """Observations ``[T, obs]`` and times ``[T]`` of one episode of ``policy``."""
    env = JuggleEnv(duration=EPISODE)
    observation, info = env.reset(seed=0)
    policy.reset()
    observations, times = [], []
    done = False
    while not done:
        observations.append(observation)
        times.append(info["time"])
        observation, _, terminated, truncated, info = env.step(policy.act(observation, times[-1]))
        done = terminated or truncated
    return np.array(observations), np.array(times)


def ms_per_call(call, calls: int, repeats: int) -> float:
    timings = []
    for _ in range(repeats):
        start = time.perf_counter()
        for index in range(calls):
            call(index)
        timings.append((time.perf_counter() - start) / calls * 1e3)
    return statistics.median(timings)


def timings(policy: ActorPolicy, batch: int, calls: int, repeats: int) -> list[float]:
    """ms per call: ``policy`` on one env, its traced file on one env, ``policy`` on ``batch``."""
    observations, times = episode(policy)
    steps = len(times)

    def one(index: int) -> None:
        if index % steps == 0:
            policy.reset()
        policy.act(observations[index % steps], times[index % steps])

    exported = trace(policy.deployed)
    rows_observed = torch.as_tensor(observations)[:, None]
    rows_timed = torch.as_tensor(times)[:, None]
    memory = torch.zeros(1, int(exported.memory_size), dtype=torch.float64)

    def one_exported(index: int) -> None:
        nonlocal memory
        step = index % steps
        with torch.inference_mode():
            _, memory = exported(rows_observed[step], rows_timed[step], memory)

    moments = np.linspace(0, steps - 1, batch).astype(int)

    def many(_: int) -> None:
        policy.act(observations[moments], times[moments])

    single = ms_per_call(one, calls, repeats)
    traced = ms_per_call(one_exported, calls, repeats)
    policy.reset()
    return [single, traced, ms_per_call(many, max(calls // 10, 10), repeats)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--policies", nargs="+", default=["lstm_centred", "ppo_juggler", "mlp"])
    parser.add_argument("--batch", type=int, default=256)
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    torch.set_num_threads(1)
    print(f"ms per call, one torch thread, median of {args.repeats}")
    print(f"{'policy':<14} {'ActorPolicy':>12} {'exported':>10} {f'batch {args.batch}':>10}")
    for name in args.policies:
        single, traced, batch = timings(policy_named(name), args.batch, args.steps, args.repeats)
        print(f"{name:<14} {single:>12.3f} {traced:>10.3f} {batch:>10.3f}")


if __name__ == "__main__":
    main()
