"""The trainers' learners on a standard Gymnasium task, beside the returns published for it.

    python scripts/benchmarks/gym_check.py                       # PPO, HalfCheetah-v5, 1 M frames
    python scripts/benchmarks/gym_check.py 'seeds=[0,1,2]' out=records.json
    python scripts/benchmarks/gym_check.py learner=td3 task.id=InvertedPendulum-v5   # 100 k frames

Trains the learner ``learner=`` names (``jugglerl.gym_check``: ``ppo``, the learner of
``algo=ppo``; ``td3``, the off-policy trainer's TD3 loss, ``algo.loss=ddpg`` its DDPG) on the
task instead of the juggling env, once per seed, with CleanRL's settings
(``configs/learner/``), and prints, per run, the mean return of its last training episodes and of
deterministic episodes at the end, and the wall time; with ``out=FILE`` the records (each run's
training returns over frames) go to a JSON file. docs/results/gym_check.md holds the figures and
their sources.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import hydra
from omegaconf import DictConfig

from jugglerl.config.command_line import exit_on_bad_command_line
from jugglerl.gym_check.offpolicy import OffPolicyCheck
from jugglerl.gym_check.ppo import PPOCheck

#: The check of each ``algo.trainer`` of ``configs/learner/``.
CHECKS = {"onpolicy": PPOCheck, "offpolicy": OffPolicyCheck}


@hydra.main(version_base="1.3", config_path="../../configs", config_name="gym_check")
def main(cfg: DictConfig) -> None:
    records = []
    for seed in cfg.seeds:
        cfg.seed = seed
        try:
            check = CHECKS[cfg.algo.trainer](cfg)
        except ValueError as error:
            sys.exit(f"error: {error}")
        try:
            record = check.run(progress=cfg.progress)
        finally:
            check.close()
        records.append(record)
        print(
            f"{record['task']} {record['algo']} seed {seed}: {record['frames']} frames in"
            f" {record['wall_seconds']:.0f} s; return {record['train_return']:.1f} (last"
            f" training episodes), {record['eval_return']:.1f} (deterministic)"
        )
    if cfg.out:
        Path(cfg.out).write_text(json.dumps(records))


if __name__ == "__main__":
    exit_on_bad_command_line("gym_check")
    main()
