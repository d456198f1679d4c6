"""What recording to rerun costs: an evaluation episode's wall time and size, a metrics call.

    python scripts/benchmarks/bench_recording.py [--policy expert] [--repeats 5] [--scene-fps 50]

Runs the same 120 s episode of the policy (paper preset) without and with an ``EpisodeRecorder``
logging into a ``RerunLogger`` file, alternating the two, and prints the medians and the recorded
file's size. Then times ``RerunLogger.log_metrics`` with 8 scalars (what a training iteration
logs), sends and file writes included. Last line: the episode recording overhead in per cent.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

from jugglerl.policies.episodes import run_episode
from jugglerl.policies.loading import load_policy
from jugglerl.recording.episode import EpisodeRecorder
from jugglerl.recording.logger import RerunLogger
from jugglerl_envs import JuggleEnv


def timed_episode(env, policy) -> float:
    start = time.perf_counter()
    run_episode(env, policy, seed=0)
    return time.perf_counter() - start


def recorded_episode(env, policy, folder: Path, scene_fps: float) -> tuple[float, int]:
    """Wall time of one recorded episode, including closing the file; and the file's bytes."""
    start = time.perf_counter()
    with RerunLogger("episode", folder) as logger:
        run_episode(EpisodeRecorder(env, logger.recording, scene_fps=scene_fps), policy, seed=0)
    return time.perf_counter() - start, logger.path.stat().st_size


def metrics_call_seconds(folder: Path, calls: int = 20000) -> float:
    """Wall time of one ``log_metrics`` call of 8 scalars, amortising sends and shutdown."""
    names = [f"train/metric_{k}" for k in range(8)]
    start = time.perf_counter()
    with RerunLogger("metrics", folder, flush_every=2.0) as logger:
        for step in range(calls):
            logger.log_metrics(dict.fromkeys(names, float(step)), step=step)
    return (time.perf_counter() - start) / calls


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--policy", default="expert")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--scene-fps", type=float, default=50.0)
    args = parser.parse_args()

    env = JuggleEnv()
    policy = load_policy(args.policy, env)
    plain, recorded, sizes = [], [], []
    with tempfile.TemporaryDirectory() as folder:
        timed_episode(env, policy)  # warm-up: caches, first-call costs
        for _ in range(args.repeats):
            plain.append(timed_episode(env, policy))
            wall, size = recorded_episode(env, policy, Path(folder), args.scene_fps)
            recorded.append(wall)
            sizes.append(size)
        metrics_call = metrics_call_seconds(Path(folder))
    plain_s, recorded_s = statistics.median(plain), statistics.median(recorded)
    print(f"policy {args.policy}, 120 s episode, median of {args.repeats}")
    print(f"plain episode     {plain_s:.3f} s")
    print(f"recorded episode  {recorded_s:.3f} s (scene at {args.scene_fps:g} Hz)")
    print(f"recording size    {max(sizes) / 1e6:.2f} MB")
    print(f"log_metrics, 8 scalars: {metrics_call * 1e6:.1f} µs a call")
    print(f"recording overhead {100 * (recorded_s / plain_s - 1):.1f} %")


if __name__ == "__main__":
    main()
