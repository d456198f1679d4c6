"""Evaluate a policy for one episode and write ``metrics.json`` into the run directory.

python scripts/evaluate.py policy=expert
python scripts/evaluate.py policy=path/to/command.yaml env=earth seed=3 duration=60
python scripts/evaluate.py policy=expert hydra.run.dir=outputs/my_eval
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import hydra
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from jugglerl.config import make_juggle_env
from jugglerl.evaluation import run_episode
from jugglerl.policies import load_policy


@hydra.main(version_base="1.3", config_path="../configs", config_name="evaluate")
def main(cfg: DictConfig) -> None:
    try:
        env = make_juggle_env(cfg.env, duration=cfg.duration)
        policy = load_policy(str(cfg.policy), env)
    except ValueError as error:
        sys.exit(f"error: {error}")
    metrics = run_episode(env, policy, seed=int(cfg.seed)).to_dict()
    env.close()
    run_dir = Path(HydraConfig.get().runtime.output_dir)
    (run_dir / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n")
    print(json.dumps(metrics, indent=2))
    print(
        f"policy {cfg.policy}: {metrics['throws']} throws in {metrics['duration']:g} s"
        f" -> {run_dir / 'metrics.json'}"
    )


if __name__ == "__main__":
    main()
