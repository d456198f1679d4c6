"""Summarise DDPG runs as a Markdown table: one row per reward and actor.

    python scripts/train.py -m reward=distance,contacts,throws actor=mlp,lstm
    python scripts/ddpg_table.py outputs/train/ddpg/multirun/<date_time>

Reads every DDPG ``metrics.json`` below the folder and reports each run's final evaluation
(``eval.seeds`` deterministic episodes of ``env.duration`` from the standard start): catch rate
(the ball caught and kept up for ``eval.catch_time``), mean throws, mean time the ball stayed up,
and the run's frames and wall time. Runs of the same reward and actor (seeds) are averaged.
"""

from __future__ import annotations

import statistics
from collections import defaultdict
from pathlib import Path

from jugglerl.ddpg.actors import ACTORS
from jugglerl.ddpg.training import METRICS
from jugglerl.run_tables import markdown_table, run_metrics, table_main
from jugglerl_envs.juggle import REWARDS


def load_runs(folder: Path) -> dict[tuple[str, str], list[dict]]:
    runs = defaultdict(list)
    for metrics in run_metrics(folder, METRICS):
        if "final_evaluation" in metrics:  # DDPG runs only
            runs[metrics["reward"], metrics["actor"]].append(metrics)
    return runs


def table(runs: dict[tuple[str, str], list[dict]]) -> str:
    header = [
        "reward",
        "actor",
        "seeds",
        "catch rate",
        "mean throws",
        "ball up (s)",
        "frames",
        "wall (min)",
    ]
    rows = []
    order = sorted(runs, key=lambda key: (REWARDS.index(key[0]), ACTORS.index(key[1])))
    for reward, actor in order:
        group = sorted(runs[reward, actor], key=lambda r: r["seed"])
        finals = [r["final_evaluation"] for r in group]
        episodes = sum(len(f["episodes"]) for f in finals)
        cells = [
            f"`{reward}`",
            f"`{actor}`",
            ",".join(str(r["seed"]) for r in group),
            f"{statistics.mean(f['catch_rate'] for f in finals):.0%} (of {episodes})",
            f"{statistics.mean(f['mean_throws'] for f in finals):.1f}",
            f"{statistics.mean(f['mean_time_to_drop'] for f in finals):.1f}"
            f" of {finals[0]['duration']:g}",
            f"{group[0]['frames']:,}",
            f"{statistics.mean(r['wall_seconds'] for r in group) / 60:.1f}",
        ]
        rows.append(cells)
    return markdown_table(header, rows)


if __name__ == "__main__":
    table_main(__doc__, load_runs, table, f"DDPG {METRICS}")
