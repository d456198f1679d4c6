"""Compare two policies start by start, from robustness benchmarks run on the same starts.

    python scripts/robustness.py 'policies=[A,B]' seeds=30 ... hydra.run.dir=RUN
    python scripts/compare_starts.py RUN A RUN B
    python scripts/compare_starts.py RUN_A A RUN_B B   # each measured in its own benchmark

Each benchmark is a ``robustness.json`` or the folder holding it; each policy is named as the
benchmark names it. Prints, per condition both measured, the mean throws of each, the mean
difference A - B with its standard error, on how many starts A threw more, fewer or as many, and
how many episodes each ended by a drop. See ``jugglerl.reports.paired``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from jugglerl.reports.paired import markdown, pair, read_benchmark


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("benchmark_a", type=Path)
    parser.add_argument("policy_a")
    parser.add_argument("benchmark_b", type=Path)
    parser.add_argument("policy_b")
    args = parser.parse_args()
    try:
        a, b = read_benchmark(args.benchmark_a), read_benchmark(args.benchmark_b)
        pairs = pair(a, args.policy_a, b, args.policy_b)
    except ValueError as error:
        sys.exit(f"error: {error}")
    print(markdown(pairs, args.policy_a, args.policy_b))


if __name__ == "__main__":
    main()
