"""Summarise DPS runs as a Markdown table: one row per update rule, medians over seeds.

    python scripts/train.py -m algo.update=greedy,weighted,elite,ereps seed=0,1,2
    python scripts/dps_table.py outputs/train/dps/multirun/<date_time>

Reads every ``metrics.json`` below the folder. Columns: seeds, best throws (median and per
seed), roll-outs to the first command with >= 39 and >= 60 throws (median over the seeds that got
there, and how many did), and the best command's mean fraction of its throws kept with start
noise (the run's ``noise_check``).
"""

from __future__ import annotations

import statistics
from collections import defaultdict
from pathlib import Path

from jugglerl.dps.training import METRICS, MILESTONES
from jugglerl.dps.updates import UPDATES
from jugglerl.run_tables import markdown_table, run_metrics, table_main


def load_runs(folder: Path) -> dict[str, list[dict]]:
    runs = defaultdict(list)
    for metrics in run_metrics(folder, METRICS):
        if "update" in metrics:  # DPS runs only
            runs[metrics["update"]].append(metrics)
    return runs


def milestone_cell(runs: list[dict], throws: int) -> str:
    reached = [r["first_rollout_with"][str(throws)] for r in runs]
    reached = [n for n in reached if n is not None]
    if not reached:
        return f"— (0/{len(runs)})"
    return f"{statistics.median(reached):g} ({len(reached)}/{len(runs)})"


def table(runs: dict[str, list[dict]]) -> str:
    header = ["update", "seeds", "best throws: median (per seed)"]
    header += [f"roll-outs to {n}" for n in MILESTONES] + ["kept with start noise"]
    rows = []
    for update in sorted(runs, key=lambda name: UPDATES.index(name)):
        group = sorted(runs[update], key=lambda r: r["seed"])
        best = [r["best_throws"] for r in group]
        kept = [r["noise_check"]["fraction_of_best"] for r in group if "noise_check" in r]
        cells = [
            f"`{update}`",
            ",".join(str(r["seed"]) for r in group),
            f"{statistics.median(best):g} ({', '.join(map(str, best))})",
            *[milestone_cell(group, n) for n in MILESTONES],
            f"{statistics.mean(kept):.0%}" if kept else "—",
        ]
        rows.append(cells)
    return markdown_table(header, rows)


if __name__ == "__main__":
    table_main(__doc__, load_runs, table, f"DPS {METRICS}")
