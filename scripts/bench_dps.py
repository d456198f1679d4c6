"""Roll-out throughput of DPS's command evaluation against a bare ``mujoco.rollout``.

    python scripts/bench_dps.py [--commands 16] [--duration 120] [--threads 2] [--repeats 3]

Samples commands around the expert from DPS's search distribution (the paper's stds), then times,
on the same model, start states, controls and thread count:
- bare: one ``mujoco.rollout`` call on precomputed controls, nothing else;
- ours: ``CommandRollouts.evaluate`` (controls built, roll-outs, throws counted).
Prints physics steps/s of each (median of ``--repeats``) and, last, the ratio ours / bare.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import mujoco
import numpy as np
from mujoco import rollout

from jugglerl.dps.distribution import sample_commands
from jugglerl.dps.params import ViaPointConstraints
from jugglerl.dps.rollouts import CommandRollouts
from jugglerl.policies.command import load_command
from jugglerl_envs import JuggleEnv


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--commands", type=int, default=16)
    parser.add_argument("--duration", type=float, default=120.0)
    parser.add_argument("--threads", type=int, default=os.cpu_count())
    parser.add_argument("--repeats", type=int, default=3)
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


if __name__ == "__main__":
    main()
