"""Ship the actor a training run deploys as a named policy: ``policy=NAME`` then runs it.

    python scripts/ship_actor.py outputs/train/apprentice/<run> lstm_juggler [--folder DIR]

Writes ``NAME.yaml`` (``kind: actor``, with the run's seed, frames and final evaluation in its
header) and ``NAME.pt`` (the actor's config, deployed weights and normalisation;
``jugglerl.policies.actor_file``) into ``assets/policies/`` or ``--folder``. Prints the path.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import yaml

from jugglerl.policies.actor_file import write_actor_policy
from jugglerl.runs.checkpoints import load_checkpoint
from jugglerl.runs.policy_files import shipped_folder


def header(run: Path, state: dict) -> str:
    """Where the actor comes from and what its run measured, for the policy file's comment."""
    cfg = state["config"]
    overrides = run / ".hydra" / "overrides.yaml"
    command = (
        " ".join(yaml.safe_load(overrides.read_text()) or [])
        if overrides.is_file()
        else f"algo={cfg['algo']['name']} actor={cfg['actor']['name']} seed={cfg['seed']}"
    )
    lines = [
        f"The {cfg['actor']['name']} actor deployed by `python scripts/train.py {command}`",
        "(shipped with scripts/ship_actor.py).",
    ]
    metrics = run / "metrics.json"
    if metrics.is_file():
        final = json.loads(metrics.read_text())["final_evaluation"]
        lines.append(
            f"Deployed actor of frame {final.get('policy_frames', state['counters']['frames'])}:"
            f" {final['mean_throws']:g} throws, ball up {final['mean_time_to_drop']:g} s in"
            f" {final['duration']:g} s from the standard start."
        )
    return "\n".join(lines)


def env_preset(run: Path) -> str | None:
    """The env preset the run trained in (Hydra's record of its choices), unless ``paper``."""
    hydra = run / ".hydra" / "hydra.yaml"
    if not hydra.is_file():
        return None
    choice = yaml.safe_load(hydra.read_text())["hydra"]["runtime"]["choices"].get("env")
    return None if choice in (None, "paper") else choice


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path, help="a training run directory or its checkpoint.pt")
    parser.add_argument("name", help="the policy's name (policy=NAME)")
    parser.add_argument("--folder", type=Path, default=None, help="default: the shipped folder")
    args = parser.parse_args()
    try:
        state = load_checkpoint(args.run)
    except ValueError as error:
        raise SystemExit(f"error: {error}") from None
    if state["deploys"] != "actor":
        raise SystemExit(f"error: {args.run} deploys {state['deploys']}, not a trained actor")
    run = args.run if args.run.is_dir() else args.run.parent
    folder = args.folder or shipped_folder()
    print(write_actor_policy(state, folder, args.name, header(run, state), env_preset(run)))


if __name__ == "__main__":
    main()
