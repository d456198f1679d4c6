"""Roll-out throughput of DPS's command evaluation against a bare ``mujoco.rollout``.

    python scripts/benchmarks/bench_dps.py [--commands 16] [--duration 120] [--threads 2] \
        [--repeats 3]
    python scripts/benchmarks/bench_dps.py --ray HEAD:6379 [--chunk 1]   # also as Ray tasks

Samples commands around the expert from DPS's search distribution (the paper's stds), then times,
on the same model, start states, controls and thread count:
- bare: one ``mujoco.rollout`` call on precomputed controls, nothing else;
- ours: ``CommandRollouts.evaluate`` (controls built, roll-outs, throws counted).
Prints physics steps/s of each (median of ``--repeats``) and the ratio ours / bare. With
``--ray ADDRESS`` (``local``: Ray started in this process) it then times the same roll-outs as
Ray tasks of ``--chunk`` commands (``ClusterCommandRollouts``, what ``cluster=ray`` runs; after
one untimed round, in which the workers start and build their envs), checks they throw the
same, and prints their rate, the ratio Ray / ours and Ray's cost per task (no-op tasks, in
CPU-ms: wall time x the cluster's CPUs / tasks).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import mujoco
import numpy as np
from mujoco import rollout
from omegaconf import OmegaConf

from jugglerl.cluster import open_cluster
from jugglerl.commands import load_command
from jugglerl.dps.cluster_rollouts import ClusterCommandRollouts
from jugglerl.dps.distribution import sample_commands
from jugglerl.dps.params import ViaPointConstraints
from jugglerl.dps.rollouts import CommandRollouts
from jugglerl_envs import JuggleEnv


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--commands", type=int, default=16)
    parser.add_argument("--duration", type=float, default=120.0)
    parser.add_argument("--threads", type=int, default=os.cpu_count())
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--ray", metavar="ADDRESS", help="also time them on this Ray cluster")
    parser.add_argument("--chunk", type=int, default=1, help="commands per Ray task")
    parser.add_argument("--noop-tasks", type=int, default=200, help="tasks timing Ray's cost")
    args = parser.parse_args()

    env = JuggleEnv(duration=args.duration)
    constraints = ViaPointConstraints.from_model(env.model, 1.0, 5.0, 0.1)
    commands = sample_commands(load_command("expert"), args.commands, constraints, seed=0)
    with CommandRollouts(env, nthread=args.threads) as ours:
        state, warmstart = ours.start_state(seed=0)
        controls = ours.controls(commands)
        steps = controls.shape[0] * controls.shape[1]
        datas = [mujoco.MjData(env.model) for _ in range(args.threads)]
        bare_times, our_times = [], []
        with rollout.Rollout(nthread=args.threads) as bare:
            for _ in range(args.repeats):
                start = time.perf_counter()
                bare.rollout(
                    [env.model] * len(commands),
                    datas,
                    initial_state=np.tile(state, (len(commands), 1)),
                    control=controls,
                    initial_warmstart=np.tile(warmstart, (len(commands), 1)),
                )
                bare_times.append(time.perf_counter() - start)
                start = time.perf_counter()
                results = ours.evaluate(commands, seeds=0)
                our_times.append(time.perf_counter() - start)
    bare_rate = steps / statistics.median(bare_times)
    our_rate = steps / statistics.median(our_times)
    print(
        f"{len(commands)} commands x {args.duration:g} s, {args.threads} threads, "
        f"median of {args.repeats}; throws: {sorted(results.throws.tolist())}"
    )
    print(f"bare mujoco.rollout  {bare_rate / 1e3:8.1f} k physics steps/s")
    print(f"CommandRollouts      {our_rate / 1e3:8.1f} k physics steps/s")
    print(f"ratio ours / bare    {our_rate / bare_rate:.3f}")
    if args.ray:
        time_on_ray(args, commands, steps, our_rate, results.throws)


def echo(items: list) -> list:
    return items


def time_on_ray(args, commands, steps: int, our_rate: float, throws: np.ndarray) -> None:
    """The same roll-outs as Ray tasks; their rate against ``our_rate`` and Ray's cost per task."""
    import ray

    cfg = {"name": "ray", "address": args.ray, "chunk": args.chunk, "cpus_per_task": 1}
    cluster = open_cluster(OmegaConf.create(cfg))
    cpus = ray.cluster_resources()["CPU"]
    with ClusterCommandRollouts({"duration": args.duration}, cluster) as remote:
        same = np.array_equal(remote.evaluate(commands, seeds=0).throws, throws)  # warm-up
        times = []
        for _ in range(args.repeats):
            start = time.perf_counter()
            remote.evaluate(commands, seeds=0)
            times.append(time.perf_counter() - start)
        start = time.perf_counter()
        list(cluster.map(echo, list(range(args.noop_tasks))))
        per_task = (time.perf_counter() - start) * cpus / -(-args.noop_tasks // args.chunk)
    ray_rate = steps / statistics.median(times)
    print(
        f"Ray tasks ({cpus:g} CPUs, {args.chunk} per task) {ray_rate / 1e3:8.1f} k physics"
        f" steps/s; same throws as here: {same}"
    )
    print(f"Ray cost per task    {per_task * 1e3:.2f} CPU-ms")
    print(f"ratio Ray / ours     {ray_rate / our_rate:.3f}")


if __name__ == "__main__":
    main()
