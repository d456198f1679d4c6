"""The Markdown tables of training runs that docs/results/ reports, from the runs' ``metrics.json``.

- ``search_table``: search runs (``algo=dps|feedback``), one row per update rule, medians over
  seeds: best throws, roll-outs to the ``MILESTONES`` throw counts, throws kept with start noise;
- ``offpolicy_table``: off-policy runs, one row per algorithm, reward and actor, means over seeds
  of the final evaluation: catch rate, throws, time up, frames and wall time.

``scripts/dps_table.py`` and ``scripts/offpolicy_table.py`` print them for a multirun folder.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from collections import defaultdict
from collections.abc import Callable, Sequence
from pathlib import Path

from jugglerl.dps.training import MILESTONES
from jugglerl.runs.files import METRICS


def run_metrics(folder: Path) -> list[dict]:
    """The parsed ``metrics.json`` of every run below ``folder``, in path order."""
    return [json.loads(path.read_text()) for path in sorted(folder.rglob(METRICS))]


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + " --- |" * len(header)]
    lines += ["| " + " | ".join(cells) + " |" for cells in rows]
    return "\n".join(lines)


def _grouped(runs: list[dict], key: Callable[[dict], tuple]) -> dict[tuple, list[dict]]:
    groups = defaultdict(list)
    for run in runs:
        groups[key(run)].append(run)
    return {k: sorted(v, key=lambda r: r["seed"]) for k, v in sorted(groups.items())}


def _milestone_cell(runs: list[dict], throws: int) -> str:
    reached = [r["first_rollout_with"][str(throws)] for r in runs]
    reached = [n for n in reached if n is not None]
    if not reached:
        return f"— (0/{len(runs)})"
    return f"{statistics.median(reached):g} ({len(reached)}/{len(runs)})"


def search_table(runs: list[dict]) -> str | None:
    """The search runs' table (None if there are none)."""
    groups = _grouped([r for r in runs if "best_throws" in r], lambda r: (r["update"],))
    if not groups:
        return None
    header = ["update", "seeds", "best throws: median (per seed)"]
    header += [f"roll-outs to {n}" for n in MILESTONES] + ["kept with start noise"]
    rows = []
    for (update,), group in groups.items():
        best = [r["best_throws"] for r in group]
        kept = [r["noise_check"]["fraction_of_best"] for r in group if "noise_check" in r]
        rows.append(
            [
                f"`{update}`",
                ",".join(str(r["seed"]) for r in group),
                f"{statistics.median(best):g} ({', '.join(map(str, best))})",
                *(_milestone_cell(group, n) for n in MILESTONES),
                f"{statistics.mean(kept):.0%}" if kept else "—",
            ]
        )
    return markdown_table(header, rows)


def offpolicy_table(runs: list[dict]) -> str | None:
    """The off-policy runs' table (None if there are none)."""
    groups = _grouped(
        [r for r in runs if "final_evaluation" in r],
        lambda r: (r.get("algo", "ddpg"), r["reward"], r["actor"]),
    )
    if not groups:
        return None
    header = ["algo", "reward", "actor", "seeds", "catch rate", "mean throws", "ball up (s)"]
    header += ["frames", "wall (min)"]
    rows = []
    for (algo, reward, actor), group in groups.items():
        finals = [r["final_evaluation"] for r in group]
        episodes = sum(len(f["episodes"]) for f in finals)
        rows.append(
            [
                f"`{algo}`",
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
        )
    return markdown_table(header, rows)


def table_main(doc: str, table: Callable[[list[dict]], str | None], what: str) -> None:
    """Parse ``folder`` from the command line and print ``table`` of its runs; no runs end with
    one ``error:`` line naming ``what``."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("folder", type=Path, help="a multirun folder (or any folder of runs)")
    args = parser.parse_args()
    rendered = table(run_metrics(args.folder))
    if rendered is None:
        sys.exit(f"error: no {what} {METRICS} below {args.folder}")
    print(rendered)
