"""Learning curves of off-policy runs as a PNG: throws and time up of each periodic evaluation.

    python scripts/plot_learning.py outputs/train/apprentice/<run> [<run> ...] [--out curves.png]

Reads each run's ``metrics.json`` (``evaluations``: ``eval.seeds`` episodes of ``eval.duration``
every ``eval.every_frames``; the last record is the final full-length evaluation, left out here)
and draws mean throws and mean time up against frames, one line per run labelled by its seed,
with the stage boundaries of ``algo.stages`` dashed; for runs evaluated under ``eval.perturbed``
conditions a third panel draws the throws ``eval.keep_best`` ranks (nominal and perturbed). A
folder may hold several runs (a multirun): every ``metrics.json`` below it is read
(``jugglerl.reports.run_tables.run_metrics``). Prints where it wrote the PNG.
"""

from __future__ import annotations

import argparse
from itertools import pairwise
from pathlib import Path

from jugglerl.batch.evaluations import score
from jugglerl.reports.run_tables import METRICS, run_metrics


def read_runs(folder: Path) -> list[dict]:
    runs = run_metrics(folder)
    if not runs:
        raise SystemExit(f"error: no {METRICS} in {folder} (a finished off-policy run directory)")
    return runs


def stage_ends(run: dict) -> list[int]:
    """Frames at which a stage ended, from the history's stage index."""
    return [a["frames"] for a, b in pairwise(run["history"]) if b["stage"] != a["stage"]]


def plot(runs: list[dict], out: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    perturbed = any("perturbed" in e for run in runs for e in run["evaluations"])
    panels = 3 if perturbed else 2
    figure, axes = plt.subplots(1, panels, figsize=(5 * panels, 3.5), sharex=True)
    throws, time_up = axes[:2]
    for run in runs:
        periodic = run["evaluations"][:-1]
        frames = [e["frames"] / 1000 for e in periodic]
        label = f"{run['algo']} {run['actor']}, seed {run['seed']}"
        throws.plot(frames, [e["mean_throws"] for e in periodic], marker="o", label=label)
        time_up.plot(frames, [e["mean_time_to_drop"] for e in periodic], marker="o", label=label)
        if perturbed:
            axes[2].plot(frames, [score(e)[1] for e in periodic], marker="o", label=label)
    for end in sorted({end for run in runs for end in stage_ends(run)}):
        for panel in axes:
            panel.axvline(end / 1000, color="grey", linestyle="--", linewidth=0.8)
    seconds = runs[0]["evaluations"][0]["duration"]
    throws.set(xlabel="frames (thousands)", ylabel=f"mean throws in {seconds:g} s")
    time_up.set(xlabel="frames (thousands)", ylabel=f"mean time up (s, of {seconds:g})")
    if perturbed:
        axes[2].set(
            xlabel="frames (thousands)",
            ylabel=f"throws, nominal and perturbed (per {seconds:g} s)",
        )
    throws.legend(fontsize="small")
    figure.tight_layout()
    figure.savefig(out, dpi=120)
    plt.close(figure)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="run directories")
    parser.add_argument("--out", type=Path, default=Path("learning_curves.png"))
    args = parser.parse_args()
    print(f"-> {plot([run for folder in args.runs for run in read_runs(folder)], args.out)}")


if __name__ == "__main__":
    main()
