"""Export a trained network as one TorchScript file that acts with plain ``torch``.

    python scripts/export_policy.py policy=lstm_centred              # a shipped actor
    python scripts/export_policy.py policy=outputs/train/apprentice/<run> file=juggler.pt

The file holds the observation normalisation, the time features, the ball clock and the
network (``jugglerl.policies.export``); ``docs/deploy.md`` shows the ten lines that run it, with
no JuggleRL installed. Its actions equal ``policy=...`` in ``scripts/evaluate.py`` bit for bit.
"""

from __future__ import annotations

import sys
from pathlib import Path

import hydra
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from jugglerl.config.command_line import exit_on_bad_command_line
from jugglerl.policies.actor import ActorPolicy
from jugglerl.policies.actor_file import read_actor_weights
from jugglerl.policies.export import export
from jugglerl.runs.files import exits_on_run_file_errors
from jugglerl.runs.policy_files import check_policy_named


def default_name(spec: str) -> str:
    """``lstm_centred`` for a name or a policy file, the run's folder for a run."""
    path = Path(spec)
    return path.parent.name if path.name == "checkpoint.pt" else path.stem


@hydra.main(version_base="1.3", config_path="../configs", config_name="export")
@exits_on_run_file_errors
def main(cfg: DictConfig) -> None:
    try:
        check_policy_named("policy", cfg.policy)
        policy = ActorPolicy.from_state(read_actor_weights(str(cfg.policy)))
    except ValueError as error:
        sys.exit(f"error: {error}")
    run_dir = Path(HydraConfig.get().runtime.output_dir)
    path = Path(cfg.file) if cfg.file else run_dir / f"{default_name(str(cfg.policy))}.pt"
    export(policy.deployed, path)
    memory = int(policy.deployed.memory_size)
    print(f"policy {cfg.policy} -> {path} (memory of {memory} values per env; docs/deploy.md)")


if __name__ == "__main__":
    exit_on_bad_command_line("export")
    main()
