"""Env steps per second of ``JuggleBatch`` against bare ``mj_step`` and a ``SyncVectorEnv``.

    python scripts/benchmarks/bench_batch.py [--envs 1 64 256 1024] [--seconds 3] [--repeats 3]

Zero action at the paper preset, the ball resting in the cup (every env is stepped 100 steps
first). For each batch size it times, in this process:

- bare ``mj_step(model, data, nstep=frame_skip)`` over the batch's ``MjData`` in a Python loop, on
  one thread and on ``--threads`` threads, each copying ``qpos`` back as the batch does: the
  physics alone, the ceiling;
- ``JuggleBatch`` on one thread and on ``--threads`` threads (the whole task: actions, physics,
  events, rewards, observations, autoresets);
- the same with the training perturbations of ``algo=ppo`` (1 cm start offsets, kicks of 2 cm/s,
  white action noise 0.003, ball-tracking noise 1 mm, servo gains drawn in 0.9-1.1: one model
  per env);
- a Gymnasium ``SyncVectorEnv`` of ``JuggleEnv``s (N <= 256), the path the off-policy trainer
  collected through before ``collector.env=batch``.

Prints the median of ``--repeats`` timings of each, and each as a fraction of bare ``mj_step`` on
``--threads`` threads.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import gymnasium as gym
import mujoco
import numpy as np

from jugglerl_envs import JuggleBatch, JuggleEnv
from jugglerl_envs.batch import usable_cores

WARM_UP = 100  # env steps: the ball falls 0.5 m into the cup and settles


def perturbed(num_envs: int) -> dict:
    """The training perturbations of ``algo=ppo``, every env under all of them."""
    gains = np.random.default_rng(0).uniform(0.9, 1.1, num_envs)
    return {
        "reset_noise": 0.01,
        "kick_rate": 0.5,
        "kick_speed": 0.02,
        "action_noise": 0.003,
        "ball_noise": 0.001,
        "servo_gain": gains.tolist(),
    }


def rate(step: Callable[[], int], seconds: float) -> float:
    """Env steps per second of repeated ``step()`` calls (each returns the env steps it made)."""
    done, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        done += step()
    return done / (time.perf_counter() - start)


def bare(batch: JuggleBatch, threads: int, seconds: float) -> float:
    """``mj_step`` alone over copies of the batch's ``MjData``, ``threads`` threads."""
    datas = [mujoco.MjData(m) for m in batch.models]
    models, skip = batch.models, batch.frame_skip
    for model, source, data in zip(models, batch.datas, datas, strict=True):
        mujoco.mj_copyData(data, model, source)
    qpos = np.zeros((len(datas), models[0].nq))
    chunks = [c for c in np.array_split(np.arange(len(datas)), threads) if len(c)]

    def advance(envs: np.ndarray) -> None:
        for env in envs.tolist():
            mujoco.mj_step(models[env], datas[env], nstep=skip)
            qpos[env] = datas[env].qpos

    if threads == 1:
        return rate(lambda: advance(chunks[0]) or len(datas), seconds)
    with ThreadPoolExecutor(threads) as pool:
        return rate(lambda: list(pool.map(advance, chunks)) and len(datas), seconds)


def batched(num_envs: int, threads: int, seconds: float, **arguments) -> tuple[float, JuggleBatch]:
    batch = JuggleBatch(num_envs, threads=threads, **arguments)
    batch.reset(seed=0)
    zero = np.zeros(batch.action_space.shape)
    for _ in range(WARM_UP):
        batch.step(zero)
    steps = rate(lambda: batch.step(zero) and num_envs, seconds)
    return steps, batch


def sync_vector(num_envs: int, seconds: float) -> float:
    envs = gym.vector.SyncVectorEnv([JuggleEnv] * num_envs)
    envs.reset(seed=0)
    zero = np.zeros(envs.action_space.shape, dtype=np.float32)
    for _ in range(WARM_UP):
        envs.step(zero)
    steps = rate(lambda: envs.step(zero) and num_envs, seconds)
    envs.close()
    return steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", type=int, nargs="+", default=[1, 64, 256, 1024])
    parser.add_argument("--seconds", type=float, default=3.0, help="per timing")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--threads", type=int, default=usable_cores())
    args = parser.parse_args()

    print(f"env steps/s, zero action, paper preset; median of {args.repeats} x {args.seconds} s")
    print(f"| N | case | env steps/s | of bare mj_step, {args.threads} threads |")
    print("| --- | --- | --- | --- |")
    for n in args.envs:
        cases: dict[str, list[float]] = {}
        for _ in range(args.repeats):
            for threads in sorted({1, args.threads}):
                steps, batch = batched(n, threads, args.seconds)
                cases.setdefault(f"JuggleBatch, {threads} thread(s)", []).append(steps)
                bare_steps = bare(batch, threads, args.seconds)
                cases.setdefault(f"bare mj_step, {threads} thread(s)", []).append(bare_steps)
                batch.close()
            steps, batch = batched(n, args.threads, args.seconds, **perturbed(n))
            cases.setdefault(f"JuggleBatch perturbed, {args.threads} thread(s)", []).append(steps)
            batch.close()
            if n <= 256:
                cases.setdefault("SyncVectorEnv of JuggleEnv", []).append(
                    sync_vector(n, args.seconds)
                )
        ceiling = statistics.median(cases[f"bare mj_step, {args.threads} thread(s)"])
        for case, values in sorted(cases.items()):
            median = statistics.median(values)
            print(f"| {n} | {case} | {median:,.0f} | {median / ceiling:.2f} |")


if __name__ == "__main__":
    main()
